/* bench_gl_local.c - see bench_gl_local.h. */
#include "bench_gl_local.h"

#include <stdio.h>
#include <string.h>

void bench_local_rows(const cb_palette *p, float *meta)
{
    uint32_t n = p->bone_count;
    int depth_max = 0, depth_sum = 0;
    for (uint32_t j = 0; j < n; ++j) {
        meta[j * 4] = (float)p->parents[j];
        memcpy(meta + (n + j) * 4, p->bone_ranges + j * 8, 4 * sizeof(float));
        memcpy(meta + (2 * n + j) * 4, p->bone_ranges + j * 8 + 4, 4 * sizeof(float));
        int depth = 0;
        for (int32_t a = p->parents[j]; a >= 0 && depth <= (int)n; a = p->parents[a]) ++depth;
        depth_max = depth > depth_max ? depth : depth_max, depth_sum += depth;
    }
    fprintf(stderr, "bench_gl: local rows, %u bones, chains to the root %d deep at most, %.2f on average (ancestors a bone walks)\n",
            n, depth_max, (double)depth_sum / n);
}
