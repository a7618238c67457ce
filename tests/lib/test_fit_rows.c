/* test_fit_rows.c - rows fitted to the runtime's linear blend (cb_fit_rows, src/core/fit.c),
 * against the minimax answers worked out by hand for one value per row.
 *
 * A fitted row r_f = sampled row + c_f. The blend errs |c_f| at row f, and halfway through
 * interval i by |d_i - (c_i + c_{i+1}) / 2|, d_i the interval's sagitta (the exact midpoint less
 * the mean of its sampled rows). The lowest worst error over every row and halfway point:
 * - every interval bending alike by d: c = d / 2 everywhere, worst d / 2;
 * - one fast interval (sagitta D) between still ones: its two rows c = D / 2, worst D / 2, where
 *   the mean of the half-sagittas (the fit before issue 43) gave its rows D / 4 and left 3D / 4;
 * - a loop of one fast interval and still ones: the same, the wrap included;
 * - a qpos bone turning a full circle at an even speed over a loop: the blend's normalized midpoint
 *   of two unit quaternions is the exact (slerp) midpoint, so no row moves - the wrap included,
 *   where the last row and the first lie in opposite hemispheres and the blend flips the first.
 * And the fit's fast path (four values a vector, a block of values stopping once a sweep moves
 * none) against the plain algorithm written out here: every row, every value, all eight sweeps,
 * one value at a time with fmax - the same bits for loops and one-shots, for values that fill
 * whole vectors and for those left over, signed zeros and the largest floats included (the fast
 * path weighs the candidates at 0, +-2a and +-2b from terms the others share). */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"

/* The worst blend error of fitted `rows` against the sampled ones and the exact `mids`. */
static double worst_error(const float *fitted, const float *sampled, const float *mids, uint32_t frames, bool loops)
{
    double worst = 0;
    for (uint32_t f = 0; f < frames; ++f) worst = fmax(worst, fabs((double)fitted[f] - sampled[f]));
    for (uint32_t i = 0; i < (loops ? frames : frames - 1); ++i) {
        double blend = 0.5 * ((double)fitted[i] + fitted[(i + 1) % frames]);
        worst = fmax(worst, fabs(mids[i] - blend));
    }
    return worst;
}

static double fit_and_measure(const float *sampled, const float *mids, uint32_t frames, bool loops)
{
    float rows[8];
    memcpy(rows, sampled, frames * sizeof *rows);
    cb_fit_rows(rows, mids, frames, 1, 1, loops, false);
    return worst_error(rows, sampled, mids, frames, loops);
}

static void test_an_even_arc_splits_its_sagitta(void **state)
{
    (void)state;
    const float sampled[5] = {0, 0, 0, 0, 0}, mids[4] = {0.2f, 0.2f, 0.2f, 0.2f};
    assert_float_equal(fit_and_measure(sampled, mids, 5, false), 0.1, 1e-6);
    assert_float_equal(fit_and_measure(sampled, mids, 4, true), 0.1, 1e-6);
}

static void test_a_fast_interval_keeps_half_its_sagitta(void **state)
{
    (void)state;
    /* Sampled error (no fit): 1. The mean of the half-sagittas: 0.75. The lowest: 0.5. */
    const float sampled[6] = {0, 0, 0, 0, 0, 0}, mids[5] = {0, 0, 1, 0, 0};
    assert_float_equal(fit_and_measure(sampled, mids, 6, false), 0.5, 1e-6);
    assert_float_equal(fit_and_measure(sampled, mids, 5, true), 0.5, 1e-6);
}

static void test_the_fit_leaves_a_straight_line(void **state)
{
    (void)state;
    const float sampled[4] = {0, 1, 2, 3}, mids[3] = {0.5f, 1.5f, 2.5f};
    float rows[4];
    memcpy(rows, sampled, sizeof rows);
    cb_fit_rows(rows, mids, 4, 1, 1, false, false);
    for (int f = 0; f < 4; ++f) assert_float_equal(rows[f], sampled[f], 0);
}

/* ---- the plain fit (fit.c before it was vectorized), for values that are not quaternions ---- */

static double plain_row_offset(double before, double after)
{
    if (before * after <= 0) return 0.25 * (before + after);
    return 0.5 * (fabs(before) > fabs(after) ? before : after);
}

static double plain_row_worst(double c, double a, double b)
{
    double w = fabs(c);
    if (!isnan(a)) w = fmax(w, fabs(a - 0.5 * c));
    if (!isnan(b)) w = fmax(w, fabs(b - 0.5 * c));
    return w;
}

static double plain_best_offset(double c, double a, double b)
{
    double cand[9] = {c, 0, 2 * a / 3, -2 * a, 2 * a, 2 * b / 3, -2 * b, 2 * b, a + b};
    double best = c, worst = plain_row_worst(c, a, b);
    for (int k = 1; k < 9; ++k) {
        if (isnan(cand[k])) continue;
        double w = plain_row_worst(cand[k], a, b);
        if (w < worst) best = cand[k], worst = w;
    }
    return best;
}

enum { PLAIN_FRAMES_MAX = 40, PLAIN_STRIDE_MAX = 40 };

static void plain_fit(float *rows, const float *mids, uint32_t frames, uint32_t stride, bool loops)
{
    static double d[PLAIN_FRAMES_MAX][PLAIN_STRIDE_MAX], c[PLAIN_FRAMES_MAX][PLAIN_STRIDE_MAX];
    uint32_t intervals = loops ? frames : frames - 1;
    for (uint32_t i = 0; i < intervals; ++i)
        for (uint32_t v = 0; v < stride; ++v)
            d[i][v] = mids[i * stride + v] -
                      0.5 * ((double)rows[i * stride + v] + rows[((i + 1) % frames) * stride + v]);
    for (uint32_t f = 0; f < frames; ++f) {
        bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
        uint32_t ip = (f + intervals - 1) % intervals, in = f % intervals;
        for (uint32_t v = 0; v < stride; ++v)
            c[f][v] = has_prev && has_next ? plain_row_offset(d[ip][v], d[in][v]) : 0.5 * (has_prev ? d[ip][v] : d[in][v]);
    }
    for (int sweep = 0; sweep < 8; ++sweep)
        for (uint32_t f = 0; f < frames; ++f) {
            bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
            uint32_t ip = (f + intervals - 1) % intervals, in = f % intervals;
            for (uint32_t v = 0; v < stride; ++v) {
                double a = has_prev ? d[ip][v] - 0.5 * c[(f + frames - 1) % frames][v] : NAN;
                double b = has_next ? d[in][v] - 0.5 * c[(f + 1) % frames][v] : NAN;
                c[f][v] = plain_best_offset(c[f][v], a, b);
            }
        }
    for (uint32_t f = 0; f < frames; ++f)
        for (uint32_t v = 0; v < stride; ++v) rows[f * stride + v] = (float)(rows[f * stride + v] + c[f][v]);
}

/* A motion with a bit of everything: still stretches, slow and fast arcs, jumps, values of
 * every size (a fixed generator: the same every run). */
static float motion(uint32_t *state, uint32_t f, uint32_t v)
{
    *state = *state * 1664525u + 1013904223u;
    double noise = (double)(*state >> 8) / (1u << 24) - 0.5;
    switch (v % 7) {
    case 0: return 0.25f; /* still */
    case 1: return (float)sin(0.3 * f + v);
    case 2: return (float)(f % 7 == 3 ? 5 * noise : 0.01 * noise); /* a fast interval now and then */
    case 3: return (float)(1000 * noise);
    case 5: return noise < 0 ? -0.0f : 0.0f; /* signed zeros: ties between candidates */
    case 6: return (float)(noise * 6e38); /* the largest floats: the candidates' doubling stays exact */
    default: return (float)(f * 0.5);
    }
}

static void test_the_fast_fit_is_the_plain_one_bit_for_bit(void **state)
{
    (void)state;
    static const uint32_t shapes[][3] = {{1, 1, 2}, {1, 8, 9}, {3, 5, 17}, {4, 8, 33}, {2, 12, 40}, {5, 7, 3}};
    for (size_t k = 0; k < sizeof shapes / sizeof shapes[0]; ++k)
        for (int loops = 0; loops < 2; ++loops) {
            uint32_t bones = shapes[k][0], values = shapes[k][1], frames = shapes[k][2], stride = bones * values;
            uint32_t seed = 12345u + (uint32_t)k, intervals = loops ? frames : frames - 1;
            float rows[PLAIN_FRAMES_MAX * PLAIN_STRIDE_MAX], plain[PLAIN_FRAMES_MAX * PLAIN_STRIDE_MAX];
            float mids[PLAIN_FRAMES_MAX * PLAIN_STRIDE_MAX];
            for (uint32_t f = 0; f < frames; ++f)
                for (uint32_t v = 0; v < stride; ++v) rows[f * stride + v] = motion(&seed, 2 * f, v);
            for (uint32_t i = 0; i < intervals; ++i)
                for (uint32_t v = 0; v < stride; ++v) mids[i * stride + v] = motion(&seed, 2 * i + 1, v);
            memcpy(plain, rows, sizeof rows);
            cb_fit_rows(rows, mids, frames, bones, values, loops, false);
            plain_fit(plain, mids, frames, stride, loops);
            assert_memory_equal(rows, plain, (size_t)frames * stride * sizeof *rows);
        }
}

/* One bone (qpos: quaternion, position, scale) turning about y by 360 / frames degrees a row; its
 * rows continue one another's hemisphere, as the bake stores them, so the last and the first are
 * opposite. */
static void full_turn(float *rows, float *mids, uint32_t frames)
{
    const double pi = 3.14159265358979323846;
    for (uint32_t f = 0; f < 2 * frames; ++f) {
        double half = pi * f / (2.0 * frames); /* half the angle at row f / 2 */
        float *q = f % 2 ? mids + (f / 2) * 8 : rows + (f / 2) * 8;
        const float value[8] = {0, (float)sin(half), 0, (float)cos(half), 0, 0, 0, 1};
        memcpy(q, value, sizeof value);
    }
}

static void test_a_full_turn_loop_keeps_its_rows_across_the_wrap(void **state)
{
    (void)state;
    enum { FRAMES = 12 };
    float rows[FRAMES * 8], sampled[FRAMES * 8], mids[FRAMES * 8];
    full_turn(sampled, mids, FRAMES);
    const float *last = sampled + (FRAMES - 1) * 8;
    assert_true(last[1] * sampled[1] + last[3] * sampled[3] < 0); /* the wrap flips */
    memcpy(rows, sampled, sizeof rows);
    cb_fit_rows(rows, mids, FRAMES, 1, 8, true, true);
    for (uint32_t v = 0; v < FRAMES * 8; ++v) assert_float_equal(rows[v], sampled[v], 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_even_arc_splits_its_sagitta),
        cmocka_unit_test(test_a_fast_interval_keeps_half_its_sagitta),
        cmocka_unit_test(test_the_fit_leaves_a_straight_line),
        cmocka_unit_test(test_the_fast_fit_is_the_plain_one_bit_for_bit),
        cmocka_unit_test(test_a_full_turn_loop_keeps_its_rows_across_the_wrap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
