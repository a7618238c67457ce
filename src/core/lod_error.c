/* lod_error.c - what the animation LOD costs (cb_measure_lod_error): each vertex skinned with
 * every influence, with its 2 largest and with its largest alone, over a model's frames.
 *
 * The reference is the skin as a runtime draws it without LOD (the weights as stored); the
 * tiers keep and renormalize weights as cb_reduce_influences does, which is what `crowdbake
 * mesh --max-influences` writes and what the shaders' cb_lod_influences keeps. */
#include "crowdbake/mesh.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

/* A vertex as the three skins read it: its weighted influences (a joint outside the skin as joint
 * 0, as cb_mesh_measure takes it) and, worked out once, the slots the tiers keep. */
typedef struct lod_vertex {
    const float *x;
    uint32_t joints[4];
    float weights[4];
    uint8_t count;          /* influences with weight */
    uint8_t first, second;  /* the largest weight's slot and the next's (first on a tie, as cb_reduce_influences) */
    double one_second_share; /* tier 2: the second's share of the two (0: one influence) */
} lod_vertex;

static bool vertex_of(const cb_primitive *prim, uint32_t v, uint32_t joint_count, lod_vertex *out)
{
    const uint16_t *j = prim->joints + (size_t)v * 4;
    const float *w = prim->weights + (size_t)v * 4;
    *out = (lod_vertex){.x = prim->positions + (size_t)v * 3};
    for (int i = 0; i < 4; ++i)
        if (w[i] > 0) out->joints[out->count] = j[i] < joint_count ? j[i] : 0, out->weights[out->count++] = w[i];
    if (!out->count) return false; /* no weight: nothing skins it */
    for (uint8_t k = 1; k < out->count; ++k)
        if (out->weights[k] > out->weights[out->first]) out->first = k;
    int second = -1;
    for (uint8_t k = 0; k < out->count; ++k)
        if (k != out->first && (second < 0 || out->weights[k] > out->weights[second])) second = k;
    if (second >= 0) {
        out->second = (uint8_t)second;
        out->one_second_share = out->weights[second] / ((double)out->weights[out->first] + out->weights[second]);
    }
    return true;
}

/* One frame: every vertex's influence points once, the three skins from them. */
static void frame_lod_error(const lod_vertex *verts, size_t count, const double *mats, int32_t animation, double time,
                            cb_lod_error *out)
{
    for (size_t v = 0; v < count; ++v) {
        const lod_vertex *lv = &verts[v];
        double p[4][3], full[3] = {0, 0, 0};
        for (int i = 0; i < lv->count; ++i) {
            const double *m = mats + (size_t)lv->joints[i] * 16;
            const float *x = lv->x;
            for (int r = 0; r < 3; ++r) {
                p[i][r] = m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r];
                full[r] += lv->weights[i] * p[i][r];
            }
        }
        double s = lv->one_second_share, one = 0, two = 0;
        for (int r = 0; r < 3; ++r) {
            double a = p[lv->first][r] - full[r];
            double b = (s > 0 ? (1 - s) * p[lv->first][r] + s * p[lv->second][r] : p[lv->first][r]) - full[r];
            one += a * a, two += b * b;
        }
        out->two = fmax(out->two, sqrt(two));
        if (sqrt(one) > out->one) out->one = sqrt(one), out->worst_animation = animation, out->worst_time = time;
    }
}

/* The skin's vertices that some weight skins, as lod_vertex; NULL on no memory. */
static lod_vertex *skin_vertices(const cb_model *model, int32_t skin, size_t *count)
{
    size_t n = 0;
    for (uint32_t i = 0; i < model->primitive_count; ++i)
        if (model->primitives[i].skin == skin) n += model->primitives[i].vertex_count;
    lod_vertex *verts = malloc((n ? n : 1) * sizeof *verts);
    *count = 0;
    for (uint32_t i = 0; verts && i < model->primitive_count; ++i) {
        const cb_primitive *prim = &model->primitives[i];
        if (prim->skin != skin || !prim->joints || !prim->weights) continue;
        for (uint32_t v = 0; v < prim->vertex_count; ++v)
            if (vertex_of(prim, v, model->skins[skin].joint_count, &verts[*count])) ++*count;
    }
    return verts;
}

cb_status cb_measure_lod_error(cb_sampler *sampler, double fps, const int32_t *animations, uint32_t count,
                               cb_lod_error *out, cb_error *err)
{
    const cb_model *model = cb_sampler_model(sampler);
    int32_t skin = cb_sampler_skin(sampler);
    *out = (cb_lod_error){0, 0, 0, 0, -1, 0};
    if (!(fps > 0)) return cb_fail(err, CB_ERR_SETTINGS, "lod error: fps must be positive (got %g)", fps);
    size_t vertex_count;
    lod_vertex *verts = skin_vertices(model, skin, &vertex_count);
    double *mats = malloc((size_t)model->skins[skin].joint_count * 16 * sizeof(double));
    if (!verts || !mats) {
        free(verts), free(mats);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory measuring the LOD's error of %s", model->source);
    }
    double lo[3], hi[3];
    out->height = cb_skin_rest_bounds(sampler, lo, hi);
    cb_limits limits = cb_default_limits();
    uint32_t n = count ? count : model->animation_count;
    cb_status status = CB_OK;
    for (uint32_t k = 0; k < n && !status; ++k) {
        int32_t a = count ? animations[k] : (int32_t)k;
        cb_clip_info info;
        if ((status = cb_clip_analyze(sampler, a, fps, -1, &limits, &info, err))) break;
        for (uint32_t f = 0; f < info.frames; ++f) { /* the frames cb_mesh_measure skins */
            cb_clip_frame_matrices(sampler, &info, f, CB_ROOT_MOTION_KEEP, mats);
            frame_lod_error(verts, vertex_count, mats, a, cb_clip_frame_time(&info, f) - info.t0, out);
        }
        out->frames += info.frames;
    }
    free(mats);
    free(verts);
    return status;
}
