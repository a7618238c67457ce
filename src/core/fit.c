/* fit.c - rows fitted to the runtime's linear blend (cb_fit_rows).
 *
 * A bone moving on an arc between two rows is cut as a chord by the runtime's blend: the
 * blend is exact at the rows and off by the arc's sagitta d halfway between them. Moving
 * every row outward by half the sagitta of its two intervals splits the error evenly: d/2 at
 * the rows, d/2 halfway. The worst visible error halves, which a sampled bake would need
 * about 1.4x the rows for (the blend's error falls as the square of the row spacing). */
#include "crowdbake/palette.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    for (uint32_t f = 0; f < frames; ++f) {
        /* The intervals on either side of row f; a one-shot's end rows have one. */
        bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
        const double *dp = has_prev ? d + (size_t)((f + intervals - 1) % intervals) * stride : NULL;
        const double *dn = has_next ? d + (size_t)(f % intervals) * stride : NULL;
        float *r = rows + (size_t)f * stride;
        for (uint32_t v = 0; v < stride; ++v) {
            double c = dp && dn ? 0.25 * (dp[v] + dn[v]) : 0.5 * (dp ? dp[v] : dn[v]);
            r[v] = (float)(r[v] + c);
        }
        for (uint32_t j = 0; qpos && j < bones; ++j) { /* a stored quaternion stays a unit one */
            float *q = r + (size_t)j * values;
            double n = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
            for (int k = 0; k < 4 && n > 0; ++k) q[k] = (float)(q[k] / n);
        }
    }
    free(d);
}
