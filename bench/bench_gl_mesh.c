/* bench_gl_mesh.c - see bench_gl_mesh.h. */
#include "bench_gl_mesh.h"

#include <stdlib.h>
#include <string.h>

void bench_sort_influences(int32_t *joints, float *weights, uint32_t vertices)
{
    for (uint32_t v = 0; v < vertices; ++v) { /* insertion sort of four, descending */
        int32_t *j = joints + v * 4;
        float *w = weights + v * 4;
        for (int a = 1; a < 4; ++a)
            for (int b = a; b > 0 && w[b] > w[b - 1]; --b) {
                float tw = w[b];
                int32_t tj = j[b];
                w[b] = w[b - 1], j[b] = j[b - 1], w[b - 1] = tw, j[b - 1] = tj;
            }
    }
}

static int influence_count(const float *weights, uint32_t v)
{
    const float *w = weights + v * 4;
    return w[3] != 0 ? 4 : w[2] != 0 ? 3 : w[1] != 0 ? 2 : 1;
}

void bench_sort_triangles(uint32_t *indices, uint32_t index_count, const float *weights)
{
    uint32_t triangles = index_count / 3, at = 0;
    uint32_t *out = malloc((size_t)index_count * sizeof *out);
    if (!out) return; /* the order is an optimisation: the mesh stays as it was */
    for (int count = 1; count <= 4; ++count) /* a counting sort by the triangle's largest count: stable */
        for (uint32_t t = 0; t < triangles; ++t) {
            const uint32_t *tri = indices + t * 3;
            int c = influence_count(weights, tri[0]);
            for (int k = 1; k < 3; ++k) c = influence_count(weights, tri[k]) > c ? influence_count(weights, tri[k]) : c;
            if (c == count) memcpy(out + at, tri, 3 * sizeof *tri), at += 3;
        }
    memcpy(indices, out, (size_t)at * sizeof *out);
    free(out);
}
