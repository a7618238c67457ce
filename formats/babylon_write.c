/* babylon_write.c - see include/crowdbake/babylon.h. The conventions come from Babylon.js's
 * sources: VertexAnimationBaker (a row is Skeleton.getTransformMatrices: (bones + 1) x 16 floats),
 * Skeleton._computeTransformMatrices (joint matrices at their skin index, an identity after the
 * last bone), and @babylonjs/loaders' GLTFLoader._loadBones/_loadBone (which nodes become bones,
 * where the chain of each stops) and _loadNodeAsync (the skinned mesh parented to the skeleton
 * node's parent). */
#include "crowdbake/babylon.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/atomic_file.h"
#include "internal/json.h"

/* The node the loader's bone chains stop at: the skin's skeleton node when the file names one,
 * else the joints' nearest common ancestor (-1: none, every chain runs up to its scene root). */
static int32_t skeleton_node(const cb_model *m, const cb_skin *skin)
{
    if (skin->skeleton >= 0) return skin->skeleton;
    for (int32_t n = skin->joints[0]; n >= 0; n = m->nodes[n].parent) {
        bool shared = true;
        for (uint32_t j = 1; j < skin->joint_count && shared; ++j) {
            int32_t a = skin->joints[j];
            while (a >= 0 && a != n) a = m->nodes[a].parent;
            shared = a == n;
        }
        if (shared) return n;
    }
    return -1;
}

/* The top of joint j's bone chain: the skeleton node, or the scene root it climbs to. */
static int32_t chain_top(const cb_model *m, int32_t node, int32_t skeleton)
{
    while (node != skeleton && m->nodes[node].parent >= 0) node = m->nodes[node].parent;
    return node;
}

/* Marks every node that becomes a bone; returns their count. */
static uint32_t mark_bones(const cb_model *m, const cb_skin *skin, int32_t skeleton, bool *bone)
{
    uint32_t count = 0;
    for (uint32_t j = 0; j < skin->joint_count; ++j)
        for (int32_t n = skin->joints[j]; n >= 0 && !bone[n]; n = n == skeleton ? -1 : m->nodes[n].parent)
            bone[n] = true, ++count;
    return count;
}

uint32_t cb_babylon_bone_count(const cb_model *m, int32_t skin)
{
    bool *bone = calloc(m->node_count ? m->node_count : 1, sizeof *bone);
    if (!bone) return 0;
    const cb_skin *s = &m->skins[skin];
    uint32_t count = mark_bones(m, s, skeleton_node(m, s), bone);
    free(bone);
    return count;
}

static void mat4_mul(double out[16], const double a[16], const double b[16])
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double v = 0;
            for (int k = 0; k < 4; ++k) v += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = v;
        }
}

/* The inverse of an affine column-major matrix (last row 0 0 0 1). */
static void affine_inverse(const double m[16], double out[16])
{
    double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    double r[9] = {(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det,
                   (f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det,
                   (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det};
    memset(out, 0, 16 * sizeof *out);
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) out[col * 4 + row] = r[row * 3 + col];
        out[12 + row] = -(r[row * 3] * m[12] + r[row * 3 + 1] * m[13] + r[row * 3 + 2] * m[14]);
    }
    out[15] = 1;
}

/* The node's rest transform relative to the scene. */
static void rest_global(const cb_model *m, int32_t node, double out[16])
{
    double local[16], up[16];
    const cb_node *n = &m->nodes[node];
    if (n->has_matrix) memcpy(local, n->matrix, sizeof local);
    else {
        double x = n->rotation[0], y = n->rotation[1], z = n->rotation[2], w = n->rotation[3];
        double rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                         2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
        memset(local, 0, sizeof local);
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) local[c * 4 + r] = rot[c * 3 + r] * n->scale[c];
        for (int r = 0; r < 3; ++r) local[12 + r] = n->translation[r];
        local[15] = 1;
    }
    if (n->parent < 0) return (void)memcpy(out, local, sizeof local);
    rest_global(m, n->parent, up);
    mat4_mul(out, up, local);
}

/* Per joint, what takes a palette matrix (scene space) to Babylon's bone space: the inverse of
 * the rest transform of its chain's parent (identity for chains that climb to a scene root). */
static void joint_rebases(const cb_model *m, const cb_skin *skin, int32_t skeleton, double *out)
{
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        double *r = out + 16 * j, g[16];
        int32_t above = m->nodes[chain_top(m, skin->joints[j], skeleton)].parent;
        memset(r, 0, 16 * sizeof *r);
        r[0] = r[5] = r[10] = r[15] = 1;
        if (above >= 0) rest_global(m, above, g), affine_inverse(g, r);
    }
}

static const char BASE64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* Base64 of n bytes (n a multiple of 3 except at the end); returns the characters written. */
static size_t base64(const unsigned char *d, size_t n, char *out)
{
    size_t o = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) | (i + 2 < n ? d[i + 2] : 0);
        out[o++] = BASE64[v >> 18 & 63], out[o++] = BASE64[v >> 12 & 63];
        out[o++] = i + 1 < n ? BASE64[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? BASE64[v & 63] : '=';
    }
    return o;
}

/* A row of the file: the palette's row; a loop's closing row: the pose at the clip's end, either
 * sampled (pose: the joint matrices, scene space) or the first row moved by the root's travel. */
typedef struct babylon_row {
    uint32_t row;
    double travel[3];
    const double *pose;
} babylon_row;

/* One row as Babylon's little-endian Float32 values: joints, zeros for non-joint bones, identity. */
static void encode_row(const cb_palette *p, const babylon_row *r, const double *rebase, uint32_t bones,
                       unsigned char *out)
{
    memset(out, 0, (size_t)(bones + 1) * 64);
    for (uint32_t j = 0; j <= p->bone_count; ++j) {
        double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, scene[16];
        uint32_t slot = j < p->bone_count ? j : bones;
        if (j < p->bone_count) {
            if (r->pose) memcpy(scene, r->pose + 16 * j, sizeof scene);
            else cb_palette_decode(p, p->texels, r->row, j, scene);
            for (int k = 0; k < 3; ++k) scene[12 + k] += r->travel[k]; /* translated: travel x the last row (0 0 0 1) */
            mat4_mul(m, rebase + 16 * j, scene);
        }
        for (int k = 0; k < 16; ++k) {
            float f = (float)m[k];
            uint32_t u;
            memcpy(&u, &f, 4);
            for (int b = 0; b < 4; ++b) out[(size_t)slot * 64 + 4 * k + b] = (unsigned char)(u >> (8 * b));
        }
    }
}

/* Babylon plays rows from..to of a loop once, then from + 1..to over and over (its shader's
 * frameCorrection): its loops end on a closing row, the pose at the clip's end (what its own bake
 * of a range holds there). Root motion kept: sampled there (ends, poses: p->clip_count x joints
 * matrices); in place, the first pose moved by the root's vertical travel (in-place bakes take
 * off x and z, and a loop's last pose is its first). */
static babylon_row *babylon_rows(const cb_palette *p, const double *ends, uint32_t joints, uint32_t *count)
{
    uint32_t n = p->rows;
    for (uint32_t c = 0; c < p->clip_count; ++c) n += p->clips[c].loops;
    babylon_row *rows = calloc(n ? n : 1, sizeof *rows);
    for (uint32_t c = 0, k = 0; rows && c < p->clip_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        for (uint32_t f = 0; f < cl->frames; ++f) rows[k++].row = cl->first_row + f;
        if (!cl->loops) continue;
        rows[k].row = cl->first_row;
        rows[k].travel[1] = cl->root_velocity[1] * cl->duration;
        rows[k++].pose = ends ? ends + (size_t)c * joints * 16 : NULL;
    }
    *count = n;
    return rows;
}

/* Root motion kept: every loop's pose at its end, sampled as the bake samples (its period set); NULL
 * in place, or when out of memory (then, as in place, the first pose: never a wrong size). */
static double *loop_end_poses(const cb_palette *p, const cb_model *m, int32_t skin, bool in_place)
{
    cb_error e = {0};
    cb_sampler *s = in_place ? NULL : cb_sampler_create(m, skin, &e);
    double *ends = s ? calloc((size_t)p->clip_count * p->bone_count * 16 + 1, sizeof *ends) : NULL;
    for (uint32_t c = 0; ends && c < p->clip_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        int32_t a = cb_model_find_animation(m, cl->name);
        if (!cl->loops || a < 0) continue;
        cb_sampler_set_baked_loop(s, a, true, cl->start, cl->duration); /* out of memory: its end unclosed */
        cb_sample_joint_matrices(s, a, cl->start + cl->duration, ends + (size_t)c * p->bone_count * 16);
    }
    if (s) cb_sampler_free(s);
    return ends;
}

uint32_t cb_babylon_clip_rows(uint32_t frames, bool loops) { return frames + loops; }

/* Clip c's first row in the file (the clips before it, their closing rows included). */
static uint32_t clip_from(const cb_palette *p, uint32_t c)
{
    uint32_t from = 0;
    for (uint32_t k = 0; k < c; ++k) from += cb_babylon_clip_rows(p->clips[k].frames, p->clips[k].loops);
    return from;
}

/* The numbers BakedVertexAnimationManager plays clip c with: from, to (inclusive), fps. */
static void json_play(cb_json *j, const cb_palette *p, uint32_t c)
{
    uint32_t from = clip_from(p, c);
    cb_json_int(j, "from", from);
    cb_json_int(j, "to", from + cb_babylon_clip_rows(p->clips[c].frames, p->clips[c].loops) - 1);
    cb_json_number(j, "fps", p->clips[c].fps);
}

/* A catalog's states, by name: what a scene plays for each (its clip's numbers). */
static void json_states(cb_json *j, const cb_palette *p, const cb_babylon_write_options *o)
{
    cb_json_object(j, "states");
    for (uint32_t s = 0; s < o->state_count; ++s) {
        cb_json_object(j, o->states[s].name);
        cb_json_string(j, "clip", p->clips[o->states[s].clip].name);
        json_play(j, p, o->states[s].clip);
        cb_json_end(j);
    }
    cb_json_end(j);
}

/* A clip's per-row travel offsets (.pal version 5), one per row of the file's range (a loop's
 * closing row is its first again), and the heading they lie along: the scene adds
 * travel[row] x heading to an instance moving at the clip's ground speed (docs/babylon.md). */
static void json_travel(cb_json *j, const cb_palette *p, uint32_t c)
{
    const cb_palette_clip *cl = &p->clips[c];
    if (!p->row_travel || !cl->travel.applied) return;
    cb_json_inline_array(j, "travel_heading");
    for (int k = 0; k < 3; ++k) cb_json_number(j, NULL, cl->travel.heading[k]);
    cb_json_end(j);
    cb_json_inline_array(j, "travel");
    for (uint32_t r = 0; r < cb_babylon_clip_rows(cl->frames, cl->loops); ++r)
        cb_json_number(j, NULL, p->row_travel[cl->first_row + r % cl->frames]);
    cb_json_end(j);
}

/* What follows vertexData: the texture's size and the clip table (rows, rates, loops). */
static char *tail_json(const cb_palette *p, uint32_t bones, uint32_t height, const cb_babylon_write_options *o)
{
    char *text = NULL, hash[17];
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) return NULL;
    fprintf(f, "\",\n\"width\": %u,\n\"height\": %u,\n\"crowdbake\": ", (bones + 1) * 4, height);
    cb_json j;
    cb_json_init(&j, f);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "writer", "crowdbake " CROWDBAKE_VERSION);
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)o->input_hash); /* 64 bits: past a double's */
    cb_json_string(&j, "input_hash", hash);
    cb_json_int(&j, "joints", p->bone_count);
    cb_json_int(&j, "bones", bones);
    cb_json_number(&j, "fps", p->fps);
    cb_json_number(&j, "speed_reference", o->speed_reference);
    cb_json_array(&j, "clips");
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        cb_json_object(&j, NULL);
        cb_json_string(&j, "name", cl->name);
        json_play(&j, p, c); /* a loop's closing row included */
        cb_json_number(&j, "start", cl->start);
        cb_json_bool(&j, "loops", cl->loops);
        json_travel(&j, p, c);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    if (o->states) json_states(&j, p, o);
    cb_json_end(&j);
    fputs("}\n", f);
    return fclose(f) == 0 ? text : (free(text), NULL);
}

static cb_status write_rows(cb_atomic_file *f, const cb_palette *p, const babylon_row *rows, uint32_t count,
                            const double *rebase, uint32_t bones, cb_error *err)
{
    size_t row_bytes = (size_t)(bones + 1) * 64; /* three rows at a time: whole base64 quads until the last */
    unsigned char *raw = malloc(row_bytes * 3);
    char *text = malloc(row_bytes * 4 + 4);
    cb_status rc = raw && text ? CB_OK : cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t r = 0; !rc && r < count; r += 3) {
        uint32_t n = count - r < 3 ? count - r : 3;
        for (uint32_t k = 0; k < n; ++k) encode_row(p, &rows[r + k], rebase, bones, raw + k * row_bytes);
        rc = cb_atomic_write(f, text, base64(raw, n * row_bytes, text), err);
    }
    free(raw), free(text);
    return rc;
}

cb_status cb_babylon_write(const char *path, const cb_palette *p, const cb_model *m, int32_t skin,
                           const cb_babylon_write_options *o, cb_error *err)
{
    if (cb_palette_timed_clip(p))
        return cb_fail(err, CB_ERR_INPUT, "%s: clip %s has timed rows, and timed rows need a .pal (Babylon has no place "
                       "for their map): write a .pal, or bake it at a fixed --fps", path, cb_palette_timed_clip(p)->name);
    const cb_skin *s = &m->skins[skin];
    int32_t skeleton = skeleton_node(m, s);
    bool *bone = calloc(m->node_count ? m->node_count : 1, sizeof *bone);
    double *rebase = malloc((size_t)s->joint_count * 16 * sizeof *rebase);
    uint32_t count;
    double *ends = loop_end_poses(p, m, skin, o->in_place);
    babylon_row *rows = babylon_rows(p, ends, p->bone_count, &count);
    char *tail = NULL;
    if (!bone || !rebase || !rows) {
        free(bone), free(rebase), free(rows);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    uint32_t bones = mark_bones(m, s, skeleton, bone);
    joint_rebases(m, s, skeleton, rebase);
    static const char head[] = "{\"vertexData\": \"";
    cb_atomic_file f;
    cb_status rc = cb_atomic_open(&f, path, err);
    if (!rc && !(tail = tail_json(p, bones, count, o))) rc = cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    if (!rc) rc = cb_atomic_write(&f, head, sizeof head - 1, err);
    if (!rc) rc = write_rows(&f, p, rows, count, rebase, bones, err);
    if (!rc) rc = cb_atomic_write(&f, tail, strlen(tail), err);
    if (rc) cb_atomic_abort(&f);
    else rc = cb_atomic_commit(&f, err);
    free(bone), free(rebase), free(rows), free(ends), free(tail);
    return rc;
}
