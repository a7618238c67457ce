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

#define PI 3.14159265358979323846
#define MAX_JOINTS 512
#define MAX_CLIPS 128
#define KEY_RATE 24.0 /* keys per second written for every animated channel */

typedef enum role {
    R_ROOT, R_SPINE, R_NECK, R_HEAD, R_JAW, R_EAR, R_TAIL, R_HIP, R_UPPER, R_LOWER, R_FOOT, R_TOE,
    R_FIN, R_WING_IN, R_WING_MID, R_WING_TIP, R_BEAK
} role;

typedef struct joint {
    char name[32];
    int parent;
    double pos[3];   /* local rest translation */
    double width;    /* thickness of the bone box ending at this joint */
    role role;
    int side;        /* -1 left, +1 right, 0 centre */
    int front;       /* 1 for front legs */
    int chain;       /* index along its chain */
} joint;

typedef struct animal animal;
typedef void (*pose_fn)(const animal *a, int clip, int j, double t, double euler[3], double trans[3]);

typedef struct clip {
    const char *name;
    double duration;
    int loops;
} clip;

struct animal {
    const char *name;
    joint joints[MAX_JOINTS];
    int joint_count;
    clip clips[MAX_CLIPS];
    int clip_count;
    pose_fn pose;
    double speed[MAX_CLIPS]; /* root travel along +Z, m/s */
};

static int add(animal *a, const char *name, int parent, double x, double y, double z, double width, role r, int side,
               int chain)
{
    joint *j = &a->joints[a->joint_count];
    snprintf(j->name, sizeof j->name, "%s", name);
    j->parent = parent;
    j->pos[0] = x, j->pos[1] = y, j->pos[2] = z;
    j->width = width;
    j->role = r;
    j->side = side;
    j->chain = chain;
    return a->joint_count++;
}

/* ---- the animals ------------------------------------------------------------------------ */

static void add_leg(animal *a, int parent, const char *prefix, double x, double z, int side, int front)
{
    char n[32];
    snprintf(n, sizeof n, "%s_hip", prefix);
    int hip = add(a, n, parent, x, -0.05, z, 0.10, R_HIP, side, 0);
    snprintf(n, sizeof n, "%s_upper", prefix);
    int up = add(a, n, hip, 0, -0.25, front ? 0.02 : -0.02, 0.08, R_UPPER, side, 1);
    snprintf(n, sizeof n, "%s_lower", prefix);
    int lo = add(a, n, up, 0, -0.25, front ? -0.03 : 0.03, 0.06, R_LOWER, side, 2);
    snprintf(n, sizeof n, "%s_foot", prefix);
    int foot = add(a, n, lo, 0, -0.18, 0, 0.05, R_FOOT, side, 3);
    snprintf(n, sizeof n, "%s_toe", prefix);
    add(a, n, foot, 0, -0.02, 0.06, 0.05, R_TOE, side, 4);
    a->joints[hip].front = a->joints[up].front = a->joints[lo].front = front;
    a->joints[foot].front = a->joints[foot + 1].front = front;
}

static double gait_phase(const joint *j)
{
    /* Diagonal pairs move together: left-front with right-hind. */
    int diagonal = (j->side < 0) == (j->front != 0);
    return diagonal ? 0.0 : PI;
}

static void quadruped_pose(const animal *a, int c, int ji, double t, double e[3], double tr[3])
{
    const joint *j = &a->joints[ji];
    const char *clip = a->clips[c].name;
    double w = 2 * PI * t / a->clips[c].duration; /* one cycle per clip */
    e[0] = e[1] = e[2] = 0;
    tr[0] = j->pos[0], tr[1] = j->pos[1], tr[2] = j->pos[2];
    int walk = strcmp(clip, "walk") == 0, run = strcmp(clip, "run") == 0;
    if (walk || run) {
        double amp = run ? 0.75 : 0.4, cycles = run ? 2 : 1;
        double ph = cycles * w + gait_phase(j);
        if (j->role == R_ROOT) {
            tr[2] = a->speed[c] * t;
            tr[1] = (run ? 0.05 : 0.02) * sin(2 * cycles * w);
        }
        if (j->role == R_HIP) e[0] = amp * sin(ph);
        if (j->role == R_LOWER) e[0] = (j->front ? -1 : 1) * amp * 0.8 * fmax(0, sin(ph + PI / 2));
        if (j->role == R_FOOT) e[0] = -amp * 0.5 * sin(ph);
        if (j->role == R_SPINE) e[1] = 0.05 * sin(cycles * w + j->chain);
        if (j->role == R_NECK) e[0] = 0.06 * sin(2 * cycles * w);
        if (j->role == R_TAIL) e[1] = 0.25 * sin(cycles * w - 0.6 * j->chain);
    } else if (strcmp(clip, "idle") == 0) {
        if (j->role == R_SPINE) e[0] = 0.02 * sin(w);
        if (j->role == R_NECK) e[1] = 0.15 * sin(w);
        if (j->role == R_TAIL) e[1] = 0.35 * sin(2 * w - 0.7 * j->chain);
        if (j->role == R_EAR) e[2] = j->side * 0.2 * sin(3 * w);
    } else if (strcmp(clip, "eat") == 0) {
        double down = 0.5 - 0.5 * cos(w); /* 0 -> 1 -> 0 */
        if (j->role == R_NECK) e[0] = 0.55 * down;
        if (j->role == R_HEAD) e[0] = 0.3 * down;
        if (j->role == R_JAW) e[0] = 0.25 * down * (0.5 + 0.5 * sin(6 * w));
        if (j->role == R_UPPER && j->front) e[0] = -0.15 * down;
        if (j->role == R_TAIL) e[1] = 0.2 * sin(2 * w - 0.5 * j->chain);
    } else if (strcmp(clip, "death") == 0) {
        double k = fmin(1.0, t / (0.8 * a->clips[c].duration)); /* falls, then lies still */
        double ease = k * k * (3 - 2 * k);
        if (j->role == R_ROOT) {
            e[2] = ease * PI / 2;
            tr[0] = ease * 0.35;
            tr[1] = -ease * 0.2;
        }
        if (j->role == R_NECK) e[0] = 0.4 * ease;
        if (j->role == R_UPPER) e[0] = 0.5 * ease * (j->front ? -1 : 1);
        if (j->role == R_TAIL) e[0] = 0.3 * ease;
    }
}

static void build_quadruped(animal *a)
{
    memset(a, 0, sizeof *a);
    a->name = "quadruped";
    a->pose = quadruped_pose;
    int root = add(a, "root", -1, 0, 0, 0, 0.05, R_ROOT, 0, 0);
    int s = add(a, "spine0", root, 0, 0.75, -0.35, 0.26, R_SPINE, 0, 0);
    int pelvis = s;
    for (int i = 1; i < 5; ++i) {
        char n[32];
        snprintf(n, sizeof n, "spine%d", i);
        s = add(a, n, s, 0, 0.02, 0.18, 0.28, R_SPINE, 0, i);
    }
    int neck = s;
    for (int i = 0; i < 3; ++i) {
        char n[32];
        snprintf(n, sizeof n, "neck%d", i);
        neck = add(a, n, neck, 0, 0.10, 0.07, 0.12, R_NECK, 0, i);
    }
    int head = add(a, "head", neck, 0, 0.06, 0.06, 0.14, R_HEAD, 0, 0);
    add(a, "jaw", head, 0, -0.04, 0.16, 0.08, R_JAW, 0, 0);
    add(a, "ear_l", head, -0.06, 0.08, 0.0, 0.04, R_EAR, -1, 0);
    add(a, "ear_r", head, 0.06, 0.08, 0.0, 0.04, R_EAR, 1, 0);
    int tail = pelvis;
    for (int i = 0; i < 8; ++i) {
        char n[32];
        snprintf(n, sizeof n, "tail%d", i);
        tail = add(a, n, tail, 0, i == 0 ? 0.02 : -0.015, -0.07, 0.06 - 0.005 * i, R_TAIL, 0, i);
    }
    add_leg(a, pelvis, "hind_l", -0.12, 0.0, -1, 0);
    add_leg(a, pelvis, "hind_r", 0.12, 0.0, 1, 0);
    add_leg(a, s, "front_l", -0.12, 0.0, -1, 1);
    add_leg(a, s, "front_r", 0.12, 0.0, 1, 1);
    a->clips[0] = (clip){"idle", 3.0, 1};
    a->clips[1] = (clip){"walk", 1.0, 1};
    a->clips[2] = (clip){"run", 0.8, 1};
    a->clips[3] = (clip){"eat", 2.5, 1};
    a->clips[4] = (clip){"death", 1.5, 0};
    a->clip_count = 5;
    a->speed[1] = 1.2;
    a->speed[2] = 4.0;
}

static void fish_pose(const animal *a, int c, int ji, double t, double e[3], double tr[3])
{
    const joint *j = &a->joints[ji];
    double w = 2 * PI * t / a->clips[c].duration;
    e[0] = e[1] = e[2] = 0;
    tr[0] = j->pos[0], tr[1] = j->pos[1], tr[2] = j->pos[2];
    if (j->role == R_ROOT) tr[2] = a->speed[c] * t;
    if (j->role == R_SPINE) e[1] = (0.05 + 0.03 * j->chain) * sin(2 * w - 0.7 * j->chain);
    if (j->role == R_TAIL) e[1] = 0.35 * sin(2 * w - 6.0);
    if (j->role == R_FIN) e[2] = j->side * 0.3 * sin(4 * w);
}

static void build_fish(animal *a)
{
    memset(a, 0, sizeof *a);
    a->name = "fish";
    a->pose = fish_pose;
    int root = add(a, "root", -1, 0, 0, 0, 0.02, R_ROOT, 0, 0);
    /* The spine runs from the head (+Z) backwards. */
    int s = add(a, "spine0", root, 0, 0.5, 0.25, 0.10, R_SPINE, 0, 0);
    int head = s;
    for (int i = 1; i < 9; ++i) {
        char n[32];
        snprintf(n, sizeof n, "spine%d", i);
        s = add(a, n, s, 0, 0, -0.06, 0.11 - 0.01 * i, R_SPINE, 0, i);
    }
    add(a, "tail_fin", s, 0, 0, -0.08, 0.03, R_TAIL, 0, 0);
    add(a, "fin_l", head, -0.05, -0.02, -0.06, 0.02, R_FIN, -1, 0);
    add(a, "fin_r", head, 0.05, -0.02, -0.06, 0.02, R_FIN, 1, 0);
    a->clips[0] = (clip){"swim", 1.0, 1};
    a->clip_count = 1;
    a->speed[0] = 0.6;
}

static void bird_pose(const animal *a, int c, int ji, double t, double e[3], double tr[3])
{
    const joint *j = &a->joints[ji];
    double w = 2 * PI * t / a->clips[c].duration;
    int flap = strcmp(a->clips[c].name, "flap") == 0;
    e[0] = e[1] = e[2] = 0;
    tr[0] = j->pos[0], tr[1] = j->pos[1], tr[2] = j->pos[2];
    if (j->role == R_ROOT) tr[2] = a->speed[c] * t, tr[1] = flap ? 0.05 * sin(w) : 0;
    double amp = flap ? 0.9 : 0.08;
    if (j->role == R_WING_IN) e[2] = j->side * amp * sin(w);
    if (j->role == R_WING_MID) e[2] = j->side * amp * 0.5 * sin(w - 0.6);
    if (j->role == R_WING_TIP) e[2] = j->side * amp * 0.4 * sin(w - 1.2);
    if (j->role == R_TAIL) e[0] = 0.1 * sin(w);
    if (j->role == R_NECK) e[0] = (flap ? 0.08 : 0.03) * sin(w + 1);
}

static void build_bird(animal *a)
{
    memset(a, 0, sizeof *a);
    a->name = "bird";
    a->pose = bird_pose;
    int root = add(a, "root", -1, 0, 0, 0, 0.02, R_ROOT, 0, 0);
    int body = add(a, "body", root, 0, 0.25, -0.05, 0.10, R_SPINE, 0, 0);
    int n0 = add(a, "neck0", body, 0, 0.04, 0.10, 0.05, R_NECK, 0, 0);
    int n1 = add(a, "neck1", n0, 0, 0.04, 0.03, 0.04, R_NECK, 0, 1);
    int head = add(a, "head", n1, 0, 0.03, 0.02, 0.05, R_HEAD, 0, 0);
    add(a, "beak", head, 0, 0, 0.05, 0.02, R_BEAK, 0, 0);
    for (int side = -1; side <= 1; side += 2) {
        const char *s = side < 0 ? "l" : "r";
        char n[32];
        snprintf(n, sizeof n, "wing_in_%s", s);
        int w0 = add(a, n, body, side * 0.05, 0.03, 0.04, 0.03, R_WING_IN, side, 0);
        snprintf(n, sizeof n, "wing_mid_%s", s);
        int w1 = add(a, n, w0, side * 0.14, 0, 0, 0.03, R_WING_MID, side, 1);
        snprintf(n, sizeof n, "wing_tip_%s", s);
        int w2 = add(a, n, w1, side * 0.14, 0, -0.02, 0.02, R_WING_TIP, side, 2);
        (void)w2;
        snprintf(n, sizeof n, "leg_%s", s);
        int l0 = add(a, n, body, side * 0.03, -0.06, 0, 0.02, R_UPPER, side, 0);
        snprintf(n, sizeof n, "foot_%s", s);
        add(a, n, l0, 0, -0.08, 0.02, 0.015, R_FOOT, side, 1);
    }
    int t0 = add(a, "tail0", body, 0, 0, -0.09, 0.04, R_TAIL, 0, 0);
    add(a, "tail1", t0, 0, 0, -0.08, 0.03, R_TAIL, 0, 1);
    add(a, "crest", head, 0, 0.03, -0.01, 0.01, R_HEAD, 0, 1);
    a->clips[0] = (clip){"flap", 0.5, 1};
    a->clips[1] = (clip){"glide", 2.0, 1};
    a->clip_count = 2;
    a->speed[0] = 5.0;
    a->speed[1] = 7.0;
}

/* A benchmark creature: a spine with limbs hanging off it, `joints` in all, `clips` clips of
 * `seconds` each, every joint rotating on every clip (the worst case for a sampler). */
static void bench_pose(const animal *a, int c, int ji, double t, double e[3], double tr[3])
{
    const joint *j = &a->joints[ji];
    double w = 2 * PI * t / a->clips[c].duration, ph = 0.37 * c + 0.11 * ji;
    tr[0] = j->pos[0], tr[1] = j->pos[1], tr[2] = j->pos[2];
    if (j->role == R_ROOT) {
        e[0] = e[1] = e[2] = 0;
        tr[2] = a->speed[c] * t;
        return;
    }
    e[0] = 0.3 * sin(w * (1 + c % 3) + ph);
    e[1] = 0.2 * sin(2 * w + ph);
    e[2] = 0.1 * sin(3 * w + 0.5 * ph);
}

static void build_bench(animal *a, int joints, int clips, double seconds, double key_rate)
{
    memset(a, 0, sizeof *a);
    a->name = "bench";
    a->pose = bench_pose;
    (void)key_rate;
    int root = add(a, "root", -1, 0, 0, 0, 0.02, R_ROOT, 0, 0);
    int spine_len = joints / 10, prev = root;
    int spine[MAX_JOINTS];
    for (int i = 0; i < spine_len && a->joint_count < joints; ++i) {
        char n[32];
        snprintf(n, sizeof n, "spine%d", i);
        prev = spine[i] = add(a, n, prev, 0, i ? 0 : 1.0, i ? 0.08 : 0, 0.1, R_SPINE, 0, i);
    }
    for (int limb = 0; a->joint_count < joints; ++limb) {
        int parent = spine[(limb * 7) % spine_len], side = limb % 2 ? 1 : -1;
        for (int i = 0; i < 20 && a->joint_count < joints; ++i) {
            char n[32];
            snprintf(n, sizeof n, "limb%d_%d", limb, i);
            parent = add(a, n, parent, i ? 0 : side * 0.06, -0.05, 0.01, 0.04, R_UPPER, side, i);
        }
    }
    a->clip_count = clips;
    for (int c = 0; c < clips; ++c) {
        static char names[MAX_CLIPS][16];
        snprintf(names[c], sizeof names[c], "clip%02d", c);
        a->clips[c] = (clip){names[c], seconds, 1};
        a->speed[c] = 1.0 + 0.1 * c;
    }
}

/* A level of detail of an animal: the same rig with some end joints dropped (their parents
 * stay), so every kept joint has the same bind pose. */
static void drop_joints(animal *a, const char *name, bool (*drop)(const joint *j))
{
    int map[MAX_JOINTS], kept = 0;
    for (int j = 0; j < a->joint_count; ++j) map[j] = drop(&a->joints[j]) ? -1 : kept++;
    for (int j = 0, k = 0; j < a->joint_count; ++j) {
        if (map[j] < 0) continue;
        a->joints[k] = a->joints[j];
        a->joints[k].parent = a->joints[j].parent >= 0 ? map[a->joints[j].parent] : -1;
        ++k;
    }
    a->joint_count = kept;
    a->name = name;
}

static bool lod1_drops(const joint *j)
{
    return j->role == R_EAR || j->role == R_JAW || j->role == R_TOE || (j->role == R_TAIL && j->chain >= 4);
}

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
    uint8_t *jnt;
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
            uint8_t *J = m->jnt + 4 * m->vcount;
            for (int i = 0; i < 3; ++i) P[i] = (float)corner[c][i], N[i] = (float)(n[i] / nl);
            int blend = (c & 4) && j1 >= 0;
            J[0] = (uint8_t)j0, J[1] = (uint8_t)(blend ? j1 : 0), J[2] = J[3] = 0;
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
    m->jnt = calloc((size_t)boxes * 24 * 4, 1);
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
    int a_jnt = accessor(&g, m.jnt, (size_t)m.vcount * 4, 5121, m.vcount, "VEC4", NULL, NULL, 4, 1);
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
