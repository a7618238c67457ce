/* fit.c - rows fitted to the runtime's linear blend (cb_fit_rows).
 *
 * A bone moving on an arc between two rows is cut as a chord by the runtime's blend: the
 * blend is exact at the rows and off by the arc's sagitta d halfway between them. Moving
 * every row outward by half the sagitta of its two intervals splits the error evenly: d/2 at
 * the rows, d/2 halfway. The worst visible error halves, which a sampled bake would need
 * about 1.4x the rows for (the blend's error falls as the square of the row spacing). Where a
 * fast interval meets a slow one, the row they share must still move by half the fast one's
 * sagitta: each row starts there (row_offset) and sweeps of coordinate descent settle every
 * value's offsets on the lowest worst error (refine_offsets). */
#include "crowdbake/palette.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h" /* CB_TARGET_CLONES */
#include "lanes.h"   /* v4df */

/* A row's first offset from the sagittas of the intervals before and after it: half the larger
 * where both bend the same way (a fast interval beside a slow one keeps its half, which the
 * mean of the two would cut to a quarter), their mean where they bend opposite ways. */
static double row_offset(double before, double after)
{
    if (before * after <= 0) return 0.25 * (before + after);
    return 0.5 * (fabs(before) > fabs(after) ? before : after);
}

/* The worst of a row's own error |c| and its two intervals' errors halfway, |a - c/2| and
 * |b - c/2| (a, b: each interval's sagitta less half its other row's offset; NAN: no such
 * interval). */
static CB_CLONE_INLINE double max_of(double w, double x) { return isnan(w) || x > w ? x : w; } /* fmax, inlined */

static CB_CLONE_INLINE double row_worst(double c, double a, double b)
{
    double w = fabs(c);
    if (!isnan(a)) w = max_of(w, fabs(a - 0.5 * c));
    if (!isnan(b)) w = max_of(w, fabs(b - 0.5 * c));
    return w;
}

/* The offset that minimises row_worst: a convex piecewise-linear function of c, lowest where
 * two of its lines cross or at a line's zero, so the best of those points. */
static CB_CLONE_INLINE double best_offset(double c, double a, double b)
{
    double cand[9] = {c, 0, 2 * a / 3, -2 * a, 2 * a, 2 * b / 3, -2 * b, 2 * b, a + b};
    double best = c, worst = row_worst(c, a, b);
    for (int k = 1; k < 9; ++k) {
        if (isnan(cand[k])) continue;
        double w = row_worst(cand[k], a, b);
        if (w < worst) best = cand[k], worst = w;
    }
    return best;
}

/* Sweeps over the rows, each row's offsets moved to the best for its neighbours' (coordinate
 * descent): no step raises the worst error of a value's rows and intervals, and a few sweeps
 * carry a fast interval's need to its neighbours. Each value's offsets depend on that value's
 * alone, so values are swept a block at a time (REFINE_BLOCK: eight cache lines of them) and a
 * block stops at the first sweep that moves none of its offsets: the next would see the same
 * inputs and move none either, so stopping there gives the same bits as all FIT_SWEEPS (so the
 * block's width moves no output). Most blocks of the shared models take all eight sweeps (92%
 * of Cow's groups of four values move in a sweep), so a wider block, fewer rows' worth of
 * bookkeeping, costs less than it loses to blocks that stop later. Since a row's moves are
 * tested once a row (speed43f), callgrind -j 1, default bakes (no -q), 16 -> 32 -> 64 -> 128 values:
 * Cow 562.7 -> 559.1 -> 556.7 -> 556.3 M, robot 698.4 -> 685.8 -> 680.0 -> 676.6 M, Husky
 * 470.5 -> 466.2 -> 464.7 -> 463.5 M, Fox 69.45 -> 69.46 -> 69.15 -> 69.04 M (8 values: Cow
 * 574.2 M); 64 keeps a block's offsets and sagittas within 1 KiB a row. */
enum { FIT_SWEEPS = 8, REFINE_BLOCK = 64 };

/* A looping clip whose bone turns a full circle ends in the quaternion hemisphere opposite its
 * first row's, and the runtime's blend across the wrap flips the first row's quaternion
 * (cb:hemisphere). Seen from the first row, that interval's sagitta and the last row's offsets
 * change sign on those values (and the last row sees the first row's offsets flipped): `sign`
 * is -1 on them and 1 elsewhere, `d0` the wrap's sagittas signed for row 0, `view` scratch. */
typedef struct {
    const double *sign, *d0;
    double *view;
} wrap_flip;

static const double *flipped(const wrap_flip *wf, const double *c, uint32_t v0, uint32_t v1)
{
    for (uint32_t v = v0; v < v1; ++v) wf->view[v] = wf->sign[v] * c[v];
    return wf->view;
}

/* The sweep, twice: for the x86-64 baseline (a max as a compare and a select), and where the
 * CPU has AVX2 with a max as one vmaxpd. MAXPD(x, w) is x > w ? x : w for every input, NaN
 * and signed zeros included (it returns its second operand unless the first is greater), so
 * both give MAX4's bits; fewer instructions and registers let the AVX2 sweep keep its values
 * in registers (speed43f: Cow's sweeps 72.2 -> 58.1 M instructions). A target_clones copy cannot
 * name the AVX intrinsic in its baseline twin, hence two functions and a test of the CPU, the
 * one the clones' resolver makes. */
typedef bool sweep_fn(double *c, const double *d, uint32_t frames, uint32_t intervals, uint32_t stride, bool loops,
                      const wrap_flip *wf, uint32_t v0, uint32_t v1);
#define SWEEP(name) name##_base
#define SWEEP_TARGET
#define MAX4(w, x) CB_SELECT4((x) > (w), x, w)
#define ABS4(x) CB_ABS4(x)
#define NEG4(x) ((v4df)((v4di)(x) ^ (v4di){INT64_MIN, INT64_MIN, INT64_MIN, INT64_MIN}))
#include "fit_sweep.h"
#if CB_CLONES
#include <immintrin.h>
#define SWEEP(name) name##_avx2
#define SWEEP_TARGET __attribute__((target("avx2")))
#define MAX4(w, x) ((v4df)_mm256_max_pd((__m256d)(x), (__m256d)(w)))
/* The sign bit cleared and flipped with one constant, -0.0 (the baseline's INT64_MAX and INT64_MIN
 * masks are the same bits): a register more for the sweep, whose values spilled (Cow's sweeps
 * 58.1 -> 56.0 M instructions). */
#define ABS4(x) ((v4df)_mm256_andnot_pd(_mm256_set1_pd(-0.0), (__m256d)(x)))
#define NEG4(x) ((v4df)_mm256_xor_pd(_mm256_set1_pd(-0.0), (__m256d)(x)))
#include "fit_sweep.h"
#endif

static void refine_offsets(double *c, const double *d, uint32_t frames, uint32_t intervals, uint32_t stride, bool loops,
                           const wrap_flip *wf)
{
    sweep_fn *sweep_block = sweep_block_base;
#if CB_CLONES
    if (__builtin_cpu_supports("avx2")) sweep_block = sweep_block_avx2;
#endif
    for (uint32_t v0 = 0; v0 < stride; v0 += REFINE_BLOCK) {
        uint32_t v1 = v0 + REFINE_BLOCK < stride ? v0 + REFINE_BLOCK : stride;
        for (int sweep = 0; sweep < FIT_SWEEPS && sweep_block(c, d, frames, intervals, stride, loops, wf, v0, v1); ++sweep) {
        }
    }
}

/* Row f's first offsets (row_offset, or half the one interval's sagitta at a one-shot's ends);
 * four values at a time where both intervals are there, each lane row_offset's operations. */
CB_TARGET_CLONES static void first_offsets(double *c, const double *dp, const double *dn, uint32_t stride)
{
    uint32_t v = 0;
#if defined(__GNUC__)
    const v4df zero = {0, 0, 0, 0}, quarter = {0.25, 0.25, 0.25, 0.25}, half = {0.5, 0.5, 0.5, 0.5};
    for (; dp && dn && v + 4 <= stride; v += 4) {
        v4df before, after;
        memcpy(&before, dp + v, sizeof before), memcpy(&after, dn + v, sizeof after);
        v4df larger = CB_SELECT4(CB_ABS4(before) > CB_ABS4(after), before, after);
        v4df offset = CB_SELECT4(before * after <= zero, quarter * (before + after), half * larger);
        memcpy(c + v, &offset, sizeof offset);
    }
#endif
    for (; v < stride; ++v) c[v] = dp && dn ? row_offset(dp[v], dn[v]) : 0.5 * (dp ? dp[v] : dn[v]);
}

/* A row's offsets added: each value widened, summed in double and rounded back to float. */
CB_TARGET_CLONES static void add_offsets(float *r, const double *c, uint32_t stride)
{
    uint32_t v = 0;
#if defined(__GNUC__)
    typedef float v4sf __attribute__((vector_size(16)));
    for (; v + 4 <= stride; v += 4) {
        v4sf value;
        v4df offset;
        memcpy(&value, r + v, sizeof value), memcpy(&offset, c + v, sizeof offset);
        value = __builtin_convertvector(__builtin_convertvector(value, v4df) + offset, v4sf);
        memcpy(r + v, &value, sizeof value);
    }
#endif
    for (; v < stride; ++v) r[v] = (float)(r[v] + c[v]);
}

/* A bone's sagittas over one interval: the exact mid-row (aj, bj its rows, mj the mid-row) less
 * the rows' mean, a qpos quaternion's scaled to the mean's length on the blend's side. Inline,
 * so that qpos's 8 values a bone are a constant its loops unroll on. */
static inline __attribute__((always_inline)) void interval_sagitta(const float *aj, const float *bj, const float *mj,
                                                                   double *dj, uint32_t values, bool qpos)
{
    double mean[16], scale = 1;
    for (uint32_t k = 0; k < values; ++k) mean[k] = 0.5 * ((double)aj[k] + bj[k]);
    if (qpos) {
        double dot = 0, mm = 0;
        for (int k = 0; k < 4; ++k) dot += mean[k] * mj[k], mm += (double)mj[k] * mj[k];
        double ml = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2] + mean[3] * mean[3]);
        scale = mm > 0 ? ml / sqrt(mm) * (dot < 0 ? -1 : 1) : 1; /* the exact direction, on the blend's side */
    }
    for (uint32_t k = 0; k < values; ++k) dj[k] = (qpos && k < 4 ? mj[k] * scale : mj[k]) - mean[k];
}

/* interval_sagitta on every bone of a qpos interval (8 values a bone) with no flip: the means
 * and the differences four values at a time, each lane interval_sagitta's operations; the
 * quaternion's dot, lengths and scale as there, one value after another. */
CB_TARGET_CLONES static void qpos_sagittas(const float *a, const float *b, const float *m, double *d, uint32_t bones)
{
    for (uint32_t j = 0; j < bones; ++j, a += 8, b += 8, m += 8, d += 8) {
#if defined(__GNUC__)
        typedef float v4sf __attribute__((vector_size(16)));
        const v4df half = {0.5, 0.5, 0.5, 0.5};
        v4sf a0, a1, b0, b1, m0, m1;
        memcpy(&a0, a, sizeof a0), memcpy(&a1, a + 4, sizeof a1), memcpy(&b0, b, sizeof b0);
        memcpy(&b1, b + 4, sizeof b1), memcpy(&m0, m, sizeof m0), memcpy(&m1, m + 4, sizeof m1);
        v4df mean0 = half * (__builtin_convertvector(a0, v4df) + __builtin_convertvector(b0, v4df));
        v4df mean1 = half * (__builtin_convertvector(a1, v4df) + __builtin_convertvector(b1, v4df));
        double mean[4], dot = 0, mm = 0;
        memcpy(mean, &mean0, sizeof mean);
        for (int k = 0; k < 4; ++k) dot += mean[k] * m[k], mm += (double)m[k] * m[k];
        double ml = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2] + mean[3] * mean[3]);
        double scale = mm > 0 ? ml / sqrt(mm) * (dot < 0 ? -1 : 1) : 1;
        v4df by = {scale, scale, scale, scale};
        v4df d0 = __builtin_convertvector(m0, v4df) * by - mean0, d1 = __builtin_convertvector(m1, v4df) - mean1;
        memcpy(d, &d0, sizeof d0), memcpy(d + 4, &d1, sizeof d1);
#else
        interval_sagitta(a, b, m, d, 8, true);
#endif
    }
}

/* The wrap's signs (wrap_flip): -1 on the quaternion of each bone whose last and first rows the
 * runtime's blend flips between (their dot below 0, as the shader tests it), 1 elsewhere; NULL
 * where none flips (or out of memory: the wrap is then fitted unflipped, as before). */
static double dot4(const float *a, const float *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2] + (double)a[3] * b[3];
}

static double *wrap_signs(const float *rows, uint32_t frames, uint32_t bones, uint32_t values)
{
    const float *last = rows + (size_t)(frames - 1) * bones * values;
    bool any = false;
    for (uint32_t j = 0; j < bones && !any; ++j) any = dot4(last + (size_t)j * values, rows + (size_t)j * values) < 0;
    double *sign = any ? malloc((size_t)bones * values * sizeof(double)) : NULL;
    for (uint32_t j = 0; sign && j < bones; ++j) {
        bool flip = dot4(last + (size_t)j * values, rows + (size_t)j * values) < 0;
        for (uint32_t k = 0; k < values; ++k) sign[(size_t)j * values + k] = flip && k < 4 ? -1 : 1;
    }
    return sign;
}

void cb_fit_rows(float *rows, const float *mids, uint32_t frames, uint32_t bones, uint32_t values, bool loops, bool qpos)
{
    uint32_t intervals = loops ? frames : frames - 1, stride = bones * values;
    if (frames < 2 || intervals == 0) return;
    double *d = malloc((size_t)intervals * stride * sizeof(double));
    if (!d) return; /* out of memory: the rows stay sampled, which is correct, only less precise between them */
    double *sign = loops && qpos ? wrap_signs(rows, frames, bones, values) : NULL;
    for (uint32_t i = 0; i < intervals; ++i) {
        const float *a = rows + (size_t)i * stride, *b = rows + (size_t)((i + 1) % frames) * stride;
        const float *m = mids + (size_t)i * stride;
        double *di = d + (size_t)i * stride;
        bool flips = sign && i + 1 == frames;
        if (qpos && values == 8 && !flips) {
            qpos_sagittas(a, b, m, di, bones);
            continue;
        }
        for (uint32_t j = 0; j < bones; ++j) {
            size_t at = (size_t)j * values;
            float bj[16];
            const float *b_as_blended = b + at;
            if (sign && i + 1 == frames && sign[at] < 0) { /* the wrap, blended towards the flipped first row */
                for (uint32_t k = 0; k < values; ++k) bj[k] = k < 4 ? -b[at + k] : b[at + k];
                b_as_blended = bj;
            }
            if (qpos && values == 8) interval_sagitta(a + at, b_as_blended, m + at, di + at, 8, true); /* unrolled */
            else interval_sagitta(a + at, b_as_blended, m + at, di + at, values, qpos);
        }
    }
    double *c = malloc((size_t)frames * stride * sizeof(double));
    double *wrap = sign ? malloc((size_t)2 * stride * sizeof(double)) : NULL;
    if (!c || (sign && !wrap)) { /* as above: the rows stay sampled */
        free(wrap), free(sign), free(c), free(d);
        return;
    }
    wrap_flip wf = {sign, wrap, wrap + stride};
    for (uint32_t v = 0; sign && v < stride; ++v) wrap[v] = sign[v] * d[(size_t)(intervals - 1) * stride + v];
    for (uint32_t f = 0; f < frames; ++f) {
        /* The intervals on either side of row f; a one-shot's end rows have one. */
        bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
        const double *dp = has_prev ? d + (size_t)((f + intervals - 1) % intervals) * stride : NULL;
        const double *dn = has_next ? d + (size_t)(f % intervals) * stride : NULL;
        if (sign && f == 0) dp = wf.d0;
        first_offsets(c + (size_t)f * stride, dp, dn, stride);
    }
    refine_offsets(c, d, frames, intervals, stride, loops, sign ? &wf : NULL);
    for (uint32_t f = 0; f < frames; ++f) {
        float *r = rows + (size_t)f * stride;
        add_offsets(r, c + (size_t)f * stride, stride);
        for (uint32_t j = 0; qpos && j < bones; ++j) { /* a stored quaternion stays a unit one */
            float *q = r + (size_t)j * values;
            double n = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
            for (int k = 0; k < 4 && n > 0; ++k) q[k] = (float)(q[k] / n);
        }
    }
    free(wrap);
    free(sign);
    free(c);
    free(d);
}
