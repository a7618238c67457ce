/* sample.c - glTF 2.0 animation sampling: channel interpolation, the node hierarchy and
 * joint matrices. */
#include "cb_math.h"
#include "sampler.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Key times are float32 in files: a STEP key this close to the sample time counts as reached. */
#define CB_STEP_EPSILON 1e-6


static void load_key(const cb_channel *ch, uint32_t k, int slot, int comps, double out[4])
{
    int stride = comps * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
    const float *v = ch->values + (size_t)k * stride + slot * comps;
    for (int i = 0; i < comps; ++i) out[i] = v[i];
}

static void eval_cubic(const cb_channel *ch, uint32_t k, double s, double dt, int comps, double out[4])
{
    double p0[4], b0[4], p1[4], a1[4];
    load_key(ch, k, 1, comps, p0);
    load_key(ch, k, 2, comps, b0);     /* out-tangent of key k */
    load_key(ch, k + 1, 1, comps, p1);
    load_key(ch, k + 1, 0, comps, a1); /* in-tangent of key k + 1 */
    double s2 = s * s, s3 = s2 * s;
    double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    for (int i = 0; i < comps; ++i) out[i] = h00 * p0[i] + h10 * dt * b0[i] + h01 * p1[i] + h11 * dt * a1[i];
}

static void channel_eval(const cb_channel *ch, double t, double out[4], uint32_t *hint, const cb_wrap *wrap);

/* A loop without a closing key, between its last key time and the end of its period: each
 * channel goes from its value at the last key time back to its first key, as the missing
 * closing key would make it (linearly; rotations by slerp; STEP holds). */
static void wrap_eval(const cb_channel *ch, double t, double out[4], uint32_t *hint, const cb_wrap *wrap)
{
    int comps = ch->path == CB_PATH_ROTATION ? 4 : 3;
    double a[4], b[4], s = (t - wrap->from) / (wrap->to - wrap->from);
    channel_eval(ch, wrap->from, a, hint, NULL);
    load_key(ch, 0, ch->interp == CB_INTERP_CUBICSPLINE ? 1 : 0, comps, b);
    if (ch->interp == CB_INTERP_STEP) s = 0;
    if (comps == 4) {
        cb_quat q = cb_quat_slerp((cb_quat){a[0], a[1], a[2], a[3]}, (cb_quat){b[0], b[1], b[2], b[3]}, s);
        out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
    } else {
        for (int i = 0; i < 3; ++i) out[i] = a[i] + (b[i] - a[i]) * s;
    }
}

static void channel_eval(const cb_channel *ch, double t, double out[4], uint32_t *hint, const cb_wrap *wrap)
{
    int comps = ch->path == CB_PATH_ROTATION ? 4 : 3;
    int value_slot = ch->interp == CB_INTERP_CUBICSPLINE ? 1 : 0;
    uint32_t last = ch->key_count - 1;
    if (wrap && t > wrap->from && wrap->to > wrap->from) {
        wrap_eval(ch, t, out, hint, wrap);
        return;
    }
    if (ch->interp == CB_INTERP_STEP) {
        load_key(ch, cb_find_key(ch->times, ch->key_count, t + CB_STEP_EPSILON, hint), 0, comps, out);
        return;
    }
    if (t <= ch->times[0] || last == 0) {
        load_key(ch, 0, value_slot, comps, out);
        return;
    }
    if (t >= ch->times[last]) {
        load_key(ch, last, value_slot, comps, out);
        return;
    }
    uint32_t k = cb_find_key(ch->times, ch->key_count, t, hint);
    double t_k = ch->times[k], dt = (double)ch->times[k + 1] - t_k;
    double s = (t - t_k) / dt;
    if (ch->interp == CB_INTERP_CUBICSPLINE) {
        eval_cubic(ch, k, s, dt, comps, out);
        if (comps == 4) {
            cb_quat q = cb_quat_normalize((cb_quat){out[0], out[1], out[2], out[3]});
            out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
        }
        return;
    }
    const float *a = ch->values + (size_t)k * comps, *b = a + comps;
    if (comps == 4) {
        cb_quat q = cb_quat_slerp((cb_quat){a[0], a[1], a[2], a[3]}, (cb_quat){b[0], b[1], b[2], b[3]}, s);
        out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
    } else {
        for (int i = 0; i < 3; ++i) out[i] = a[i] + ((double)b[i] - a[i]) * s;
    }
}

void cb_channel_eval(const cb_channel *ch, double t, double out[4])
{
    uint32_t hint = 0;
    channel_eval(ch, t, out, &hint, NULL);
}

void cb_channel_eval_at(const cb_channel *ch, double t, double out[4], uint32_t *hint, const cb_wrap *wrap)
{
    channel_eval(ch, t, out, hint, wrap);
}

static uint32_t node_depth(const cb_model *m, uint32_t n)
{
    uint32_t d = 0;
    for (int32_t p = m->nodes[n].parent; p >= 0; p = m->nodes[p].parent) ++d;
    return d;
}

/* ---- similarities: rigs of rotations, uniform scales and translations ---- */

/* Relative: float32 inverse bind matrices of real rigs deviate by ~1e-7 from similarities. */
#define CB_SIMILARITY_TOLERANCE 1e-6

/* The uniform scale of (x, y, z), when they agree within the tolerance and are positive. */
static bool uniform_scale(double x, double y, double z, double *out)
{
    double s = (x + y + z) / 3, tol = CB_SIMILARITY_TOLERANCE * s;
    *out = s;
    return s > 0 && fabs(x - s) <= tol && fabs(y - s) <= tol && fabs(z - s) <= tol;
}

/* The similarity an affine matrix is, when it is one: equal, orthogonal columns, no mirror. */
static bool similarity_from_matrix(const double m[16], cb_similarity *out)
{
    if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) return false;
    cb_vec3 c[3] = {{m[0], m[1], m[2]}, {m[4], m[5], m[6]}, {m[8], m[9], m[10]}};
    double s;
    if (!uniform_scale(cb_vec3_length(c[0]), cb_vec3_length(c[1]), cb_vec3_length(c[2]), &s) ||
        cb_mat4_determinant3(m) <= 0)
        return false;
    double tol = CB_SIMILARITY_TOLERANCE * s * s;
    if (fabs(cb_vec3_dot(c[0], c[1])) > tol || fabs(cb_vec3_dot(c[0], c[2])) > tol || fabs(cb_vec3_dot(c[1], c[2])) > tol)
        return false;
    double r[16];
    for (int i = 0; i < 16; ++i) r[i] = m[i] / s;
    cb_quat q = cb_quat_from_mat4(r);
    *out = (cb_similarity){{q.x, q.y, q.z, q.w}, {m[12], m[13], m[14]}, s};
    return true;
}

static bool node_similarity(const cb_node *n, cb_similarity *out)
{
    if (n->has_matrix) return similarity_from_matrix(n->matrix, out);
    memcpy(out->rotation, n->rotation, sizeof out->rotation);
    memcpy(out->translation, n->translation, sizeof out->translation);
    return uniform_scale(n->scale[0], n->scale[1], n->scale[2], &out->scale);
}

/* Scale keys a similarity can follow: uniform and positive, and not a spline, which can
 * overshoot through zero between positive keys. */
static bool scale_channel_similar(const cb_channel *ch)
{
    if (ch->interp == CB_INTERP_CUBICSPLINE) return false;
    double s;
    for (uint32_t k = 0; k < ch->key_count; ++k)
        if (!uniform_scale(ch->values[k * 3], ch->values[k * 3 + 1], ch->values[k * 3 + 2], &s)) return false;
    return true;
}

static bool rig_is_similar(const cb_sampler *s)
{
    const cb_model *m = s->model;
    const cb_skin *sk = &m->skins[s->skin];
    for (uint32_t k = 0; k < s->relevant_count; ++k) {
        uint32_t i = s->relevant_order[k];
        if (!node_similarity(&m->nodes[i], &s->sim_rest[i])) return false;
    }
    for (uint32_t j = 0; j < sk->joint_count; ++j)
        if (!similarity_from_matrix(sk->inverse_bind + (size_t)j * 16, &s->sim_ibm[j])) return false;
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) {
            const cb_channel *ch = &m->animations[a].channels[c];
            if (s->relevant[ch->node] && ch->path == CB_PATH_SCALE && !scale_channel_similar(ch)) return false;
        }
    return true;
}

/* Returns false only when out of memory. */
static bool prepare_similarity(cb_sampler *s)
{
    const cb_model *m = s->model;
    const cb_skin *sk = &m->skins[s->skin];
    size_t n = m->node_count ? m->node_count : 1;
    s->relevant = calloc(n, sizeof *s->relevant);
    s->relevant_order = calloc(n, sizeof *s->relevant_order);
    s->slot = calloc(n, sizeof *s->slot);
    s->parent_slot = calloc(n, sizeof *s->parent_slot);
    s->sim_rest = calloc(n, sizeof *s->sim_rest);
    s->sim_ibm = calloc(sk->joint_count ? sk->joint_count : 1, sizeof *s->sim_ibm);
    if (!s->relevant || !s->relevant_order || !s->slot || !s->parent_slot || !s->sim_rest || !s->sim_ibm)
        return false;
    for (uint32_t j = 0; j < sk->joint_count; ++j)
        for (int32_t p = sk->joints[j]; p >= 0 && !s->relevant[p]; p = m->nodes[p].parent) s->relevant[p] = true;
    for (uint32_t k = 0; k < m->node_count; ++k)
        if (s->relevant[s->order[k]]) {
            s->slot[s->order[k]] = s->relevant_count;
            s->relevant_order[s->relevant_count++] = s->order[k];
        }
    for (uint32_t k = 0; k < s->relevant_count; ++k) { /* a relevant node's parent is relevant, and before it */
        int32_t p = m->nodes[s->relevant_order[k]].parent;
        s->parent_slot[k] = p >= 0 ? (int32_t)s->slot[p] : -1;
    }
    s->similar = rig_is_similar(s);
    if (s->similar) {
        s->lanes = malloc((s->relevant_count ? s->relevant_count : 1) * sizeof(double) * 8 * CB_SAMPLE_BATCH);
        if (!s->lanes || !cb_sampler_prepare_spans(s)) return false;
    }
    return true;
}

bool cb_sampler_is_similarity(const cb_sampler *s) { return s->similar; }


void cb_similarity_matrix(const cb_similarity *s, double out[16])
{
    cb_quat q = {s->rotation[0], s->rotation[1], s->rotation[2], s->rotation[3]};
    cb_mat4_from_trs(out, (cb_vec3){s->translation[0], s->translation[1], s->translation[2]}, q,
                     (cb_vec3){s->scale, s->scale, s->scale});
}

void cb_sample_joint_similarities(cb_sampler *s, int32_t animation, double t, cb_similarity *out)
{
    cb_sample_joint_similarities_batch(s, animation, &t, 1, out);
}

/* ---- the sampler ---- */

cb_sampler *cb_sampler_create(const cb_model *model, int32_t skin, cb_error *err)
{
    if (skin < 0 || skin >= (int32_t)model->skin_count) {
        cb_fail(err, CB_ERR_INPUT, "%s: has no skin %d (it has %u)", model->source, skin, model->skin_count);
        return NULL;
    }
    uint32_t n = model->node_count;
    cb_sampler *s = calloc(1, sizeof *s);
    uint32_t *depth = calloc(n ? n : 1, sizeof *depth);
    if (s) {
        s->order = calloc(n ? n : 1, sizeof *s->order);
        s->local_trs = calloc(n ? (size_t)n * 10 : 1, sizeof *s->local_trs);
        s->animated = calloc(n ? n : 1, sizeof *s->animated);
        s->globals = calloc(n ? (size_t)n * 16 : 1, sizeof *s->globals);
    }
    if (!s || !depth || !s->order || !s->local_trs || !s->animated || !s->globals) {
        free(depth);
        cb_sampler_free(s);
        cb_fail(err, CB_ERR_INTERNAL, "out of memory creating a sampler for %s", model->source);
        return NULL;
    }
    s->model = model;
    s->skin = skin;
    s->affine_ibm = true;
    const cb_skin *sk = &model->skins[skin];
    for (uint32_t j = 0; j < sk->joint_count; ++j) {
        const double *m = sk->inverse_bind + (size_t)j * 16;
        if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) s->affine_ibm = false;
    }
    uint32_t channels = 0;
    s->cursor_base = calloc(model->animation_count + 1, sizeof *s->cursor_base);
    for (uint32_t a = 0; s->cursor_base && a < model->animation_count; ++a) {
        s->cursor_base[a] = channels;
        channels += model->animations[a].channel_count;
    }
    s->cursor = calloc(channels + 1, sizeof *s->cursor);
    s->wraps = calloc(model->animation_count + 1, sizeof *s->wraps);
    s->closed = calloc(model->animation_count + 1, sizeof *s->closed);
    s->closed_with = calloc((size_t)(model->animation_count + 1) * 5, sizeof *s->closed_with);
    if (!s->cursor_base || !s->cursor || !s->wraps || !s->closed || !s->closed_with) {
        free(depth);
        cb_sampler_free(s);
        cb_fail(err, CB_ERR_INTERNAL, "out of memory creating a sampler for %s", model->source);
        return NULL;
    }
    /* Order by depth (a stable counting sort) so parents are evaluated first. */
    uint32_t max_depth = 0;
    for (uint32_t i = 0; i < n; ++i) {
        depth[i] = node_depth(model, i);
        if (depth[i] > max_depth) max_depth = depth[i];
    }
    uint32_t filled = 0;
    for (uint32_t d = 0; d <= max_depth && filled < n; ++d)
        for (uint32_t i = 0; i < n; ++i)
            if (depth[i] == d) s->order[filled++] = i;
    free(depth);
    if (!prepare_similarity(s)) {
        cb_sampler_free(s);
        cb_fail(err, CB_ERR_INTERNAL, "out of memory creating a sampler for %s", model->source);
        return NULL;
    }
    return s;
}

void cb_sampler_free(cb_sampler *s)
{
    if (!s) return;
    free(s->relevant);
    free(s->relevant_order);
    free(s->slot);
    free(s->parent_slot);
    free(s->sim_rest);
    free(s->sim_ibm);
    free(s->lanes);
    free(s->span_group);
    free(s->group_base);
    free(s->group_times);
    free(s->group_keys);
    free(s->group_cursor);
    free(s->spans);
    free(s->clip_paths);
    free(s->order);
    free(s->local_trs);
    free(s->animated);
    free(s->globals);
    free(s->cursor);
    free(s->cursor_base);
    free(s->wraps);
    for (uint32_t a = 0; s->closed && a < s->model->animation_count; ++a) cb_sampler_open_clip(s, (int32_t)a);
    free(s->closed);
    free(s->closed_with);
    free(s);
}

void cb_sampler_set_period(cb_sampler *s, int32_t animation, double period)
{
    if (animation < 0 || animation >= (int32_t)s->model->animation_count) return;
    const cb_animation *a = &s->model->animations[animation];
    /* Within a microsecond of the key span: a closed loop, whose last key is its first pose. */
    bool open = period > a->t1 - a->t0 + 1e-6;
    s->wraps[animation] = open ? (cb_wrap){a->t1, a->t0 + period} : (cb_wrap){0, 0};
}

const cb_model *cb_sampler_model(const cb_sampler *s) { return s->model; }
int32_t cb_sampler_skin(const cb_sampler *s) { return s->skin; }

static void local_matrix(const cb_sampler *s, uint32_t node, double out[16])
{
    const cb_node *n = &s->model->nodes[node];
    if (n->has_matrix && !s->animated[node]) {
        memcpy(out, n->matrix, sizeof n->matrix);
        return;
    }
    const double *trs = s->local_trs + (size_t)node * 10;
    cb_mat4_from_trs(out, (cb_vec3){trs[0], trs[1], trs[2]}, (cb_quat){trs[3], trs[4], trs[5], trs[6]},
                     (cb_vec3){trs[7], trs[8], trs[9]});
}

/* The global matrices of the nodes order[0 .. count - 1] (parents first; a node's parent among
 * them, or a root) at time t: every node (cb_sample_globals) or only those the joints hang from
 * (`relevant`: cb_sample_joint_matrices). */
CB_TARGET_CLONES
static void sample_nodes(cb_sampler *s, int32_t animation, double t, const uint32_t *order, uint32_t count,
                         const bool *relevant)
{
    const cb_model *m = s->model;
    for (uint32_t k = 0; k < count; ++k) {
        uint32_t i = order[k];
        double *trs = s->local_trs + (size_t)i * 10;
        memcpy(trs, m->nodes[i].translation, 3 * sizeof(double));
        memcpy(trs + 3, m->nodes[i].rotation, 4 * sizeof(double));
        memcpy(trs + 7, m->nodes[i].scale, 3 * sizeof(double));
        s->animated[i] = false;
    }
    if (animation >= 0 && animation < (int32_t)m->animation_count) {
        const cb_animation *anim = cb_sampler_clip(s, animation);
        for (uint32_t c = 0; c < anim->channel_count; ++c) {
            const cb_channel *ch = &anim->channels[c];
            if (relevant && !relevant[ch->node]) continue;
            double v[4];
            channel_eval(ch, t, v, &s->cursor[s->cursor_base[animation] + c], &s->wraps[animation]);
            double *trs = s->local_trs + (size_t)ch->node * 10;
            int offset = ch->path == CB_PATH_TRANSLATION ? 0 : ch->path == CB_PATH_ROTATION ? 3 : 7;
            memcpy(trs + offset, v, (ch->path == CB_PATH_ROTATION ? 4 : 3) * sizeof(double));
            s->animated[ch->node] = true;
        }
    }
    for (uint32_t k = 0; k < count; ++k) {
        uint32_t i = order[k];
        double local[16];
        local_matrix(s, i, local);
        int32_t p = m->nodes[i].parent;
        if (p < 0)
            memcpy(s->globals + (size_t)i * 16, local, sizeof local);
        else
            cb_mat4_mul_affine(s->globals + (size_t)i * 16, s->globals + (size_t)p * 16, local);
    }
}

const double *cb_sample_globals(cb_sampler *s, int32_t animation, double t)
{
    sample_nodes(s, animation, t, s->order, s->model->node_count, NULL);
    return s->globals;
}

void cb_sample_joint_matrices(cb_sampler *s, int32_t animation, double t, double *out)
{
    sample_nodes(s, animation, t, s->relevant_order, s->relevant_count, s->relevant);
    const double *globals = s->globals;
    const cb_skin *skin = &s->model->skins[s->skin];
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        const double *ibm = skin->inverse_bind + (size_t)j * 16;
        if (s->affine_ibm)
            cb_mat4_mul_affine(out + (size_t)j * 16, globals + (size_t)skin->joints[j] * 16, ibm);
        else
            cb_mat4_mul(out + (size_t)j * 16, globals + (size_t)skin->joints[j] * 16, ibm);
    }
}

uint32_t cb_skin_root_joint(const cb_model *model, int32_t skin_index)
{
    const cb_skin *skin = &model->skins[skin_index];
    uint32_t best = 0, best_depth = UINT32_MAX;
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        uint32_t d = node_depth(model, (uint32_t)skin->joints[j]);
        if (d < best_depth) {
            best_depth = d;
            best = j;
        }
    }
    return best;
}
