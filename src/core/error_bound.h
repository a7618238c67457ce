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

#include <math.h>

/* What a bound needs of each joint's difference D (16 doubles, column-major). */
typedef struct cb_joint_error {
    double at_bind;     /* |D b|: the error at the joint's bind position */
    double stretch;     /* an upper bound on |A|, the 3x3 part's largest stretch */
    double slack_fixed; /* rounding slack for the terms that do not grow with the reach */
    double translation; /* |t|, D's translation */
    const double *diff; /* D itself */
} cb_joint_error;

/* The terms of one joint's difference D (16 doubles, column-major: D[3], D[7], D[11] and D[15]
 * are not read) at its bind position b: terms = {at_bind, stretch, slack_fixed, translation}.
 * Inline, so that a loop over many differences held as lanes vectorizes; every caller gets the
 * same operations in the same order, so the same bits. Returns at_bind + slack_fixed, which is
 * finite exactly when a bound holds. */
static inline __attribute__((always_inline)) double cb_joint_error_terms(const double *D, double bx, double by,
                                                                         double bz, double terms[4])
{
    double ex = D[0] * bx + D[4] * by + D[8] * bz + D[12];
    double ey = D[1] * bx + D[5] * by + D[9] * bz + D[13];
    double ez = D[2] * bx + D[6] * by + D[10] * bz + D[14];
    /* The stretch: an upper bound on the 3x3 part's largest stretch (spectral norm), the square
     * root of the largest Gershgorin row sum of its Gram matrix G = A^T A, whose eigenvalues are
     * the squared stretches. Tighter than the Frobenius norm for the near-rotations that
     * encodings leave (sqrt(4/3) instead of sqrt(2) times the stretch at worst for a small
     * rotation). */
    const double *c0 = D, *c1 = D + 4, *c2 = D + 8; /* columns of A */
    double g00 = c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2], g11 = c1[0] * c1[0] + c1[1] * c1[1] + c1[2] * c1[2];
    double g22 = c2[0] * c2[0] + c2[1] * c2[1] + c2[2] * c2[2];
    double g01 = fabs(c0[0] * c1[0] + c0[1] * c1[1] + c0[2] * c1[2]);
    double g02 = fabs(c0[0] * c2[0] + c0[1] * c2[1] + c0[2] * c2[2]);
    double g12 = fabs(c1[0] * c2[0] + c1[1] * c2[1] + c1[2] * c2[2]);
    double r0 = g00 + g01 + g02, r1 = g01 + g11 + g12, r2 = g02 + g12 + g22;
    /* Not fmax: a compare and a select, where fmax is a call. They differ only for NaN, and a
     * difference with one has a NaN at_bind, which fails the bound either way. */
    double r = r0 > r1 ? r0 : r1;
    double a = sqrt(r > r2 ? r : r2) * (1 + 1e-9), t = sqrt(D[12] * D[12] + D[13] * D[13] + D[14] * D[14]);
    terms[0] = sqrt(ex * ex + ey * ey + ez * ez);
    terms[1] = a;
    /* Rounding in skinning and here is far below 1e-9 of the terms' sizes: the slack keeps the
     * bound above the computed error even where D b and t cancel (far from the origin). */
    terms[2] = 1e-9 * (a * sqrt(bx * bx + by * by + bz * bz) + t);
    terms[3] = t;
    return terms[0] + terms[2];
}

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
