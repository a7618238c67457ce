/* vertex_groups.c - see vertex_groups.h. */
#include "vertex_groups.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"
#include "lanes.h" /* cb_skin_vertex */

/* A vertex as grouping sorts it: by main joint, then along a Z-order curve through the
 * primitive's box, so that a group's vertices lie close together. */
typedef struct keyed_vertex {
    uint64_t key; /* main joint, then place */
    uint32_t vertex;
} keyed_vertex;

/* Sorts by key, equal keys in their order (by vertex): a stable radix sort, 11 bits a pass over
 * the 46 the keys use (16 of joint, 30 of place). Leaves the result in keys. */
static void sort_keys(keyed_vertex *keys, keyed_vertex *scratch, uint32_t n)
{
    for (int shift = 0; shift < 46; shift += 11) {
        uint32_t count[2048] = {0};
        for (uint32_t i = 0; i < n; ++i) count[keys[i].key >> shift & 2047]++;
        for (uint32_t d = 0, sum = 0; d < 2048; ++d) {
            uint32_t c = count[d];
            count[d] = sum, sum += c;
        }
        for (uint32_t i = 0; i < n; ++i) scratch[count[keys[i].key >> shift & 2047]++] = keys[i];
        keyed_vertex *swap = keys;
        keys = scratch, scratch = swap;
    }
    /* Five passes, an odd number: the sorted keys are in the other buffer; copy them back. */
    memcpy(scratch, keys, n * sizeof *keys);
}

/* fmin/fmax without the library calls (the values are finite). */
static inline double lesser(double a, double b) { return b < a ? b : a; }
static inline double greater(double a, double b) { return b > a ? b : a; }

/* 10 bits, spread to every third bit. */
static uint32_t spread_bits(uint32_t v)
{
    v = (v | v << 16) & 0x030000FFu;
    v = (v | v << 8) & 0x0300F00Fu;
    v = (v | v << 4) & 0x030C30C3u;
    return (v | v << 2) & 0x09249249u;
}

/* The Z-order index of x in the box lo..hi (1024 steps an axis). */
static uint32_t z_order(const float *x, const float *lo, const float *hi)
{
    uint32_t code = 0;
    for (int k = 0; k < 3; ++k) {
        double t = hi[k] > lo[k] ? ((double)x[k] - lo[k]) / ((double)hi[k] - lo[k]) : 0;
        code |= spread_bits((uint32_t)(fmin(fmax(t, 0), 1) * 1023)) << k;
    }
    return code;
}

/* Bind-space distance from joint j's bind position, in double (no float rounding to cover). */
static double distance_from(const float *x, const float *bind, uint32_t j)
{
    const float *b = bind + (size_t)j * 3;
    double dx = (double)x[0] - b[0], dy = (double)x[1] - b[1], dz = (double)x[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* The index of joint j in the group's list of `count`, or count. */
static uint32_t find_joint(const cb_group_joint *joints, uint32_t count, uint32_t j)
{
    uint32_t k = 0;
    while (k < count && joints[k].joint != j) ++k;
    return k;
}

/* Adds vertex v's joints to the group's list (joints[0 .. *count)) and grows each one's box of
 * vertices (box[k]: lo then hi). A joint named twice by one vertex counts with the sum of its
 * |weights|, as skinning applies both. */
static void add_vertex_joints(const cb_primitive *prim, uint32_t v, const float *bind, cb_group_joint *joints,
                              uint32_t *count, double (*box)[6])
{
    const uint16_t *jv = prim->joints + (size_t)v * 4;
    const float *wv = prim->weights + (size_t)v * 4, *x = prim->positions + (size_t)v * 3;
    for (int i = 0; i < 4; ++i) {
        if (wv[i] == 0) continue;
        bool seen = false;
        for (int e = 0; e < i; ++e) seen |= wv[e] != 0 && jv[e] == jv[i];
        if (seen) continue;
        double weight = 0;
        for (int e = i; e < 4; ++e)
            if (wv[e] != 0 && jv[e] == jv[i]) weight += fabs((double)wv[e]);
        uint32_t k = find_joint(joints, *count, jv[i]);
        if (k == *count) {
            joints[(*count)++] = (cb_group_joint){jv[i], 0, 0, {0, 0, 0}, 0};
            for (int a = 0; a < 3; ++a) box[k][a] = INFINITY, box[k][3 + a] = -INFINITY;
        }
        joints[k].reach = greater(joints[k].reach, distance_from(x, bind, jv[i]));
        joints[k].weight = greater(joints[k].weight, weight);
        for (int a = 0; a < 3; ++a) box[k][a] = lesser(box[k][a], x[a]), box[k][3 + a] = greater(box[k][3 + a], x[a]);
    }
}

/* Grows the spread of vertex v's joints: its distance from their centres. */
static void spread_vertex_joints(const cb_primitive *prim, uint32_t v, cb_group_joint *joints, uint32_t count)
{
    const float *x = prim->positions + (size_t)v * 3;
    for (int i = 0; i < 4; ++i) {
        if (prim->weights[(size_t)v * 4 + i] == 0) continue;
        cb_group_joint *gj = &joints[find_joint(joints, count, prim->joints[(size_t)v * 4 + i])];
        double dx = (double)x[0] - gj->centre[0], dy = (double)x[1] - gj->centre[1], dz = (double)x[2] - gj->centre[2];
        gj->spread = greater(gj->spread, sqrt(dx * dx + dy * dy + dz * dz));
    }
}

/* The joint with the largest |weight| (the first of equals); false when none is non-zero. */
static bool main_joint(const cb_primitive *prim, uint32_t v, uint32_t *joint)
{
    const float *wv = prim->weights + (size_t)v * 4;
    int best = -1;
    for (int i = 0; i < 4; ++i)
        if (wv[i] != 0 && (best < 0 || fabsf(wv[i]) > fabsf(wv[best]))) best = i;
    if (best >= 0) *joint = prim->joints[(size_t)v * 4 + best];
    return best >= 0;
}

/* Groups one primitive's moved vertices; the arrays have room for all of them. */
static void group_primitive(const cb_primitive *prim, uint32_t pi, const float *bind, keyed_vertex *keys,
                            cb_vertex_groups *g, uint32_t *vertex_count, uint32_t *joint_count)
{
    uint32_t n = 0;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < prim->vertex_count; ++v)
        for (int a = 0; a < 3; ++a)
            lo[a] = (float)lesser(lo[a], prim->positions[(size_t)v * 3 + a]), hi[a] = (float)greater(hi[a], prim->positions[(size_t)v * 3 + a]);
    for (uint32_t v = 0; v < prim->vertex_count; ++v) {
        uint32_t j;
        if (main_joint(prim, v, &j)) keys[n++] = (keyed_vertex){(uint64_t)j << 32 | z_order(prim->positions + (size_t)v * 3, lo, hi), v};
    }
    sort_keys(keys, keys + prim->vertex_count, n);
    double box[4 * CB_VERTEX_GROUP_SIZE][6];
    for (uint32_t i = 0; i < n;) {
        cb_vertex_group *grp = &g->groups[g->group_count++];
        *grp = (cb_vertex_group){pi, *vertex_count, 0, *joint_count, 0, 0};
        uint64_t joint = keys[i].key >> 32;
        while (i < n && grp->count < CB_VERTEX_GROUP_SIZE && keys[i].key >> 32 == joint) {
            uint32_t v = keys[i++].vertex;
            const float *wv = prim->weights + (size_t)v * 4;
            double sum = fabs((double)wv[0]) + fabs((double)wv[1]) + fabs((double)wv[2]) + fabs((double)wv[3]);
            grp->weight_sum = greater(grp->weight_sum, sum);
            g->vertices[grp->first + grp->count++] = v;
            add_vertex_joints(prim, v, bind, g->joints + grp->joint_first, &grp->joint_count, box);
        }
        cb_group_joint *joints = g->joints + grp->joint_first;
        for (uint32_t k = 0; k < grp->joint_count; ++k)
            for (int a = 0; a < 3; ++a) joints[k].centre[a] = 0.5 * (box[k][a] + box[k][3 + a]);
        for (uint32_t n = 0; n < grp->count; ++n) spread_vertex_joints(prim, g->vertices[grp->first + n], joints, grp->joint_count);
        *vertex_count += grp->count;
        *joint_count += grp->joint_count;
    }
}

bool cb_vertex_groups_build(const cb_model *m, int32_t skin, const float *bind, cb_vertex_groups *out)
{
    memset(out, 0, sizeof *out);
    size_t total = 0, largest = 0;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi)
        if (m->primitives[pi].skin == skin) {
            total += m->primitives[pi].vertex_count;
            if (m->primitives[pi].vertex_count > largest) largest = m->primitives[pi].vertex_count;
        }
    /* At most a group and 4 joints per vertex; trimmed after. */
    out->groups = malloc((total ? total : 1) * sizeof *out->groups);
    out->vertices = malloc((total ? total : 1) * sizeof *out->vertices);
    out->joints = malloc((total ? total : 1) * 4 * sizeof *out->joints);
    keyed_vertex *keys = malloc((largest ? largest : 1) * 2 * sizeof *keys); /* and the sort's scratch */
    if (!out->groups || !out->vertices || !out->joints || !keys) {
        free(keys);
        cb_vertex_groups_free(out);
        return false;
    }
    uint32_t vertex_count = 0, joint_count = 0;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi)
        if (m->primitives[pi].skin == skin) group_primitive(&m->primitives[pi], pi, bind, keys, out, &vertex_count, &joint_count);
    free(keys);
    cb_group_joint *joints = realloc(out->joints, (joint_count ? joint_count : 1) * sizeof *joints);
    if (joints) out->joints = joints;
    cb_vertex_group *groups = realloc(out->groups, (out->group_count ? out->group_count : 1) * sizeof *groups);
    if (groups) out->groups = groups;
    return true;
}

void cb_vertex_groups_free(cb_vertex_groups *g)
{
    free(g->groups), free(g->vertices), free(g->joints);
    memset(g, 0, sizeof *g);
}

/* cb_skin_positions' arithmetic in its order (skinning.c), for a list of vertices, keeping only
 * the largest squared length. */
CB_TARGET_CLONES
double cb_skin_group_worst(const cb_primitive *prim, const uint32_t *vertices, uint32_t count, const double *mats)
{
    double worst = 0;
    for (uint32_t k = 0; k < count; ++k) {
        double r[3];
        cb_skin_vertex(prim, vertices[k], mats, r);
        double d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        worst = d2 > worst ? d2 : worst;
    }
    return worst;
}
