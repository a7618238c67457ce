/* mesh.c - runtime-ready meshes: palette-bone joints, fewer influences, quantized attributes,
 * batches of copies; and what they cost in vertex error (mesh.h). */
#include "crowdbake/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void cb_reduce_influences(const uint16_t joints[4], const float weights[4], uint32_t max, uint16_t out_joints[4],
                          float out_weights[4])
{
    int order[4] = {0, 1, 2, 3};
    for (int i = 1; i < 4; ++i) /* insertion sort, largest first; stable so ties keep file order */
        for (int k = i; k > 0 && weights[order[k]] > weights[order[k - 1]]; --k) {
            int t = order[k];
            order[k] = order[k - 1];
            order[k - 1] = t;
        }
    double sum = 0;
    for (uint32_t i = 0; i < max && i < 4; ++i) sum += weights[order[i]] > 0 ? weights[order[i]] : 0;
    for (uint32_t i = 0; i < 4; ++i) {
        bool keep = i < max && weights[order[i]] > 0 && sum > 0;
        out_joints[i] = keep ? joints[order[i]] : 0;
        out_weights[i] = keep ? (float)(weights[order[i]] / sum) : 0.0f;
    }
}

void cb_quantize_weights(const float weights[4], uint32_t scale, uint16_t out[4])
{
    double frac[4];
    uint32_t total = 0;
    for (int i = 0; i < 4; ++i) {
        double x = weights[i] > 0 ? weights[i] * (double)scale : 0;
        out[i] = (uint16_t)fmin(floor(x), scale);
        frac[i] = x - out[i];
        total += out[i];
    }
    /* Round up the largest remainders until the integers sum to `scale` (the first on a tie).
     * Only slots with a weight may grow, so a dropped influence stays dropped. */
    while (total < scale) {
        int best = -1;
        for (int i = 0; i < 4; ++i)
            if (weights[i] > 0 && out[i] < scale && (best < 0 || frac[i] > frac[best])) best = i;
        if (best < 0) break;
        out[best]++, frac[best] = -1, total++;
    }
}

static void free_part(cb_mesh_part *p)
{
    free(p->colors);
    free(p->positions), free(p->normals), free(p->texcoords), free(p->joints), free(p->weights);
    free(p->weights_q), free(p->normals_i8), free(p->texcoords_u16), free(p->indices), free(p->instance_ids);
}

void cb_mesh_free(cb_mesh *mesh)
{
    for (uint32_t i = 0; i < mesh->part_count; ++i) free_part(&mesh->parts[i]);
    free(mesh->parts);
    memset(mesh, 0, sizeof *mesh);
}

/* Quantizes a part's first copy in place: normals to i8, texcoords to u16 when in 0..1. */
static void quantize_part(cb_mesh_part *p, uint32_t n, cb_mesh *mesh)
{
    if (p->normals) {
        for (uint32_t i = 0; i < n; ++i) {
            float *v = p->normals + (size_t)i * 3;
            double len = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]), dot = 0, qlen = 0;
            for (int k = 0; k < 3; ++k) {
                double c = len > 0 ? v[k] / len : 0;
                p->normals_i8[(size_t)i * 3 + k] = (int8_t)lrint(fmax(-127, fmin(127, c * 127)));
            }
            for (int k = 0; k < 3; ++k) {
                double q = p->normals_i8[(size_t)i * 3 + k] / 127.0;
                dot += q * (len > 0 ? v[k] / len : 0), qlen += q * q;
                v[k] = (float)q; /* what a runtime reads back */
            }
            if (len > 0 && qlen > 0) {
                double angle = acos(fmin(1, dot / sqrt(qlen))) * 180 / 3.14159265358979323846;
                mesh->normal_error_deg = fmax(mesh->normal_error_deg, angle);
            }
        }
    }
    if (p->texcoords) {
        bool unit = true;
        for (uint32_t i = 0; i < n * 2 && unit; ++i) unit = p->texcoords[i] >= 0 && p->texcoords[i] <= 1;
        if (!unit) { /* u16 normalized holds 0..1 only: these stay float */
            free(p->texcoords_u16);
            p->texcoords_u16 = NULL;
            return;
        }
        for (uint32_t i = 0; i < n * 2; ++i) {
            p->texcoords_u16[i] = (uint16_t)lrint(p->texcoords[i] * 65535.0);
            float q = (float)(p->texcoords_u16[i] / 65535.0);
            mesh->texcoord_error = fmax(mesh->texcoord_error, fabs((double)q - p->texcoords[i]));
            p->texcoords[i] = q;
        }
    }
}

/* Copies 0 .. batch-1 of the first copy's `per` values of each of n vertices. */
#define REPEAT(arr, per, n, batch)                                                                     \
    do {                                                                                              \
        if (arr)                                                                                      \
            for (uint32_t c_ = 1; c_ < (batch); ++c_)                                                 \
                memcpy((arr) + (size_t)c_ * (n) * (per), (arr), (size_t)(n) * (per) * sizeof *(arr)); \
    } while (0)

static cb_status build_part(const char *source, const cb_primitive *src, const cb_skin *skin, const cb_mesh_options *o,
                            cb_mesh_part *p, cb_mesh *mesh, cb_error *err)
{
    uint32_t n = src->vertex_count, k = o->batch, ic = src->indices ? src->index_count : n;
    if ((uint64_t)n * k > UINT32_MAX || (uint64_t)ic * k > UINT32_MAX)
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_BATCH,
                               "%s: %u copies of %u vertices overflow 32-bit indices; batch fewer copies", source, k, n);
    size_t nk = (size_t)n * k;
    p->vertex_count = (uint32_t)nk;
    p->index_count = ic * k;
    p->positions = malloc(nk * 3 * sizeof(float));
    p->joints = malloc(nk * 4 * sizeof(uint16_t));
    p->weights = malloc(nk * 4 * sizeof(float));
    p->indices = malloc((size_t)p->index_count * sizeof(uint32_t));
    if (src->normals) p->normals = malloc(nk * 3 * sizeof(float));
    if (src->texcoords) p->texcoords = malloc(nk * 2 * sizeof(float));
    if (o->quantize) {
        p->weights_q = malloc(nk * 4 * sizeof(uint16_t));
        if (src->normals) p->normals_i8 = malloc(nk * 3);
        if (src->texcoords) p->texcoords_u16 = malloc(nk * 2 * sizeof(uint16_t));
    }
    if (k > 1) p->instance_ids = malloc(nk * sizeof(float));
    if (src->colors) p->colors = malloc(nk * 4 * sizeof(float));
    p->material = src->material;
    if ((src->colors && !p->colors) || !p->positions || !p->joints || !p->weights || !p->indices || (src->normals && !p->normals) ||
        (src->texcoords && !p->texcoords) || (o->quantize && (!p->weights_q || (src->normals && !p->normals_i8) ||
                                                              (src->texcoords && !p->texcoords_u16))) ||
        (k > 1 && !p->instance_ids))
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    memcpy(p->positions, src->positions, (size_t)n * 3 * sizeof(float));
    if (src->normals) memcpy(p->normals, src->normals, (size_t)n * 3 * sizeof(float));
    if (src->texcoords) memcpy(p->texcoords, src->texcoords, (size_t)n * 2 * sizeof(float));
    if (src->colors) memcpy(p->colors, src->colors, (size_t)n * 4 * sizeof(float));
    for (uint32_t v = 0; v < n; ++v) {
        uint16_t bones[4];
        for (int i = 0; i < 4; ++i) {
            uint16_t j = src->joints[(size_t)v * 4 + i];
            if (j >= skin->joint_count && src->weights[(size_t)v * 4 + i] != 0)
                return cb_fail(err, CB_ERR_INPUT, "%s: vertex %u uses joint %u of a skin with %u joints; re-export the mesh",
                               source, v, j, skin->joint_count);
            bones[i] = j >= skin->joint_count ? 0 : (uint16_t)(o->remap ? o->remap[j] : j);
        }
        uint16_t *oj = p->joints + (size_t)v * 4;
        float *ow = p->weights + (size_t)v * 4;
        cb_reduce_influences(bones, src->weights + (size_t)v * 4, o->max_influences, oj, ow);
        if (o->quantize) {
            uint16_t *q = p->weights_q + (size_t)v * 4, scale = o->weights_u16 ? 65535 : 255;
            cb_quantize_weights(ow, scale, q);
            for (int i = 0; i < 4; ++i) ow[i] = (float)(q[i] / (double)scale), oj[i] = q[i] ? oj[i] : 0;
        }
    }
    for (uint32_t i = 0; i < ic; ++i) p->indices[i] = src->indices ? src->indices[i] : i;
    if (o->quantize) quantize_part(p, n, mesh);
    REPEAT(p->positions, 3, n, k);
    REPEAT(p->normals, 3, n, k);
    REPEAT(p->texcoords, 2, n, k);
    REPEAT(p->joints, 4, n, k);
    REPEAT(p->weights, 4, n, k);
    REPEAT(p->weights_q, 4, n, k);
    REPEAT(p->normals_i8, 3, n, k);
    REPEAT(p->texcoords_u16, 2, n, k);
    REPEAT(p->colors, 4, n, k);
    for (uint32_t c = 1; c < k; ++c)
        for (uint32_t i = 0; i < ic; ++i) p->indices[(size_t)c * ic + i] = p->indices[i] + c * n;
    for (size_t v = 0; k > 1 && v < nk; ++v) p->instance_ids[v] = (float)(v / n);
    return CB_OK;
}

cb_status cb_mesh_build(const cb_model *model, int32_t skin, const cb_mesh_options *o, cb_mesh *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    out->batch = o->batch ? o->batch : 1;
    out->max_influences = o->max_influences;
    out->bone_count = o->bone_count;
    out->quantized = o->quantize;
    out->weight_scale = o->quantize ? (o->weights_u16 ? 65535 : 255) : 0;
    cb_mesh_options opt = *o;
    opt.batch = out->batch;
    for (uint32_t i = 0; i < model->primitive_count; ++i) out->part_count += model->primitives[i].skin == skin;
    out->parts = calloc(out->part_count ? out->part_count : 1, sizeof *out->parts);
    if (!out->parts) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    if (!out->part_count) {
        cb_mesh_free(out);
        return cb_fail(err, CB_ERR_INPUT, "%s: skin %d has no skinned mesh", model->source, skin);
    }
    for (uint32_t i = 0, p = 0; i < model->primitive_count; ++i) {
        if (model->primitives[i].skin != skin) continue;
        if (build_part(model->source, &model->primitives[i], &model->skins[skin], &opt, &out->parts[p++], out, err)) {
            cb_mesh_free(out);
            return err->status;
        }
    }
    return CB_OK;
}

void cb_mesh_bytes(const cb_mesh *mesh, uint64_t *vertex_bytes, uint64_t *index_bytes)
{
    *vertex_bytes = *index_bytes = 0;
    for (uint32_t i = 0; i < mesh->part_count; ++i) {
        const cb_mesh_part *p = &mesh->parts[i];
        uint32_t stride = 12 + (p->normals ? (p->normals_i8 ? 4 : 12) : 0) + (p->texcoords ? (p->texcoords_u16 ? 4 : 8) : 0) +
                          (mesh->bone_count <= 256 ? 4 : 8) + (p->weights_q ? (mesh->weight_scale == 255 ? 4 : 8) : 16) + (p->instance_ids ? 4 : 0) + (p->colors ? 16 : 0);
        *vertex_bytes += (uint64_t)stride * p->vertex_count;
        *index_bytes += (uint64_t)p->index_count * (p->vertex_count <= 65535 ? 2 : 4);
    }
}

void cb_mesh_batch_bytes(const cb_mesh *mesh, uint32_t copies, uint64_t *vertex_bytes, uint64_t *index_bytes)
{
    uint64_t vb, ib;
    cb_mesh_bytes(mesh, &vb, &ib);
    *vertex_bytes = *index_bytes = 0;
    for (uint32_t i = 0; i < mesh->part_count; ++i) {
        uint64_t n = (uint64_t)mesh->parts[i].vertex_count * copies;
        *vertex_bytes += 4 * n; /* the instance id */
        *index_bytes += (uint64_t)mesh->parts[i].index_count * copies * (n <= 65535 ? 2 : 4);
    }
    *vertex_bytes += vb * copies;
}

cb_status cb_mesh_build_measured(cb_sampler *ps, const cb_model *model, int32_t skin, const cb_mesh_options *o, double fps,
                                 double max_extra_mm, cb_mesh *out, cb_mesh_error *error, cb_error *err)
{
    if (cb_mesh_build(model, skin, o, out, err)) return err->status;
    if (cb_mesh_measure(ps, model, skin, out, o->remap, fps, error, err)) {
        cb_mesh_free(out);
        return err->status;
    }
    if (!o->quantize || o->weights_u16) return CB_OK;
    cb_mesh plain;
    cb_mesh_error plain_error;
    cb_mesh_options p = *o;
    p.quantize = false;
    if (cb_mesh_build(model, skin, &p, &plain, err) || cb_mesh_measure(ps, model, skin, &plain, o->remap, fps, &plain_error, err)) {
        cb_mesh_free(&plain);
        cb_mesh_free(out);
        return err->status;
    }
    cb_mesh_free(&plain);
    if (error->max_mm_per_m - plain_error.max_mm_per_m <= max_extra_mm) return CB_OK;
    cb_mesh_free(out); /* u8 weights cost too much here: u16 */
    p.quantize = true, p.weights_u16 = true;
    if (cb_mesh_build(model, skin, &p, out, err)) return err->status;
    if (cb_mesh_measure(ps, model, skin, out, o->remap, fps, error, err)) cb_mesh_free(out);
    return err->status;
}

/* ---- error ---- */

typedef struct measure_state {
    cb_primitive *ref, *test; /* per part: the model's skinning and the mesh's, first copies */
    double *mats, *a, *b;
    uint32_t parts;
} measure_state;

static void free_measure(measure_state *st)
{
    for (uint32_t i = 0; st->ref && i < st->parts; ++i) free(st->ref[i].joints);
    free(st->ref), free(st->test), free(st->mats), free(st->a), free(st->b);
}

/* Skins every part both ways with `mats`; updates the worst distance. */
static void compare_frame(measure_state *st, int32_t animation, double time, cb_mesh_error *out)
{
    uint64_t base = 0;
    for (uint32_t i = 0; i < st->parts; ++i) {
        cb_skin_positions(&st->ref[i], st->mats, st->a);
        cb_skin_positions(&st->test[i], st->mats, st->b);
        for (uint32_t v = 0; v < st->ref[i].vertex_count; ++v) {
            double dx = st->a[v * 3] - st->b[v * 3], dy = st->a[v * 3 + 1] - st->b[v * 3 + 1], dz = st->a[v * 3 + 2] - st->b[v * 3 + 2];
            double d = sqrt(dx * dx + dy * dy + dz * dz);
            if (d > out->max) out->max = d, out->worst_vertex = base + v, out->worst_animation = animation, out->worst_time = time;
        }
        base += st->ref[i].vertex_count;
    }
}

static double rest_height(measure_state *st)
{
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < st->parts; ++i) {
        cb_skin_positions(&st->ref[i], st->mats, st->a);
        for (uint32_t v = 0; v < st->ref[i].vertex_count; ++v) lo = fmin(lo, st->a[v * 3 + 1]), hi = fmax(hi, st->a[v * 3 + 1]);
    }
    return isfinite(hi - lo) ? hi - lo : 0;
}

cb_status cb_mesh_measure(cb_sampler *palette_sampler, const cb_model *model, int32_t skin, const cb_mesh *mesh,
                          const uint32_t *remap, double fps, cb_mesh_error *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    out->worst_animation = -1;
    const cb_model *pm = cb_sampler_model(palette_sampler);
    uint32_t bones = pm->skins[cb_sampler_skin(palette_sampler)].joint_count, most = 0;
    measure_state st = {0};
    st.parts = mesh->part_count;
    st.ref = calloc(st.parts, sizeof *st.ref);
    st.test = calloc(st.parts, sizeof *st.test);
    st.mats = malloc((size_t)bones * 16 * sizeof(double));
    if (!st.ref || !st.test || !st.mats) goto oom;
    for (uint32_t i = 0, p = 0; i < model->primitive_count; ++i) {
        const cb_primitive *src = &model->primitives[i];
        if (src->skin != skin) continue;
        cb_primitive *r = &st.ref[p], *t = &st.test[p];
        const cb_mesh_part *mp = &mesh->parts[p++];
        *r = *src;
        r->joints = malloc((size_t)src->vertex_count * 4 * sizeof(uint16_t));
        if (!r->joints) goto oom;
        for (size_t k = 0; k < (size_t)src->vertex_count * 4; ++k) {
            uint16_t j = src->joints[k];
            r->joints[k] = j >= model->skins[skin].joint_count ? 0 : (uint16_t)(remap ? remap[j] : j);
        }
        *t = *r;
        t->positions = mp->positions, t->joints = mp->joints, t->weights = mp->weights;
        most = src->vertex_count > most ? src->vertex_count : most;
    }
    st.a = malloc((size_t)most * 3 * sizeof(double));
    st.b = malloc((size_t)most * 3 * sizeof(double));
    if (!st.a || !st.b) goto oom;
    cb_sample_joint_matrices(palette_sampler, -1, 0, st.mats);
    out->height = rest_height(&st);
    compare_frame(&st, -1, 0, out);
    cb_limits limits = cb_default_limits();
    for (uint32_t a = 0; a < pm->animation_count; ++a) {
        cb_clip_info info;
        if (cb_clip_analyze(palette_sampler, (int32_t)a, fps, -1, &limits, &info, err)) {
            free_measure(&st);
            return err->status;
        }
        for (uint32_t f = 0; f < info.frames; ++f) {
            cb_clip_frame_matrices(palette_sampler, &info, f, CB_ROOT_MOTION_KEEP, st.mats);
            compare_frame(&st, (int32_t)a, cb_clip_frame_time(&info, f) - info.t0, out);
        }
        out->frames += info.frames;
    }
    out->max_mm_per_m = cb_mm_per_m(out->max, out->height);
    free_measure(&st);
    return CB_OK;
oom:
    free_measure(&st);
    return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
}
