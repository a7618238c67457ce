/* model_validate.c - cb_model_validate: a loaded model checked whole (nodes, skins, meshes,
 * every animation key) before anything samples it, each problem named with its place. */
#include "cb_math.h"
#include "crowdbake/core.h"
#include "key_scan.h"
#include "internal/plumbing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *path_name(cb_path p)
{
    return p == CB_PATH_TRANSLATION ? "translation" : p == CB_PATH_ROTATION ? "rotation" : "scale";
}

/* Gives every node a TRS: matrix nodes are decomposed (an animation channel may replace
 * parts of it), rotations are normalized. */
static void normalize_node_transforms(cb_model *m)
{
    for (uint32_t i = 0; i < m->node_count; ++i) {
        cb_node *n = &m->nodes[i];
        if (n->has_matrix) {
            cb_vec3 t, s;
            cb_quat r;
            cb_mat4_decompose(n->matrix, &t, &r, &s, 1e-4);
            double trs[10] = {t.x, t.y, t.z, r.x, r.y, r.z, r.w, s.x, s.y, s.z};
            memcpy(n->translation, trs, sizeof n->translation);
            memcpy(n->rotation, trs + 3, sizeof n->rotation);
            memcpy(n->scale, trs + 7, sizeof n->scale);
        } else if (isfinite(n->rotation[0] + n->rotation[1] + n->rotation[2] + n->rotation[3])) {
            cb_quat q = cb_quat_normalize((cb_quat){n->rotation[0], n->rotation[1], n->rotation[2], n->rotation[3]});
            n->rotation[0] = q.x, n->rotation[1] = q.y, n->rotation[2] = q.z, n->rotation[3] = q.w;
        }
    }
}

static cb_status validate_nodes(cb_model *m, cb_error *err)
{
    for (uint32_t i = 0; i < m->node_count; ++i) {
        const cb_node *n = &m->nodes[i];
        if (n->parent < -1 || n->parent >= (int32_t)m->node_count)
            return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has parent %d out of range", m->source, i, n->name,
                           n->parent);
        for (int k = 0; k < 3; ++k)
            if (!isfinite(n->translation[k]) || !isfinite(n->scale[k]))
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has a NaN or infinite transform", m->source, i,
                               n->name);
        for (int k = 0; k < 4; ++k)
            if (!isfinite(n->rotation[k]))
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has a NaN or infinite rotation", m->source, i,
                               n->name);
        for (int k = 0; k < 16 && n->has_matrix; ++k)
            if (!isfinite(n->matrix[k]))
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has a NaN or infinite matrix", m->source, i, n->name);
        /* Walking up at most node_count steps finds a root unless there is a cycle. */
        int32_t p = n->parent;
        for (uint32_t steps = 0; p >= 0; ++steps) {
            if (steps >= m->node_count)
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) is part of a cycle in the node hierarchy",
                               m->source, i, n->name);
            p = m->nodes[p].parent;
        }
    }
    return CB_OK;
}

static cb_status validate_skins(const cb_model *m, const cb_limits *limits, cb_error *err)
{
    for (uint32_t s = 0; s < m->skin_count; ++s) {
        const cb_skin *skin = &m->skins[s];
        if (skin->joint_count == 0)
            return cb_fail(err, CB_ERR_INPUT, "%s: skin %u (%s) has no joints", m->source, s, skin->name);
        if (skin->joint_count > limits->max_joints)
            return cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_JOINTS, "%s: skin %u (%s) has %u joints, over the limit of %u",
                           m->source, s, skin->name, skin->joint_count, limits->max_joints);
        int32_t common_root = -1;
        for (uint32_t j = 0; j < skin->joint_count; ++j) {
            if (skin->joints[j] < 0 || skin->joints[j] >= (int32_t)m->node_count)
                return cb_fail(err, CB_ERR_INPUT, "%s: skin %u (%s) joint %u names node %d, which does not exist",
                               m->source, s, skin->name, j, skin->joints[j]);
            for (int k = 0; k < 16; ++k)
                if (!isfinite(skin->inverse_bind[j * 16 + k]))
                    return cb_fail(err, CB_ERR_INPUT, "%s: skin %u (%s) inverse bind matrix %u is NaN or infinite",
                                   m->source, s, skin->name, j);
            int32_t root = skin->joints[j];
            while (m->nodes[root].parent >= 0) root = m->nodes[root].parent;
            if (common_root >= 0 && root != common_root)
                return cb_fail(err, CB_ERR_INPUT,
                               "%s: skin %u (%s) joints have no common root: joint %u (%s) is in the tree rooted at node "
                               "%d (%s), joint 0 in the one rooted at node %d (%s); parent all joints to one armature",
                               m->source, s, skin->name, j, m->nodes[skin->joints[j]].name, root, m->nodes[root].name,
                               common_root, m->nodes[common_root].name);
            common_root = root;
        }
    }
    return CB_OK;
}

static cb_status validate_primitives(const cb_model *m, cb_error *err)
{
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        const cb_primitive *prim = &m->primitives[p];
        if (prim->skin < 0 || prim->skin >= (int32_t)m->skin_count)
            return cb_fail(err, CB_ERR_INPUT, "%s: skinned primitive %u uses skin %d, which does not exist",
                           m->source, p, prim->skin);
        uint32_t joint_count = m->skins[prim->skin].joint_count;
        for (uint64_t i = 0; i < (uint64_t)prim->vertex_count * 4; ++i) {
            if (prim->weights[i] != 0 && prim->joints[i] >= joint_count)
                return cb_fail(err, CB_ERR_INPUT,
                               "%s: vertex %llu of mesh node %d uses joint %u, but its skin has %u joints",
                               m->source, (unsigned long long)(i / 4), prim->node, prim->joints[i], joint_count);
            if (!isfinite(prim->weights[i]))
                return cb_fail(err, CB_ERR_INPUT, "%s: vertex %llu of mesh node %d has a NaN or infinite weight",
                               m->source, (unsigned long long)(i / 4), prim->node);
        }
        for (uint64_t i = 0; i < (uint64_t)prim->vertex_count * 3; ++i)
            if (!isfinite(prim->positions[i]))
                return cb_fail(err, CB_ERR_INPUT, "%s: vertex %llu of mesh node %d has a NaN or infinite position",
                               m->source, (unsigned long long)(i / 3), prim->node);
        for (uint32_t i = 0; i < prim->index_count; ++i)
            if (prim->indices[i] >= prim->vertex_count)
                return cb_fail(err, CB_ERR_INPUT, "%s: index %u of mesh node %d is %u, past its %u vertices",
                               m->source, i, prim->node, prim->indices[i], prim->vertex_count);
    }
    return CB_OK;
}

/* `checked`: key times an earlier channel of the clip passed (they are often shared). `good`:
 * the pre-scan found its keys clean (key_scan.c), so only node and count are checked. */
static cb_status validate_channel(const cb_model *m, uint32_t a, uint32_t c, const cb_channel *checked, bool good,
                                  cb_error *err)
{
    const cb_animation *anim = &m->animations[a];
    cb_channel *ch = &anim->channels[c];
    if (ch->node < 0 || ch->node >= (int32_t)m->node_count)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u targets node %d, which does not exist", m->source,
                       anim->name, c, ch->node);
    if (ch->key_count == 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u (%s of %s) has no keys", m->source, anim->name, c,
                       path_name(ch->path), m->nodes[ch->node].name);
    if (good) return CB_OK;
    bool times_checked = checked && cb_same_key_times(checked, ch);
    for (uint32_t k = 0; k < ch->key_count && !times_checked; ++k) {
        if (!isfinite(ch->times[k]))
            return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u key %u has a NaN or infinite time", m->source,
                           anim->name, c, k);
        if (k > 0 && !(ch->times[k] > ch->times[k - 1]))
            return cb_fail(err, CB_ERR_INPUT,
                           "%s: clip '%s' channel %u (%s of %s): key times are not increasing at key %u (%g after %g)",
                           m->source, anim->name, c, path_name(ch->path), m->nodes[ch->node].name, k,
                           (double)ch->times[k], (double)ch->times[k - 1]);
    }
    int comps = cb_path_components(ch->path);
    int per_key = comps * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
    uint64_t value_count = (uint64_t)ch->key_count * per_key;
    for (uint64_t i = cb_floats_finite(ch->values, value_count) ? value_count : 0; i < value_count; ++i)
        if (!isfinite(ch->values[i]))
            return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u (%s of %s) key %llu has a NaN or infinite value",
                           m->source, anim->name, c, path_name(ch->path), m->nodes[ch->node].name,
                           (unsigned long long)(i / per_key));
    if (ch->path == CB_PATH_ROTATION) {
        /* Real exporters write keys of length 0.9998; glTF wants unit quaternions. Keys that
         * are unit to float precision are left as they are (most are). The first key that is
         * not gives the channel a copy of its values in the model's arena, which is normalized:
         * the keys may lie in the loader's read-only mapping of the file, which is never
         * written (cb_model.release drops its pages, and reading them again gives the file's
         * bytes). Tangents of cubic splines are not rotations and stay too. */
        int value_slot = ch->interp == CB_INTERP_CUBICSPLINE ? 1 : 0;
        const float *keys = ch->values; /* as loaded; `own` is the copy, once made */
        float *own = NULL;
        for (const float *q = keys + value_slot * 4; q < keys + value_count; q += per_key) {
            double len2 = (double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3];
            if (fabs(len2 - 1) <= 0x1p-22) continue; /* float rounding of a unit quaternion */
            if (len2 < 1e-24)
                return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u (rotation of %s) key %u is a zero quaternion",
                               m->source, anim->name, c, m->nodes[ch->node].name, (uint32_t)((q - keys) / per_key));
            if (!own && !(own = cb_arena_alloc(m->arena, value_count, sizeof(float))))
                return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory", m->source);
            if (ch->values != own) ch->values = memcpy(own, keys, value_count * sizeof(float));
            double inv = 1 / sqrt(len2);
            for (int i = 0; i < 4; ++i) own[q - keys + i] = (float)(q[i] * inv);
        }
    }
    return CB_OK;
}

static cb_status validate_animation(cb_model *m, uint32_t a, const bool *good, cb_error *err)
{
    cb_animation *anim = &m->animations[a];
    if (anim->channel_count == 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' has no channels (remove it or give it keys)", m->source,
                       anim->name);
    anim->t0 = INFINITY;
    anim->t1 = -INFINITY;
    for (uint32_t c = 0; c < anim->channel_count; ++c) {
        if (validate_channel(m, a, c, c ? &anim->channels[c - 1] : NULL, good[c], err)) return err->status;
        const cb_channel *ch = &anim->channels[c];
        if (ch->times[0] < anim->t0) anim->t0 = ch->times[0];
        if (ch->times[ch->key_count - 1] > anim->t1) anim->t1 = ch->times[ch->key_count - 1];
    }
    return CB_OK;
}

/* Keeps the clips that pass; the others go to skipped_clips, in file order. good: the
 * pre-scan's flags, from first[a] on for clip a. */
static cb_status validate_clips(cb_model *m, const uint32_t *first, const bool *good, cb_error *err)
{
    m->skipped_clips = cb_model_alloc(m, m->animation_count, sizeof *m->skipped_clips);
    if (!m->skipped_clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint32_t kept = 0;
    cb_error first_error = {0};
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_error why = {0};
        if (!validate_animation(m, a, good + first[a], &why)) {
            m->animations[kept++] = m->animations[a];
            continue;
        }
        if (why.status != CB_ERR_INPUT) return *err = why, err->status;
        if (!first_error.status) first_error = why;
        struct cb_skipped_clip *skip = &m->skipped_clips[m->skipped_clip_count++];
        skip->name = m->animations[a].name;
        if (!(skip->reason = cb_model_strdup(m, why.message))) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    m->animation_count = kept;
    if (kept == 0) return *err = first_error, err->status;
    return CB_OK;
}

/* The pre-scan (cb_scan_channel_keys) over every clip, then each clip checked (validate_clips). */
static cb_status validate_animations(cb_model *m, cb_error *err)
{
    if (m->animation_count == 0) return CB_OK;
    uint64_t channels = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a) channels += m->animations[a].channel_count;
    uint32_t *first = malloc(m->animation_count * sizeof *first);
    bool *good = channels < UINT32_MAX ? malloc(channels ? channels : 1) : NULL;
    cb_status rc = first && good ? CB_OK : cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t a = 0, at = 0; !rc && a < m->animation_count; at += m->animations[a++].channel_count) first[a] = at;
    if (!rc) cb_scan_channel_keys(m, first, good);
    if (!rc) rc = validate_clips(m, first, good, err);
    free(first);
    free(good);
    return rc;
}

cb_status cb_model_validate(cb_model *model, const cb_limits *limits, cb_error *err)
{
    cb_limits defaults = cb_default_limits();
    if (!limits) limits = &defaults;
    if (validate_nodes(model, err)) return err->status;
    normalize_node_transforms(model);
    if (validate_skins(model, limits, err) || validate_primitives(model, err) ||
        validate_animations(model, err))
        return err->status;
    return CB_OK;
}
