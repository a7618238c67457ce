/* test_fit_rows.c - rows fitted to the runtime's linear blend (cb_fit_rows, src/core/fit.c),
 * against the minimax answers worked out by hand for one value per row.
 *
 * A fitted row r_f = sampled row + c_f. The blend errs |c_f| at row f, and halfway through
 * interval i by |d_i - (c_i + c_{i+1}) / 2|, d_i the interval's sagitta (the exact midpoint less
 * the mean of its sampled rows). The lowest worst error over every row and halfway point:
 * - every interval bending alike by d: c = d / 2 everywhere, worst d / 2;
 * - one fast interval (sagitta D) between still ones: its two rows c = D / 2, worst D / 2, where
 *   the mean of the half-sagittas (the fit before issue 43) gave its rows D / 4 and left 3D / 4;
 * - a loop of one fast interval and still ones: the same, the wrap included. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_even_arc_splits_its_sagitta),
        cmocka_unit_test(test_a_fast_interval_keeps_half_its_sagitta),
        cmocka_unit_test(test_the_fit_leaves_a_straight_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
