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
#include <stdlib.h>
#include <string.h>

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
static double row_worst(double c, double a, double b)
{
    double w = fabs(c);
    if (!isnan(a)) w = fmax(w, fabs(a - 0.5 * c));
    if (!isnan(b)) w = fmax(w, fabs(b - 0.5 * c));
    return w;
}

/* The offset that minimises row_worst: a convex piecewise-linear function of c, lowest where
 * two of its lines cross or at a line's zero, so the best of those points. */
static double best_offset(double c, double a, double b)
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
 * carry a fast interval's need to its neighbours. */
enum { FIT_SWEEPS = 8 };

static void refine_offsets(double *c, const double *d, uint32_t frames, uint32_t intervals, uint32_t stride, bool loops)
{
    for (int sweep = 0; sweep < FIT_SWEEPS; ++sweep)
        for (uint32_t f = 0; f < frames; ++f) {
            bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
            uint32_t prev_row = (f + frames - 1) % frames, next_row = (f + 1) % frames;
            const double *dp = has_prev ? d + (size_t)((f + intervals - 1) % intervals) * stride : NULL;
            const double *dn = has_next ? d + (size_t)(f % intervals) * stride : NULL;
            for (uint32_t v = 0; v < stride; ++v) {
                double a = dp ? dp[v] - 0.5 * c[(size_t)prev_row * stride + v] : NAN;
                double b = dn ? dn[v] - 0.5 * c[(size_t)next_row * stride + v] : NAN;
                double *cv = &c[(size_t)f * stride + v];
                *cv = best_offset(*cv, a, b);
            }
        }
}

void cb_fit_rows(float *rows, const float *mids, uint32_t frames, uint32_t bones, uint32_t values, bool loops, bool qpos)
{
    uint32_t intervals = loops ? frames : frames - 1, stride = bones * values;
    if (frames < 2 || intervals == 0) return;
    double *d = malloc((size_t)intervals * stride * sizeof(double));
    if (!d) return; /* out of memory: the rows stay sampled, which is correct, only less precise between them */
    for (uint32_t i = 0; i < intervals; ++i) {
        const float *a = rows + (size_t)i * stride, *b = rows + (size_t)((i + 1) % frames) * stride;
        const float *m = mids + (size_t)i * stride;
        double *di = d + (size_t)i * stride;
        for (uint32_t j = 0; j < bones; ++j) {
            const float *aj = a + (size_t)j * values, *bj = b + (size_t)j * values, *mj = m + (size_t)j * values;
            double *dj = di + (size_t)j * values, mean[16], scale = 1;
            for (uint32_t k = 0; k < values; ++k) mean[k] = 0.5 * ((double)aj[k] + bj[k]);
            if (qpos) {
                double dot = 0, mm = 0;
                for (int k = 0; k < 4; ++k) dot += mean[k] * mj[k], mm += (double)mj[k] * mj[k];
                double ml = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2] + mean[3] * mean[3]);
                scale = mm > 0 ? ml / sqrt(mm) * (dot < 0 ? -1 : 1) : 1; /* the exact direction, on the blend's side */
            }
            for (uint32_t k = 0; k < values; ++k) dj[k] = (qpos && k < 4 ? mj[k] * scale : mj[k]) - mean[k];
        }
    }
    double *c = malloc((size_t)frames * stride * sizeof(double));
    if (!c) { /* as above: the rows stay sampled */
        free(d);
        return;
    }
    for (uint32_t f = 0; f < frames; ++f) {
        /* The intervals on either side of row f; a one-shot's end rows have one. */
        bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
        const double *dp = has_prev ? d + (size_t)((f + intervals - 1) % intervals) * stride : NULL;
        const double *dn = has_next ? d + (size_t)(f % intervals) * stride : NULL;
        for (uint32_t v = 0; v < stride; ++v)
            c[(size_t)f * stride + v] = dp && dn ? row_offset(dp[v], dn[v]) : 0.5 * (dp ? dp[v] : dn[v]);
    }
    refine_offsets(c, d, frames, intervals, stride, loops);
    for (uint32_t f = 0; f < frames; ++f) {
        float *r = rows + (size_t)f * stride;
        for (uint32_t v = 0; v < stride; ++v) r[v] = (float)(r[v] + c[(size_t)f * stride + v]);
        for (uint32_t j = 0; qpos && j < bones; ++j) { /* a stored quaternion stays a unit one */
            float *q = r + (size_t)j * values;
            double n = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
            for (int k = 0; k < 4 && n > 0; ++k) q[k] = (float)(q[k] / n);
        }
    }
    free(c);
    free(d);
}
