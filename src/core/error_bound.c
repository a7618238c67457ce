/* error_bound.c - see error_bound.h. */
#include "error_bound.h"
#include "cb_math.h"

#include <math.h>
#include <stdlib.h>

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
        double terms[4];
        double sum = cb_joint_error_terms(D, bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2], terms);
        out[j] = (cb_joint_error){terms[0], terms[1], terms[2], terms[3], D};
        finite &= isfinite(sum); /* no exit from the loop: it vectorizes */
    }
    return finite;
}

/* min(W max_j e_j, sum_j w_j e_j) over the group's joints, e_j from the bind position out to the
 * reach or (centred) from the centre out to the spread. */
static CB_CLONE_INLINE double combine(const cb_vertex_groups *g, const cb_vertex_group *grp, const cb_joint_error *joints, bool centred)
{
    double most = 0, sum = 0;
    const cb_group_joint *gj = g->joints + grp->joint_first, *end = gj + grp->joint_count;
    for (; gj < end; ++gj) { /* by pointer: an index took 5 instructions a joint to address */
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
