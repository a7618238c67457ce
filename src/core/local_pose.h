/* local_pose.h - the arithmetic of local rows (.pal version 6, docs/pal-format.md "Local rows"),
 * written once for the library's two users: the encoder and the C runtime (local_rows.c), and the
 * rate choice and the palette's measurement (local_rate.c). A bone's transform is a qpos:
 * v -> p + s rotate(q, v - b), b its bind position, p the image of b. */
#ifndef CB_LOCAL_POSE_H
#define CB_LOCAL_POSE_H

#include "cb_math.h"

typedef struct local_qpos {
    cb_quat q;
    cb_vec3 p;
    double s;
} local_qpos;

/* A global child in its global parent's frame (the parent's bind position bp), the spec's
 * conversion: q_L = conj(q_p) q_j, s_L = s_j / s_p, p_L = b_p + rotate(conj(q_p), p_j - p_p) / s_p. */
static inline local_qpos local_qpos_localize(local_qpos parent, cb_vec3 bp, local_qpos child)
{
    cb_quat inv = {-parent.q.x, -parent.q.y, -parent.q.z, parent.q.w};
    cb_vec3 d = cb_quat_rotate(inv, cb_vec3_sub(child.p, parent.p));
    double k = parent.s != 0 ? 1 / parent.s : 0;
    return (local_qpos){cb_quat_mul(inv, child.q), {bp.x + d.x * k, bp.y + d.y * k, bp.z + d.z * k}, child.s * k};
}

/* The parent's transform (about its bind position bp) after its child's local one: q_p q_L,
 * p_p + s_p rotate(q_p, p_L - b_p), s_p s_L. q is not normalised here. */
static inline local_qpos local_qpos_compose(local_qpos parent, cb_vec3 bp, local_qpos local)
{
    cb_vec3 d = cb_quat_rotate(parent.q, cb_vec3_sub(local.p, bp));
    return (local_qpos){cb_quat_mul(parent.q, local.q),
                        {parent.p.x + parent.s * d.x, parent.p.y + parent.s * d.y, parent.p.z + parent.s * d.z},
                        parent.s * local.s};
}

/* b blended into a by f as the runtime blends two rows: b's quaternion flipped into a's
 * hemisphere, every term a (1 - f) + b f, the quaternion normalised (nlerp). */
static inline local_qpos local_qpos_blend(local_qpos a, local_qpos b, double f)
{
    double x[8] = {a.q.x, a.q.y, a.q.z, a.q.w, a.p.x, a.p.y, a.p.z, a.s};
    double y[8] = {b.q.x, b.q.y, b.q.z, b.q.w, b.p.x, b.p.y, b.p.z, b.s};
    double sign = x[0] * y[0] + x[1] * y[1] + x[2] * y[2] + x[3] * y[3] < 0 ? -1 : 1;
    for (int k = 0; k < 8; ++k) x[k] = x[k] * (1 - f) + (k < 4 ? sign : 1) * y[k] * f;
    return (local_qpos){cb_quat_normalize((cb_quat){x[0], x[1], x[2], x[3]}), {x[4], x[5], x[6]}, x[7]};
}

#endif
