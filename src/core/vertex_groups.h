/* vertex_groups.h - the skin's vertices in small groups for measuring a bake's error (internal;
 * see palette_error.c). Each group holds vertices of one primitive that share their main joint
 * and lie about as far from it, with every joint that moves them, how far its vertices lie from
 * that joint's bind position and their largest weight on it. From a row's joint differences
 * D_j (exact less decoded) a group's worst vertex error is bounded in O(its joints), the way
 * error_bound.h bounds a whole row:
 *
 *     |sum_i w_i D_ji x| <= sum_i |w_i| (|D_ji b_ji| + |A_ji| r_gji)
 *                        <= min(W_g max_j e_gj, sum_j w_gj e_gj)
 *
 * with r_gj the group's reach from joint j, w_gj its largest |weight| on j, W_g its largest sum
 * of |weights| and A_j the 3x3 part of D_j. A row's bound is its largest group bound, and
 * measuring skins only the groups whose bound exceeds the worst error found so far: the same
 * maximum, bit for bit, as skinning every vertex. */
#ifndef CB_VERTEX_GROUPS_H
#define CB_VERTEX_GROUPS_H

#include "crowdbake/crowdbake.h"

/* Vertices per group: small enough for tight reaches, large enough that bounding a group costs
 * little next to skinning it. */
#define CB_VERTEX_GROUP_SIZE 32

typedef struct cb_group_joint {
    uint32_t joint;
    double reach;     /* farthest of the group's vertices it moves, from its bind position */
    double weight;    /* the largest sum of |weights| a vertex of the group gives it */
    double centre[3]; /* the middle of the box of those vertices */
    double spread;    /* farthest of them from the centre */
} cb_group_joint;

typedef struct cb_vertex_group {
    uint32_t primitive;              /* index into the model's primitives */
    uint32_t first, count;           /* its vertices: vertices[first .. first + count) */
    uint32_t joint_first, joint_count; /* its joints: joints[joint_first ..] */
    double weight_sum;               /* the largest sum of |weights| of one of its vertices */
} cb_vertex_group;

typedef struct cb_vertex_groups {
    cb_vertex_group *groups;
    uint32_t group_count;
    uint32_t *vertices; /* vertex indices within each group's primitive */
    cb_group_joint *joints;
} cb_vertex_groups;

/* Groups the vertices of the skin's primitives (bind: 3 floats per joint). False when out of
 * memory. */
bool cb_vertex_groups_build(const cb_model *m, int32_t skin, const float *bind, cb_vertex_groups *out);
void cb_vertex_groups_free(cb_vertex_groups *g);

/* The largest squared displacement of the group's vertices skinned with `mats` (16 doubles per
 * joint), each computed exactly as cb_skin_positions does. */
double cb_skin_group_worst(const cb_primitive *prim, const uint32_t *vertices, uint32_t count, const double *mats);

#endif
