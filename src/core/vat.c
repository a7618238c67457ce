/* vat.c - see vat.h. */
#include "crowdbake/vat.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void cb_vat_texel_xy(const cb_vat *vat, uint32_t frame, uint64_t vertex, uint32_t *x, uint32_t *y)
{
    uint64_t row = (uint64_t)frame * vat->rows_per_frame + vertex / vat->frame_width;
    uint32_t block = (uint32_t)(row / vat->geometry.height);
    *x = block * vat->frame_width + (uint32_t)(vertex % vat->frame_width);
    *y = (uint32_t)(row % vat->geometry.height);
}

void cb_vat_free(cb_vat *vat)
{
    free(vat->positions);
    free(vat->normals);
    memset(vat, 0, sizeof *vat);
}

/* Skinned normal: the blend of the joints' linear parts applied to n, renormalized. */
static void skin_normal(const cb_primitive *prim, const double *mats, uint32_t v, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    if (!prim->normals) return;
    const float *n = prim->normals + (size_t)v * 3;
    for (int i = 0; i < 4; ++i) {
        double w = prim->weights[(size_t)v * 4 + i];
        if (w == 0) continue;
        const double *m = mats + (size_t)prim->joints[(size_t)v * 4 + i] * 16;
        for (int k = 0; k < 3; ++k) out[k] += w * (m[k] * n[0] + m[4 + k] * n[1] + m[8 + k] * n[2]);
    }
    double len = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    for (int k = 0; k < 3 && len > 0; ++k) out[k] /= len;
}

static cb_status frame_plan(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *plan, uint32_t count,
                            cb_clip_info **infos, uint32_t *frames, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    if (!plan) count = m->animation_count;
    *infos = calloc(count ? count : 1, sizeof **infos);
    if (!*infos) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint64_t total = 0;
    for (uint32_t i = 0; i < count; ++i) {
        cb_clip_plan one = plan ? plan[i] : (cb_clip_plan){(int32_t)i, NULL, -1, 0, false, false, 0, NULL};
        if (cb_clip_analyze(s, one.animation, cb_clip_plan_fps(&one, o->fps), one.loop, &o->limits, &(*infos)[i], err))
            return err->status;
        total += (*infos)[i].frames;
    }
    if (total > o->limits.max_frames)
        return cb_fail(err, CB_ERR_INPUT, "%s: %llu frames, over the limit of %u", m->source, (unsigned long long)total,
                       o->limits.max_frames);
    *frames = (uint32_t)total;
    return CB_OK;
}

cb_status cb_vat_bake(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *plan, uint32_t plan_count, bool store,
                      cb_vat *vat, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    memset(vat, 0, sizeof *vat);
    vat->vertices = cb_model_skin_vertex_count(m, skin);
    if (vat->vertices == 0) return cb_fail(err, CB_ERR_INPUT, "%s: has no skinned vertices to bake", m->source);
    cb_clip_info *infos = NULL;
    double *mats = NULL, lo[3], hi[3];
    if (frame_plan(s, o, plan, plan_count, &infos, &vat->frames, err)) goto done;
    if (!cb_vat_geometry(vat->vertices, vat->frames, o->max_texture_size, &vat->geometry)) {
        cb_fail(err, CB_ERR_INPUT, "%s: a VAT of %llu vertices x %u frames exceeds a %u-texel texture even wrapped",
                m->source, (unsigned long long)vat->vertices, vat->frames, o->max_texture_size);
        goto done;
    }
    vat->frame_width = vat->vertices < o->max_texture_size ? (uint32_t)vat->vertices : o->max_texture_size;
    vat->rows_per_frame = (uint32_t)((vat->vertices + vat->frame_width - 1) / vat->frame_width);
    size_t texels = (size_t)vat->geometry.width * vat->geometry.height;
    mats = malloc((size_t)m->skins[skin].joint_count * 16 * sizeof(double));
    if (store) {
        vat->positions = calloc(texels * 4, sizeof(uint16_t));
        vat->normals = calloc(texels * 4, sizeof(uint16_t));
    }
    if (!mats || (store && (!vat->positions || !vat->normals))) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for a %ux%u VAT", m->source, vat->geometry.width,
                vat->geometry.height);
        goto done;
    }
    uint32_t frame = 0;
    for (uint32_t c = 0; c < (plan ? plan_count : m->animation_count); ++c)
        for (uint32_t f = 0; f < infos[c].frames; ++f, ++frame) {
            cb_clip_frame_matrices(s, &infos[c], f, o->root_motion, mats);
            uint64_t v0 = 0;
            for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
                const cb_primitive *prim = &m->primitives[pi];
                if (prim->skin != skin) continue;
                for (uint32_t v = 0; v < prim->vertex_count; ++v) {
                    double p[3], n[3];
                    cb_skin_positions(&(cb_primitive){.vertex_count = 1, .positions = prim->positions + (size_t)v * 3,
                                                       .joints = prim->joints + (size_t)v * 4,
                                                       .weights = prim->weights + (size_t)v * 4},
                                      mats, p);
                    double e2 = 0;
                    uint16_t hp[3];
                    for (int k = 0; k < 3; ++k) {
                        hp[k] = cb_float_to_half((float)p[k]);
                        double d = cb_half_to_float(hp[k]) - p[k];
                        e2 += d * d;
                    }
                    if (sqrt(e2) > vat->max_error) vat->max_error = sqrt(e2);
                    if (!store) continue;
                    skin_normal(prim, mats, v, n);
                    uint32_t x, y;
                    cb_vat_texel_xy(vat, frame, v0 + v, &x, &y);
                    uint16_t *P = vat->positions + ((size_t)y * vat->geometry.width + x) * 4;
                    uint16_t *N = vat->normals + ((size_t)y * vat->geometry.width + x) * 4;
                    for (int k = 0; k < 3; ++k) P[k] = hp[k], N[k] = cb_float_to_half((float)n[k]);
                    P[3] = cb_float_to_half(1.0f);
                    N[3] = 0;
                }
                v0 += prim->vertex_count;
            }
        }
    vat->model_height = cb_skin_rest_bounds(s, lo, hi);
done:
    free(infos);
    free(mats);
    if (err->status) cb_vat_free(vat);
    return err->status;
}
