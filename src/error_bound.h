/* error_bound.h - cheap upper bounds on a row's worst vertex error, so measuring can skip the
 * rows and vertex groups that cannot change the worst (internal to the bake; see
 * palette_error.c's measurement).
 *
 * A vertex x skinned with joint differences D_j (exact less decoded, 4x4 column-major) moves by
 * |sum_i w_i D_ji x| <= sum_i |w_i| e_i <= W max_i e_i, e_i = |D_i b_i| + |A_i| r_i, where W is the
 * largest sum of |weights| in the group, b_i a point of the joint
 * (its bind position, or the centre of a group's vertices), r_i the farthest vertex of the group
 * from it and |A_i| a bound on the stretch of D_i's 3x3 part. O(a group's joints) per group
 * against O(its vertices) for skinning. */
#ifndef CB_ERROR_BOUND_H
#define CB_ERROR_BOUND_H

#include "crowdbake/crowdbake.h"
#include "vertex_groups.h"

/* What a bound needs of each joint's difference D (16 doubles, column-major). */
typedef struct cb_joint_error {
    double at_bind;     /* |D b|: the error at the joint's bind position */
    double stretch;     /* an upper bound on |A|, the 3x3 part's largest stretch */
    double slack_fixed; /* rounding slack for the terms that do not grow with the reach */
    double translation; /* |t|, D's translation */
    const double *diff; /* D itself */
} cb_joint_error;

/* The terms for every joint; false when a difference is not finite (then no bound holds). */
bool cb_joint_errors(const double *diff, uint32_t bones, const float *bind, cb_joint_error *out);

/* An upper bound on the error cb_skin_group_worst computes for group g (vertex_groups.h) from
 * the differences whose terms are `joints`, rounding included. The cheap bound (from the
 * joints' bind positions) where that is at most `above`, else the tighter of it and the bound
 * from the centres of the group's vertices (0: always the tighter). */
double cb_group_error_bound(const cb_vertex_groups *g, uint32_t group, const cb_joint_error *joints, double above);

/* A bound on every group's bound (cb_group_error_bound) at once, from each joint's largest reach
 * in any group (reach: one a joint) and the groups' largest weight sum: a group's cheap bound
 * with the largest of each of its terms, and the tighter bound is below the cheap one. When it
 * is at most a row's worst error so far, no group of the row can exceed it. O(bones). */
double cb_row_error_cap(const cb_joint_error *joints, uint32_t bones, const double *reach, double weight_sum);

/* A row to measure and its bound. */
typedef struct cb_bounded_row {
    double bound;
    uint32_t frame;
} cb_bounded_row;

/* Sorts rows by bound, largest first (ties by frame), so the worst rows are measured first. */
void cb_sort_bounded_rows(cb_bounded_row *rows, uint32_t count);

#endif
