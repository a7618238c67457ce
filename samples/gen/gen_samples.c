/* gen_samples.c - writes crowdbake's own rigged, animated sample animals as GLB files:
 *
 *   quadruped.glb  41 joints; idle, walk, run (a diagonal-pair gait with root travel), eat, death
 *   fish.glb       13 joints; swim (a travelling wave along the spine)
 *   bird.glb       19 joints; flap, glide
 *   quadruped_lod1.glb  the quadruped without ears, jaw, toes and tail tip (a LOD of its rig)
 *
 * Meters, +Y up, facing +Z. Every bone is a box skinned to its joint, its far end blended
 * with the child joint so bends look smooth. Standalone C11: no crowdbake code, no libraries.
 *
 * usage: gen_samples OUT_DIR
 */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "animals.h"

/* ---- math --------------------------------------------------------------------------------- */

static void euler_to_quat(const double e[3], double q[4])
{
    /* X then Y then Z (intrinsic): q = qz * qy * qx */
    double cx = cos(e[0] / 2), sx = sin(e[0] / 2), cy = cos(e[1] / 2), sy = sin(e[1] / 2), cz = cos(e[2] / 2),
           sz = sin(e[2] / 2);
    q[0] = sx * cy * cz - cx * sy * sz;
    q[1] = cx * sy * cz + sx * cy * sz;
    q[2] = cx * cy * sz - sx * sy * cz;
    q[3] = cx * cy * cz + sx * sy * sz;
}

static void global_rest(const animal *a, int j, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (int k = j; k >= 0; k = a->joints[k].parent)
        for (int i = 0; i < 3; ++i) out[i] += a->joints[k].pos[i];
}

/* ---- output buffer ------------------------------------------------------------------------ */

typedef struct bytes {
    unsigned char *data;
    size_t size, cap;
} bytes;

static size_t put(bytes *b, const void *p, size_t n)
{
    if (b->size + n + 8 > b->cap) {
        b->cap = (b->size + n + 8) * 2;
        b->data = realloc(b->data, b->cap);
        if (!b->data) exit(1);
    }
    while (b->size % 4) b->data[b->size++] = 0; /* every view starts 4-aligned */
    size_t at = b->size;
    memcpy(b->data + at, p, n);
    b->size += n;
    return at;
}

typedef struct text {
    char *s;
    size_t len, cap;
} text;

static void tprintf(text *t, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int n = vsnprintf(t->s ? t->s + t->len : NULL, t->s ? t->cap - t->len : 0, fmt, ap);
        va_end(ap);
        if (t->s && t->len + (size_t)n < t->cap) {
            t->len += (size_t)n;
            return;
        }
        t->cap = (t->cap + (size_t)n + 1) * 2;
        t->s = realloc(t->s, t->cap);
        if (!t->s) exit(1);
    }
}

typedef struct gltf {
    bytes bin;
    text views, accessors;
    int view_count, accessor_count;
} gltf;

/* Adds a bufferView and an accessor over `data`; returns the accessor index. */
static int accessor(gltf *g, const void *data, size_t bytes_len, int component, int count, const char *type,
                    const float *min, const float *max, int comps, int target)
{
    size_t at = put(&g->bin, data, bytes_len);
    tprintf(&g->views, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu%s}", g->view_count ? "," : "", at,
            bytes_len, target == 1 ? ",\"target\":34962" : target == 2 ? ",\"target\":34963" : "");
    tprintf(&g->accessors, "%s{\"bufferView\":%d,\"componentType\":%d,\"count\":%d,\"type\":\"%s\"",
            g->accessor_count ? "," : "", g->view_count, component, count, type);
    if (min && max) {
        tprintf(&g->accessors, ",\"min\":[");
        for (int i = 0; i < comps; ++i) tprintf(&g->accessors, "%s%.9g", i ? "," : "", (double)min[i]);
        tprintf(&g->accessors, "],\"max\":[");
        for (int i = 0; i < comps; ++i) tprintf(&g->accessors, "%s%.9g", i ? "," : "", (double)max[i]);
        tprintf(&g->accessors, "]");
    }
    tprintf(&g->accessors, "}");
    g->view_count++;
    return g->accessor_count++;
}

/* ---- mesh: a box per bone ----------------------------------------------------------------- */

typedef struct mesh {
    float *pos, *nrm, *wgt;
    uint16_t *jnt; /* written as bytes while every joint index fits one (the samples) */
    uint16_t *idx;
    int vcount, icount;
} mesh;

static void basis(const double d[3], double u[3], double v[3])
{
    double a[3] = {0, 1, 0};
    if (fabs(d[1]) > 0.9) a[0] = 1, a[1] = 0;
    u[0] = d[1] * a[2] - d[2] * a[1], u[1] = d[2] * a[0] - d[0] * a[2], u[2] = d[0] * a[1] - d[1] * a[0];
    double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; ++i) u[i] /= l;
    v[0] = d[1] * u[2] - d[2] * u[1], v[1] = d[2] * u[0] - d[0] * u[2], v[2] = d[0] * u[1] - d[1] * u[0];
}

/* A box around the bone from `from` to `to`: 6 flat faces, 4 vertices each. Corners at the
 * `to` end blend half-and-half with joint j1 (the child) when there is one. */
static void add_box(mesh *m, const double from[3], const double to[3], double width, int j0, int j1)
{
    double d[3] = {to[0] - from[0], to[1] - from[1], to[2] - from[2]};
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; ++i) d[i] /= len;
    double u[3], v[3], h = width / 2;
    basis(d, u, v);
    double corner[8][3];
    for (int c = 0; c < 8; ++c) {
        double su = c & 1 ? h : -h, sv = c & 2 ? h : -h, sd = c & 4 ? len : 0;
        for (int i = 0; i < 3; ++i) corner[c][i] = from[i] + su * u[i] + sv * v[i] + sd * d[i];
    }
    /* Faces as corner quads, counter-clockwise seen from outside (u x v = d). */
    static const int faces[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
    for (int f = 0; f < 6; ++f) {
        const double *p0 = corner[faces[f][0]], *p1 = corner[faces[f][1]], *p2 = corner[faces[f][2]];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        int base = m->vcount;
        for (int k = 0; k < 4; ++k) {
            int c = faces[f][k];
            float *P = m->pos + 3 * m->vcount, *N = m->nrm + 3 * m->vcount, *W = m->wgt + 4 * m->vcount;
            uint16_t *J = m->jnt + 4 * m->vcount;
            for (int i = 0; i < 3; ++i) P[i] = (float)corner[c][i], N[i] = (float)(n[i] / nl);
            int blend = (c & 4) && j1 >= 0;
            J[0] = (uint16_t)j0, J[1] = (uint16_t)(blend ? j1 : 0), J[2] = J[3] = 0;
            W[0] = blend ? 0.5f : 1.0f, W[1] = blend ? 0.5f : 0.0f, W[2] = W[3] = 0;
            m->vcount++;
        }
        static const uint16_t tri[6] = {0, 1, 2, 0, 2, 3};
        for (int i = 0; i < 6; ++i) m->idx[m->icount++] = (uint16_t)(base + tri[i]);
    }
}

static void build_mesh(const animal *a, mesh *m)
{
    int boxes = a->joint_count;
    boxes *= 2; /* a bone box plus, for leaves, a cap */
    m->pos = calloc((size_t)boxes * 24 * 3, sizeof(float));
    m->nrm = calloc((size_t)boxes * 24 * 3, sizeof(float));
    m->wgt = calloc((size_t)boxes * 24 * 4, sizeof(float));
    m->jnt = calloc((size_t)boxes * 24 * 4, sizeof(uint16_t));
    m->idx = calloc((size_t)boxes * 36, sizeof(uint16_t));
    if (!m->pos || !m->nrm || !m->wgt || !m->jnt || !m->idx) exit(1);
    for (int j = 1; j < a->joint_count; ++j) {
        int p = a->joints[j].parent;
        if (a->joints[p].role == R_ROOT) continue; /* the root is a ground marker: no bone */
        double from[3], to[3];
        global_rest(a, p, from);
        global_rest(a, j, to);
        int has_child = 0;
        for (int k = 0; k < a->joint_count; ++k) has_child |= a->joints[k].parent == j;
        add_box(m, from, to, a->joints[j].width, p, has_child ? j : -1);
        if (!has_child) { /* a small cap at the leaf so every joint drives something */
            double tip[3] = {to[0], to[1] + 0.001, to[2] + 0.02};
            add_box(m, to, tip, a->joints[j].width * 0.8, j, -1);
        }
    }
}

/* ---- GLB ---------------------------------------------------------------------------------- */

static void write_animal(const animal *a, const char *dir)
{
    gltf g = {0};
    mesh m = {0};
    build_mesh(a, &m);
    float pmin[3] = {1e9f, 1e9f, 1e9f}, pmax[3] = {-1e9f, -1e9f, -1e9f};
    for (int i = 0; i < m.vcount; ++i)
        for (int k = 0; k < 3; ++k) pmin[k] = fminf(pmin[k], m.pos[3 * i + k]), pmax[k] = fmaxf(pmax[k], m.pos[3 * i + k]);
    int a_pos = accessor(&g, m.pos, (size_t)m.vcount * 12, 5126, m.vcount, "VEC3", pmin, pmax, 3, 1);
    int a_nrm = accessor(&g, m.nrm, (size_t)m.vcount * 12, 5126, m.vcount, "VEC3", NULL, NULL, 3, 1);
    /* JOINTS_0 as unsigned bytes up to 256 joints (the samples), unsigned shorts beyond (bench rigs of 800) */
    bool wide = a->joint_count > 256;
    uint8_t *jnt8 = malloc((size_t)m.vcount * 4 + 1);
    if (!jnt8) exit(1);
    for (int i = 0; i < m.vcount * 4; ++i) jnt8[i] = (uint8_t)m.jnt[i];
    int a_jnt = wide ? accessor(&g, m.jnt, (size_t)m.vcount * 8, 5123, m.vcount, "VEC4", NULL, NULL, 4, 1)
                     : accessor(&g, jnt8, (size_t)m.vcount * 4, 5121, m.vcount, "VEC4", NULL, NULL, 4, 1);
    free(jnt8);
    int a_wgt = accessor(&g, m.wgt, (size_t)m.vcount * 16, 5126, m.vcount, "VEC4", NULL, NULL, 4, 1);
    int a_idx = accessor(&g, m.idx, (size_t)m.icount * 2, 5123, m.icount, "SCALAR", NULL, NULL, 1, 2);
    float *ibm = calloc((size_t)a->joint_count * 16, sizeof(float));
    for (int j = 0; j < a->joint_count; ++j) {
        double p[3];
        global_rest(a, j, p);
        float *M = ibm + 16 * j;
        M[0] = M[5] = M[10] = M[15] = 1;
        M[12] = (float)-p[0], M[13] = (float)-p[1], M[14] = (float)-p[2];
    }
    int a_ibm = accessor(&g, ibm, (size_t)a->joint_count * 64, 5126, a->joint_count, "MAT4", NULL, NULL, 16, 0);

    text anims = {0};
    for (int c = 0; c < a->clip_count; ++c) {
        const clip *cl = &a->clips[c];
        int keys = (int)ceil(cl->duration * KEY_RATE) + 1;
        float *times = malloc(sizeof(float) * keys);
        for (int k = 0; k < keys; ++k) times[k] = (float)(cl->duration * k / (keys - 1));
        float tmin = 0, tmax = (float)cl->duration;
        int a_time = accessor(&g, times, sizeof(float) * keys, 5126, keys, "SCALAR", &tmin, &tmax, 1, 0);
        text samplers = {0}, channels = {0};
        int n = 0;
        for (int j = 0; j < a->joint_count; ++j) {
            float *rot = malloc(sizeof(float) * 4 * keys), *tra = malloc(sizeof(float) * 3 * keys);
            int rot_moves = 0, tra_moves = 0;
            for (int k = 0; k < keys; ++k) {
                double e[3], tr[3], q[4];
                a->pose(a, c, j, times[k], e, tr);
                euler_to_quat(e, q);
                for (int i = 0; i < 4; ++i) rot[4 * k + i] = (float)q[i];
                for (int i = 0; i < 3; ++i) tra[3 * k + i] = (float)tr[i];
                rot_moves |= fabs(q[3]) < 1 - 1e-9;
                for (int i = 0; i < 3; ++i) tra_moves |= fabs(tr[i] - a->joints[j].pos[i]) > 1e-9;
            }
            if (rot_moves) {
                int acc = accessor(&g, rot, sizeof(float) * 4 * keys, 5126, keys, "VEC4", NULL, NULL, 4, 0);
                tprintf(&samplers, "%s{\"input\":%d,\"output\":%d,\"interpolation\":\"LINEAR\"}", n ? "," : "", a_time, acc);
                tprintf(&channels, "%s{\"sampler\":%d,\"target\":{\"node\":%d,\"path\":\"rotation\"}}", n ? "," : "", n, j + 1);
                n++;
            }
            if (tra_moves) {
                int acc = accessor(&g, tra, sizeof(float) * 3 * keys, 5126, keys, "VEC3", NULL, NULL, 3, 0);
                tprintf(&samplers, "%s{\"input\":%d,\"output\":%d,\"interpolation\":\"LINEAR\"}", n ? "," : "", a_time, acc);
                tprintf(&channels, "%s{\"sampler\":%d,\"target\":{\"node\":%d,\"path\":\"translation\"}}", n ? "," : "", n, j + 1);
                n++;
            }
            free(rot);
            free(tra);
        }
        tprintf(&anims, "%s{\"name\":\"%s\",\"samplers\":[%s],\"channels\":[%s]}", c ? "," : "", cl->name, samplers.s,
                channels.s);
        free(samplers.s);
        free(channels.s);
        free(times);
    }

    /* Node 0 is the mesh; joint j is node j + 1. */
    text nodes = {0};
    tprintf(&nodes, "{\"name\":\"%s_mesh\",\"mesh\":0,\"skin\":0}", a->name);
    for (int j = 0; j < a->joint_count; ++j) {
        const joint *jt = &a->joints[j];
        tprintf(&nodes, ",{\"name\":\"%s\",\"translation\":[%.9g,%.9g,%.9g]", jt->name, jt->pos[0], jt->pos[1], jt->pos[2]);
        int first = 1;
        for (int k = 0; k < a->joint_count; ++k)
            if (a->joints[k].parent == j) {
                tprintf(&nodes, "%s%d", first ? ",\"children\":[" : ",", k + 1);
                first = 0;
            }
        tprintf(&nodes, "%s}", first ? "" : "]");
    }
    text joints = {0};
    for (int j = 0; j < a->joint_count; ++j) tprintf(&joints, "%s%d", j ? "," : "", j + 1);

    text json = {0};
    tprintf(&json,
            "{\"asset\":{\"version\":\"2.0\",\"generator\":\"crowdbake samples/gen\"},\"scene\":0,"
            "\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[%s],"
            "\"meshes\":[{\"name\":\"%s\",\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d,"
            "\"JOINTS_0\":%d,\"WEIGHTS_0\":%d},\"indices\":%d}]}],"
            "\"skins\":[{\"name\":\"%s_rig\",\"inverseBindMatrices\":%d,\"skeleton\":1,\"joints\":[%s]}],"
            "\"animations\":[%s],\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":[%s],\"accessors\":[%s]}",
            nodes.s, a->name, a_pos, a_nrm, a_jnt, a_wgt, a_idx, a->name, a_ibm, joints.s, anims.s,
            (g.bin.size + 3) / 4 * 4, g.views.s, g.accessors.s);
    while (json.len % 4) tprintf(&json, " ");
    while (g.bin.size % 4) g.bin.data[g.bin.size++] = 0;

    char path[1024], tmp[1100];
    snprintf(path, sizeof path, "%s/%s.glb", dir, a->name);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        perror(tmp);
        exit(5);
    }
    uint32_t header[5] = {0x46546C67u, 2, (uint32_t)(12 + 8 + json.len + 8 + g.bin.size), (uint32_t)json.len, 0x4E4F534Au};
    uint32_t bin_header[2] = {(uint32_t)g.bin.size, 0x004E4942u};
    int ok = fwrite(header, 4, 5, f) == 5 && fwrite(json.s, 1, json.len, f) == json.len &&
             fwrite(bin_header, 4, 2, f) == 2 && fwrite(g.bin.data, 1, g.bin.size, f) == g.bin.size;
    if (fclose(f) != 0 || !ok || rename(tmp, path) != 0) {
        perror(path);
        exit(5);
    }
    printf("wrote %s: %d joints, %d vertices, %d clips\n", path, a->joint_count, m.vcount, a->clip_count);
    free(m.pos), free(m.nrm), free(m.wgt), free(m.jnt), free(m.idx), free(ibm);
    free(g.bin.data), free(g.views.s), free(g.accessors.s), free(anims.s), free(nodes.s), free(joints.s), free(json.s);
}

int main(int argc, char **argv)
{
    static animal a;
    if (argc == 6 && strcmp(argv[1], "--bench") == 0) {
        /* gen_samples --bench OUT_DIR JOINTS CLIPS SECONDS: a rig for `make bench` */
        int joints = atoi(argv[3]), clips = atoi(argv[4]);
        double seconds = atof(argv[5]);
        if (joints < 20 || joints > MAX_JOINTS || clips < 1 || clips > MAX_CLIPS || !(seconds > 0)) {
            fprintf(stderr, "gen_samples --bench: 20..%d joints, 1..%d clips, seconds > 0\n", MAX_JOINTS, MAX_CLIPS);
            return 2;
        }
        build_bench(&a, joints, clips, seconds, KEY_RATE);
        char name[64];
        snprintf(name, sizeof name, "bench_j%d_c%d_s%g", joints, clips, seconds);
        a.name = name;
        write_animal(&a, argv[2]);
        return 0;
    }
    if (argc != 2) {
        fprintf(stderr, "usage: gen_samples OUT_DIR | gen_samples --bench OUT_DIR JOINTS CLIPS SECONDS\n");
        return 2;
    }
    build_quadruped(&a);
    write_animal(&a, argv[1]);
    drop_joints(&a, "quadruped_lod1", lod1_drops);
    write_animal(&a, argv[1]);
    build_fish(&a);
    write_animal(&a, argv[1]);
    build_bird(&a);
    write_animal(&a, argv[1]);
    return 0;
}
