/* error_bound.c - see error_bound.h. */
#include "error_bound.h"
#include "cb_math.h"

#include <math.h>
#include <stdlib.h>

/* An upper bound on the 3x3 part's largest stretch (spectral norm): the square root of the
 * largest Gershgorin row sum of its Gram matrix G = A^T A, whose eigenvalues are the squared
 * stretches. Tighter than the Frobenius norm for the near-rotations that encodings leave
 * (sqrt(4/3) instead of sqrt(2) times the stretch at worst for a small rotation). */
static CB_CLONE_INLINE double stretch(const double *D)
{
    const double *c0 = D, *c1 = D + 4, *c2 = D + 8; /* columns of A */
    double g00 = c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2], g11 = c1[0] * c1[0] + c1[1] * c1[1] + c1[2] * c1[2];
    double g22 = c2[0] * c2[0] + c2[1] * c2[1] + c2[2] * c2[2];
    double g01 = fabs(c0[0] * c1[0] + c0[1] * c1[1] + c0[2] * c1[2]);
    double g02 = fabs(c0[0] * c2[0] + c0[1] * c2[1] + c0[2] * c2[2]);
    double g12 = fabs(c1[0] * c2[0] + c1[1] * c2[1] + c1[2] * c2[2]);
    double r0 = g00 + g01 + g02, r1 = g01 + g11 + g12, r2 = g02 + g12 + g22;
    /* Not fmax: a compare and a select, where fmax is a call. They differ only for NaN, and a
     * difference with one makes cb_joint_errors fail (its at_bind is not finite) either way. */
    double r = r0 > r1 ? r0 : r1;
    return sqrt(r > r2 ? r : r2) * (1 + 1e-9);
}

static int by_bound(const void *pa, const void *pb)
{
    const cb_bounded_row *a = pa, *b = pb;
    if (a->bound != b->bound) return a->bound < b->bound ? 1 : -1;
    return (a->frame > b->frame) - (a->frame < b->frame);
}

void cb_sort_bounded_rows(cb_bounded_row *rows, uint32_t count) { qsort(rows, count, sizeof *rows, by_bound); }

CB_TARGET_CLONES
bool cb_joint_errors(const double *diff, uint32_t bones, const float *bind, cb_joint_error *out)
{
    bool finite = true;
    for (uint32_t j = 0; j < bones; ++j) {
        const double *D = diff + (size_t)j * 16;
        double bx = bind[j * 3], by = bind[j * 3 + 1], bz = bind[j * 3 + 2];
        double ex = D[0] * bx + D[4] * by + D[8] * bz + D[12];
        double ey = D[1] * bx + D[5] * by + D[9] * bz + D[13];
        double ez = D[2] * bx + D[6] * by + D[10] * bz + D[14];
        double a = stretch(D), t = sqrt(D[12] * D[12] + D[13] * D[13] + D[14] * D[14]);
        out[j].at_bind = sqrt(ex * ex + ey * ey + ez * ez);
        out[j].stretch = a;
        /* Rounding in skinning and here is far below 1e-9 of the terms' sizes: the slack keeps
         * the bound above the computed error even where D b and t cancel (far from the origin). */
        out[j].slack_fixed = 1e-9 * (a * sqrt(bx * bx + by * by + bz * bz) + t);
        out[j].translation = t, out[j].diff = D;
        finite &= isfinite(out[j].at_bind + out[j].slack_fixed); /* no exit from the loop: it vectorizes */
    }
    return finite;
}

/* min(W max_j e_j, sum_j w_j e_j) over the group's joints, e_j from the bind position out to the
 * reach or (centred) from the centre out to the spread. */
static CB_CLONE_INLINE double combine(const cb_vertex_groups *g, const cb_vertex_group *grp, const cb_joint_error *joints, bool centred)
{
    double most = 0, sum = 0;
    for (uint32_t k = 0; k < grp->joint_count; ++k) {
        const cb_group_joint *gj = &g->joints[grp->joint_first + k];
        const cb_joint_error *je = &joints[gj->joint];
        double e = je->at_bind + je->stretch * gj->reach * (1 + 2e-9) + je->slack_fixed;
        if (centred) {
            const double *D = je->diff, *c = gj->centre;
            double cx = D[0] * c[0] + D[4] * c[1] + D[8] * c[2] + D[12];
            double cy = D[1] * c[0] + D[5] * c[1] + D[9] * c[2] + D[13];
            double cz = D[2] * c[0] + D[6] * c[1] + D[10] * c[2] + D[14];
            double size = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) + gj->spread;
            double around = sqrt(cx * cx + cy * cy + cz * cz) + je->stretch * gj->spread * (1 + 2e-9) +
                            1e-9 * (je->stretch * size + je->translation);
            e = around < e ? around : e;
        }
        most = e > most ? e : most;
        sum += gj->weight * e;
    }
    double bound = grp->weight_sum * most;
    return (sum < bound ? sum : bound) * (1 + 1e-9);
}

/* The same operations as combine's (not centred) in the same order, each on terms at least as
 * large: rounding is monotonic, so the result is at least every group's. */
double cb_row_error_cap(const cb_joint_error *joints, uint32_t bones, const double *reach, double weight_sum)
{
    double most = 0;
    for (uint32_t j = 0; j < bones; ++j) {
        const cb_joint_error *je = &joints[j];
        double e = je->at_bind + je->stretch * reach[j] * (1 + 2e-9) + je->slack_fixed;
        most = e > most ? e : most;
    }
    return weight_sum * most * (1 + 1e-9);
}

CB_TARGET_CLONES
double cb_group_error_bound(const cb_vertex_groups *g, uint32_t group, const cb_joint_error *joints, double above)
{
    const cb_vertex_group *grp = &g->groups[group];
    double bound = combine(g, grp, joints, false);
    return bound > above ? combine(g, grp, joints, true) : bound;
}
