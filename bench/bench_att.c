/* bench_att.c - crowdbake's qpos palettes against the encoding of Unreal's AnimToTexture plugin in
 * its bone mode, on its own ground: the same model, the same frames (every clip at the palette's
 * rows), the same skinning weights, the same ground truth (the glTF's own skinning, exact).
 *
 * AnimToTexture's bone mode, written from its documented rules (Epic's API reference and the
 * plugin's parameters: per frame and bone a position texel and a rotation texel; positions
 * normalized into one bounding box, BoneMinBBox + BoneSizeBBox; rotations as axis and angle; 8 or
 * 16 bits a channel; frame 0 the reference pose; linear blend skinning from the rotation and
 * position relative to that reference). Its source was not available here, so this is a model of
 * the encoding, not its code: each channel is an unsigned normalized integer (RGBA8 or RGBA16),
 * the axis stored as (n + 1) / 2 and the angle (0..pi, the shorter way) as angle / pi, and the
 * decoded axis renormalized - the choices that favour it where its documentation is silent. The
 * mesh's weights are exact on both sides (AnimToTexture keeps them in a texture too; what is
 * compared here is the animation). No scale is stored: a bone's animated scale is its error.
 *
 *   bench_att MODEL [FPS]     one JSON line per encoding: bytes, worst and mean error in mm per
 *                             metre of the model's height, over every vertex of every row */
#include "bench_model.h"

#define PI 3.14159265358979323846

typedef struct frame_ref {
    int32_t animation;
    double time;  /* clip time of the row */
    uint32_t row; /* the palette row */
} frame_ref;

/* Every row of the palette with the clip time it was sampled at (root motion kept: the glTF's own poses). */
static frame_ref *palette_frames(cb_sampler *s, const cb_palette *p, double fps, uint32_t *count)
{
    uint32_t n = 0, rows = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) rows += p->clips[c].frames;
    frame_ref *f = calloc(rows ? rows : 1, sizeof *f);
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        cb_clip_info info;
        cb_error err = {0};
        if (cb_clip_analyze(s, (int32_t)c, fps, p->clips[c].loops, NULL, &info, &err) != CB_OK) {
            fprintf(stderr, "bench_att: clip %u: %s\n", c, err.message);
            exit(1);
        }
        for (uint32_t k = 0; k < p->clips[c].frames; ++k)
            f[n++] = (frame_ref){(int32_t)c, cb_clip_frame_time(&info, k), p->clips[c].first_row + k};
    }
    *count = n;
    return f;
}

/* ---- AnimToTexture's bone mode, as modelled above ---- */

static double quantize(double x, int bits)
{
    double top = (double)((1u << bits) - 1);
    x = x < 0 ? 0 : x > 1 ? 1 : x;
    return round(x * top) / top;
}

/* A column-major 4x4's rotation (its 3x3 with unit columns) as a unit quaternion (x, y, z, w), w >= 0. */
static void rotation_of(const double *g, double q[4])
{
    double columns[3];
    bench_quat_of(g, q, columns);
    double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) * (q[3] < 0 ? -1 : 1);
    for (int k = 0; k < 4; ++k) q[k] /= len;
}

/* A rotation through its axis-angle texel and back: the rotation matrix a shader decodes (row-major 3x3). */
static void axis_angle_texel(const double q[4], int bits, double m[9])
{
    double s = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]), angle = 2 * atan2(s, q[3]);
    double axis[3] = {1, 0, 0};
    if (s > 0) axis[0] = q[0] / s, axis[1] = q[1] / s, axis[2] = q[2] / s;
    double n[3], len = 0;
    for (int k = 0; k < 3; ++k) n[k] = quantize((axis[k] + 1) / 2, bits) * 2 - 1, len += n[k] * n[k];
    len = sqrt(len);
    for (int k = 0; k < 3; ++k) n[k] = len > 0 ? n[k] / len : 0;
    angle = quantize(angle / PI, bits) * PI;
    double c = cos(angle), si = sin(angle), t = 1 - c, x = n[0], y = n[1], z = n[2];
    double r[9] = {t * x * x + c, t * x * y - si * z, t * x * z + si * y, t * x * y + si * z, t * y * y + c,
                   t * y * z - si * x, t * x * z - si * y, t * y * z + si * x, t * z * z + c};
    memcpy(m, r, sizeof r);
}

/* G = J * inverse(IBM): the bone's own transform, from the joint matrix and the bind (IBM^-1). */
static void mul4(const double *a, const double *b, double *out)
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double v = 0;
            for (int k = 0; k < 4; ++k) v += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = v;
        }
}

static void invert_affine(const double *m, double *out)
{
    /* General 3x3 inverse (the bind may scale), then the translation. */
    double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g, det = a * A + b * B + c * C;
    double inv[9] = {A / det, -(b * i - c * h) / det, (b * f - c * e) / det, B / det, (a * i - c * g) / det,
                     -(a * f - c * d) / det, C / det, -(a * h - b * g) / det, (a * e - b * d) / det}; /* row-major */
    memset(out, 0, 16 * sizeof(double));
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) out[k * 4 + r] = inv[r * 3 + k];
    for (int r = 0; r < 3; ++r) out[12 + r] = -(inv[r * 3] * m[12] + inv[r * 3 + 1] * m[13] + inv[r * 3 + 2] * m[14]);
    out[15] = 1;
}

/* The skeleton's parent node (the armature: the parent of the joint whose parent is no joint) in
 * the scene at a time, identity when the skeleton is a root. Unreal imports the skeleton under the
 * component, so the bones' transforms are relative to it: their bind is the inverse bind matrix. */
static void armature(cb_sampler *s, const cb_model *m, const cb_skin *skin, int32_t animation, double t, double out[16])
{
    int32_t parent = -1;
    for (uint32_t j = 0; j < skin->joint_count && parent < 0; ++j) {
        int32_t p = m->nodes[skin->joints[j]].parent;
        bool is_joint = false;
        for (uint32_t k = 0; k < skin->joint_count && p >= 0; ++k) is_joint |= skin->joints[k] == p;
        if (!is_joint && p >= 0) parent = p;
    }
    static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    memcpy(out, parent >= 0 ? cb_sample_globals(s, animation, t) + (size_t)parent * 16 : identity, 16 * sizeof(double));
}

/* A bone's transform relative to the armature at a frame: A^-1 J IBM^-1. */
static void bone_transform(const double *a_inverse, const double *joint, const double *inverse_bind, double out[16])
{
    double bind[16], g[16];
    invert_affine(inverse_bind, bind);
    mul4(joint, bind, g);
    mul4(a_inverse, g, out);
}

/* The bone matrices AnimToTexture's shader rebuilds at a frame: R = dec(rot) dec(rot0)^T and
 * v -> R (v - dec(p0)) + dec(p), from the frame's texels and frame 0's (the reference pose: the
 * bind, IBM^-1), then placed by the armature a, as the component places the mesh. */
static void att_matrices(const cb_skin *skin, const double *joint, const double *a, const double *bbox, int bits, double *out)
{
    double a_inverse[16];
    invert_affine(a, a_inverse);
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        double ref[16], g[16], q[4], q0[4], r[9], r0[9], p[3], p0[3], o[16];
        invert_affine(skin->inverse_bind + j * 16, ref);
        bone_transform(a_inverse, joint + j * 16, skin->inverse_bind + j * 16, g);
        rotation_of(g, q), rotation_of(ref, q0);
        axis_angle_texel(q, bits, r), axis_angle_texel(q0, bits, r0);
        for (int k = 0; k < 3; ++k) {
            p[k] = bbox[k] + quantize((g[12 + k] - bbox[k]) / bbox[3 + k], bits) * bbox[3 + k];
            p0[k] = bbox[k] + quantize((ref[12 + k] - bbox[k]) / bbox[3 + k], bits) * bbox[3 + k];
        }
        memset(o, 0, sizeof o);
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col) { /* (R R0^T)[row][col] */
                double v = 0;
                for (int k = 0; k < 3; ++k) v += r[row * 3 + k] * r0[col * 3 + k];
                o[col * 4 + row] = v;
            }
        for (int row = 0; row < 3; ++row)
            o[12 + row] = p[row] - (o[row] * p0[0] + o[4 + row] * p0[1] + o[8 + row] * p0[2]);
        o[15] = 1;
        mul4(a, o, out + j * 16);
    }
}

/* BoneMinBBox and BoneSizeBBox: the box of every bone position at every frame and in the reference. */
static void att_bbox(cb_sampler *s, const cb_model *m, const cb_skin *skin, const frame_ref *f, uint32_t n, double *joint,
                     double bbox[6])
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i <= n; ++i) {
        double a[16], a_inverse[16];
        if (i < n) {
            cb_sample_joint_matrices(s, f[i].animation, f[i].time, joint);
            armature(s, m, skin, f[i].animation, f[i].time, a);
            invert_affine(a, a_inverse);
        }
        for (uint32_t j = 0; j < skin->joint_count; ++j) {
            double g[16];
            if (i < n) bone_transform(a_inverse, joint + j * 16, skin->inverse_bind + j * 16, g);
            else invert_affine(skin->inverse_bind + j * 16, g);
            for (int k = 0; k < 3; ++k) lo[k] = fmin(lo[k], g[12 + k]), hi[k] = fmax(hi[k], g[12 + k]);
        }
    }
    for (int k = 0; k < 3; ++k) bbox[k] = lo[k], bbox[3 + k] = fmax(hi[k] - lo[k], 1e-9);
}

static void report(const char *model, const char *encoding, size_t bytes, const bench_errors *e, double height, uint32_t rows,
                   uint32_t bones)
{
    printf("{\"model\": \"%s\", \"encoding\": \"%s\", \"bytes\": %zu, \"worst_mm_per_m\": %.4f, \"mean_mm_per_m\": %.4f, "
           "\"rows\": %u, \"bones\": %u}\n",
           model, encoding, bytes, e->worst / height * 1000, e->sum / (double)e->count / height * 1000, rows, bones);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_att MODEL.glb [FPS]\n");
        return 2;
    }
    double fps = argc > 2 ? atof(argv[2]) : 30;
    bench_model model = bench_load("bench_att", argv[1]);
    cb_model *m = model.m;
    cb_sampler *s = model.s;
    const cb_skin *skin = &m->skins[cb_sampler_skin(s)];
    size_t mat_bytes = skin->joint_count * 16 * sizeof(double), vertex_bytes = model.vertices * 3 * sizeof(double) + 1;
    double *joint = malloc(mat_bytes), *decoded = malloc(mat_bytes), bbox[6];
    double *skinned = malloc(vertex_bytes), *exact = malloc(vertex_bytes);
    cb_palette pal[2];
    const cb_precision precisions[2] = {CB_PRECISION_U16, CB_PRECISION_HALF};
    for (int k = 0; k < 2; ++k) bench_bake_qpos("bench_att", s, precisions[k], fps, &pal[k]);
    uint32_t n;
    frame_ref *f = palette_frames(s, &pal[0], fps, &n);
    double height = pal[0].model_height;
    bench_errors e[4] = {{0}};
    att_bbox(s, m, skin, f, n, joint, bbox);
    for (uint32_t i = 0; i < n; ++i) {
        cb_sample_joint_matrices(s, f[i].animation, f[i].time, joint);
        for (int k = 0; k < 2; ++k) { /* crowdbake: the row as the runtime decodes it */
            cb_instance at_row = {f[i].row, 1, 0, 0};
            cb_runtime_matrices(&pal[k], pal[k].texels, &at_row, 0, decoded);
            bench_skin_errors(m, cb_sampler_skin(s), decoded, joint, skinned, exact, &e[k]);
        }
        double a[16];
        armature(s, m, skin, f[i].animation, f[i].time, a);
        for (int k = 0; k < 2; ++k) {
            att_matrices(skin, joint, a, bbox, k ? 16 : 8, decoded);
            bench_skin_errors(m, cb_sampler_skin(s), decoded, joint, skinned, exact, &e[2 + k]);
        }
    }
    uint32_t bones = skin->joint_count;
    for (int k = 0; k < 2; ++k) /* the palette and its bind-position texture (bones x 2 RGBA32F) */
        report(model.name, k ? "crowdbake qpos/half" : "crowdbake qpos/u16", pal[k].texel_bytes + (size_t)bones * 2 * 16, &e[k],
               height, n, bones);
    for (int k = 0; k < 2; ++k) /* position + rotation texel per bone and frame, frame 0 the reference pose */
        report(model.name, k ? "AnimToTexture bone 16-bit" : "AnimToTexture bone 8-bit", (size_t)(n + 1) * bones * 2 * (k ? 8 : 4),
               &e[2 + k], height, n, bones);
    for (int k = 0; k < 2; ++k) cb_palette_free(&pal[k]);
    free(f), free(joint), free(decoded), free(skinned), free(exact);
    bench_free(&model);
    return 0;
}
