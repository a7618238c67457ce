/* skinning.c - exact (double precision) linear blend skinning: the ground truth that
 * palette encodings and runtimes are measured against. */
#include <math.h>
#include <stdlib.h>

#include "cb_math.h"
#include "lanes.h"
#include "crowdbake/core.h"

/* The matrix products run on 4 lanes (the 4th, the matrices' last row, is dropped): one AVX2
 * vector each where the CPU has it, with the scalar code's operations in its order
 * (cb_skin_vertex, lanes.h). */
CB_TARGET_CLONES
void cb_skin_positions(const cb_primitive *prim, const double *joint_mats, double *out)
{
    for (uint32_t v = 0; v < prim->vertex_count; ++v) cb_skin_vertex(prim, v, joint_mats, out + (size_t)v * 3);
}

double cb_skin_rest_bounds(cb_sampler *sampler, double min[3], double max[3])
{
    const cb_model *m = cb_sampler_model(sampler);
    int32_t skin = cb_sampler_skin(sampler);
    for (int k = 0; k < 3; ++k) min[k] = INFINITY, max[k] = -INFINITY;
    double *mats = malloc((size_t)m->skins[skin].joint_count * 16 * sizeof(double));
    if (!mats) return 0;
    cb_sample_joint_matrices(sampler, -1, 0, mats);
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        const cb_primitive *prim = &m->primitives[p];
        if (prim->skin != skin) continue;
        double *pos = malloc((size_t)prim->vertex_count * 3 * sizeof(double));
        if (!pos) break;
        cb_skin_positions(prim, mats, pos);
        for (uint32_t v = 0; v < prim->vertex_count; ++v)
            for (int k = 0; k < 3; ++k) {
                min[k] = fmin(min[k], pos[(size_t)v * 3 + k]);
                max[k] = fmax(max[k], pos[(size_t)v * 3 + k]);
            }
        free(pos);
    }
    free(mats);
    return isfinite(max[1] - min[1]) ? max[1] - min[1] : 0;
}
