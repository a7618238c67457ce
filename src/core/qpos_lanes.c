/* qpos_lanes.c - what qpos takes of a pose's joint matrices (palette_rows.c's qpos_similarity:
 * the quaternion of each rotation and its scale), four joints at a time.
 *
 * A search's probes derive it once a pose and keep it with the pose (palette_probe_poses), but
 * each new pose still needs it for every joint: Cow's default bake derived 115 K joints, about
 * 260 instructions each, one at a time (30 M). Here four joints are the lanes of GCC's vector
 * types (lanes.h), and each lane runs qpos_similarity's, cb_mat4_determinant3's,
 * cb_quat_from_mat4's and cb_quat_normalize's operations in their order - Shepperd's four
 * cases by masks, each lane taking its own case's expression for the root and for every
 * component - so its values are the same bits (speed43f: 30 -> 14 M on Cow). Where any joint
 * is no similarity the pose is left to qpos_similarity, joint by joint, which says which and
 * why. The search only: a bake without a pose cache derives as before. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "cb_math.h"
#include "lanes.h" /* v4df, v4di */
#include "palette_bake.h"

#define QPOS_TOLERANCE_LANES 1e-4 /* palette_rows.c's QPOS_TOLERANCE */

#if defined(__GNUC__)
/* The quaternion of the rotation r (elements 0 .. 10 of four joint matrices, a lane each) as
 * cb_quat_from_mat4 then cb_quat_normalize make it, into q[0 .. 3] (x, y, z, w). */
static CB_CLONE_INLINE void quat_lanes(const v4df *r, v4df *q)
{
    const v4df one = CB_SPLAT4(1.0), zero = CB_SPLAT4(0.0);
    v4df m00 = r[0], m11 = r[5], m22 = r[10], trace = m00 + m11 + m22;
    v4di a = trace > zero, b = ~a & (m00 > m11) & (m00 > m22), c = ~a & ~b & (m11 > m22); /* else the last case */
    v4df root = CB_SELECT4(a, trace + one,
                     CB_SELECT4(b, one + m00 - m11 - m22, CB_SELECT4(c, one + m11 - m00 - m22, one + m22 - m00 - m11)));
    cb_sqrt4(&root);
    v4df s = root * CB_SPLAT4(2.0), inv = one / s, quarter = CB_SPLAT4(0.25) * s;
    v4df d69 = (r[6] - r[9]) * inv, d82 = (r[8] - r[2]) * inv, d14 = (r[1] - r[4]) * inv;
    v4df s41 = (r[4] + r[1]) * inv, s82 = (r[8] + r[2]) * inv, s96 = (r[9] + r[6]) * inv;
    v4df w = CB_SELECT4(a, quarter, CB_SELECT4(b, d69, CB_SELECT4(c, d82, d14)));
    v4df x = CB_SELECT4(a, d69, CB_SELECT4(b, quarter, CB_SELECT4(c, s41, s82)));
    v4df y = CB_SELECT4(a, d82, CB_SELECT4(b, s41, CB_SELECT4(c, quarter, s96)));
    v4df z = CB_SELECT4(a, d14, CB_SELECT4(b, s82, CB_SELECT4(c, s96, quarter)));
    v4df len2 = x * x + y * y + z * z + w * w, norm = len2;
    cb_sqrt4(&norm);
    norm = one / norm;
    v4di empty = len2 == zero;
    q[0] = CB_SELECT4(empty, zero, x * norm), q[1] = CB_SELECT4(empty, zero, y * norm), q[2] = CB_SELECT4(empty, zero, z * norm);
    q[3] = CB_SELECT4(empty, one, w * norm);
}

/* Joints j .. j + 3 (a short last pass repeats joint j in its spare lanes): false where one is
 * no similarity, else their quaternions and scales into q and s. */
static CB_CLONE_INLINE bool similarity4(const double *mats, uint32_t j, uint32_t n, v4df *q, v4df *s)
{
    const double *first = mats + (size_t)j * 16;
    const double *M[4] = {first, n > 1 ? first + 16 : first, n > 2 ? first + 32 : first, n > 3 ? first + 48 : first};
    v4df m[12]; /* elements 0 .. 11 of the four matrices: three 4x4 transposes of 32-byte loads */
#pragma GCC unroll 3
    for (int k = 0; k < 12; k += 4) {
        v4df rows[4];
        memcpy(&rows[0], M[0] + k, 32), memcpy(&rows[1], M[1] + k, 32), memcpy(&rows[2], M[2] + k, 32),
            memcpy(&rows[3], M[3] + k, 32);
        cb_transpose4(rows, m + k);
    }
    v4df l0 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2], l1 = m[4] * m[4] + m[5] * m[5] + m[6] * m[6];
    v4df l2 = m[8] * m[8] + m[9] * m[9] + m[10] * m[10];
    cb_sqrt4(&l0), cb_sqrt4(&l1), cb_sqrt4(&l2);
    *s = (l0 + l1 + l2) / CB_SPLAT4(3.0);
    v4df det = m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
               m[8] * (m[1] * m[6] - m[5] * m[2]);
    v4df d01 = m[0] * m[4] + m[1] * m[5] + m[2] * m[6], d02 = m[0] * m[8] + m[1] * m[9] + m[2] * m[10];
    v4df d12 = m[4] * m[8] + m[5] * m[9] + m[6] * m[10];
    v4df tol = CB_SPLAT4(QPOS_TOLERANCE_LANES) * *s, tol2 = tol * *s;
    v4di fails = (det <= CB_SPLAT4(0.0)) | (CB_ABS4(l0 - *s) > tol) | (CB_ABS4(l1 - *s) > tol) | (CB_ABS4(l2 - *s) > tol) |
                 (CB_ABS4(d01) > tol2) | (CB_ABS4(d02) > tol2) | (CB_ABS4(d12) > tol2);
    if (fails[0] | fails[1] | fails[2] | fails[3]) return false;
    v4df inv = CB_SPLAT4(1.0) / *s, r[11];
    for (int k = 0; k < 11; ++k) r[k] = m[k] * inv;
    quat_lanes(r, q);
    return true;
}
#endif

CB_TARGET_CLONES bool palette_qpos_similarity_pose(const double *mats, uint32_t bones, double *out)
{
#if defined(__GNUC__)
    for (uint32_t j = 0; j < bones; j += 4) {
        uint32_t n = bones - j < 4 ? bones - j : 4;
        v4df q[4], s;
        if (!similarity4(mats, j, n, q, &s)) return false;
        v4df per_joint[4]; /* lane i: joint j + i's quaternion */
        cb_transpose4(q, per_joint);
        for (uint32_t i = 0; i < n; ++i) {
            double *o = out + (size_t)(j + i) * 5;
            memcpy(o, &per_joint[i], sizeof per_joint[i]), o[4] = s[i];
        }
    }
    return true;
#else
    (void)mats, (void)bones, (void)out;
    return false; /* qpos_similarity, joint by joint */
#endif
}
