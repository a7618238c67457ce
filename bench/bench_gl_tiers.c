/* bench_gl_tiers.c - see bench_gl_tiers.h. */
#include "bench_gl_tiers.h"

#include <stdlib.h>

/* Float arithmetic in the shader's order: w is the fourth row of view_projection times (place, 1). */
static float pixels_tall(const float place[3], const float vp[16], float at_w1)
{
    float w = vp[3] * place[0] + vp[7] * place[1] + vp[11] * place[2] + vp[15];
    return at_w1 / w;
}

int bench_lod_tier(const float place[3], const float view_projection[16], const float lod[3])
{
    float pixels = pixels_tall(place, view_projection, lod[0]);
    return pixels < lod[2] ? 0 : pixels < lod[1] ? 1 : 2;
}

void bench_sort_by_tier(const float *instances, uint32_t stride, uint32_t n, const float view_projection[16],
                        const float lod[3], int32_t *order, bench_tiers *tiers)
{
    uint32_t next[3] = {0};
    for (uint32_t i = 0; i < n; ++i) next[bench_lod_tier(instances + (size_t)i * stride, view_projection, lod)]++;
    for (int k = 0; k < 3; ++k) tiers->count[k] = next[k];
    tiers->first[0] = 0, tiers->first[1] = next[0], tiers->first[2] = next[0] + next[1];
    for (int k = 0; k < 3; ++k) next[k] = tiers->first[k];
    for (uint32_t i = 0; i < n; ++i) /* the tier again, not stored: no scratch array to allocate */
        order[next[bench_lod_tier(instances + (size_t)i * stride, view_projection, lod)]++] = (int32_t)i;
}

static int by_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

void bench_split_tiers(const float *instances, uint32_t stride, uint32_t n, const float view_projection[16], float lod[3])
{
    float *sizes = malloc((size_t)n * sizeof(float));
    for (uint32_t i = 0; i < n; ++i) sizes[i] = pixels_tall(instances + (size_t)i * stride, view_projection, lod[0]);
    qsort(sizes, n, sizeof(float), by_float);
    lod[2] = 0.5f * (sizes[n / 3 - 1] + sizes[n / 3]);
    lod[1] = 0.5f * (sizes[2 * n / 3 - 1] + sizes[2 * n / 3]);
    free(sizes);
}
