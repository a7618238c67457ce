/* animals.c - the sample animals: their joints, clips and poses (see animals.h). */
#include "animals.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

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

void build_quadruped(animal *a)
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

void build_fish(animal *a)
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

void build_bird(animal *a)
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

void build_bench(animal *a, int joints, int clips, double seconds, double key_rate)
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
void drop_joints(animal *a, const char *name, bool (*drop)(const joint *j))
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

bool lod1_drops(const joint *j)
{
    return j->role == R_EAR || j->role == R_JAW || j->role == R_TOE || (j->role == R_TAIL && j->chain >= 4);
}
