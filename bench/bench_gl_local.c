/* bench_gl_local.c - see bench_gl_local.h. */
#include "bench_gl_local.h"

#include <stdio.h>

void bench_local_rows(const cb_palette *p)
{
    uint32_t n = p->bone_count;
    int depth_max = 0, depth_sum = 0;
    for (uint32_t j = 0; j < n; ++j) {
        int depth = 0;
        for (int32_t a = p->parents[j]; a >= 0 && depth <= (int)n; a = p->parents[a]) ++depth;
        depth_max = depth > depth_max ? depth : depth_max, depth_sum += depth;
    }
    fprintf(stderr, "bench_gl: local rows, %u bones, chains to the root %d deep at most, %.2f on average (ancestors a bone walks)\n",
            n, depth_max, (double)depth_sum / n);
}
