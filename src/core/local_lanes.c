/* local_lanes.c - see local_lanes.h.
 *
 * Measuring local rows takes, at every point, every bone's blend of two local rows, its
 * composition with its parent's, its matrix and its difference from the exact one, then the
 * difference's bound terms: Husky's local bake did that at 4,016 points, 49 bones each, about
 * 700 instructions a bone one point at a time (the blends and compositions 61 M, the matrices
 * 19 M, the differences 31 M, their terms 24 M). Here four points are the lanes of GCC's vector types
 * (lanes.h), bone by bone in the skeleton's order, and each lane runs the scalar operations in
 * their order - local_qpos_blend's, cb_quat_normalize's, local_qpos_compose's (cb_quat_rotate's,
 * cb_quat_mul's), cb_mat4_from_trs's, the differences and cb_joint_error_terms's - so its values
 * are the same bits (measure_lanes.c does the same for global rows). Compilers without vector
 * types take the scalar functions one lane at a time. tests/lib/test_local_lanes.c holds the lanes
 * to the scalar operations, bit for bit. */
#include <math.h>
#include <string.h>

#include "cb_math.h"
#include "lanes.h"
#include "local_lanes.h"

_Static_assert(sizeof(local_qpos) == 8 * sizeof(double), "a local row's bone is 8 doubles: q, p, s");

static cb_vec3 bind_at(const float *bind, uint32_t j)
{
    return (cb_vec3){bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]};
}

#if defined(__GNUC__)
/* Bone j of four lanes' rows (8 doubles each: q, p, s) as lanes: v[k][l] = x[l][j]'s value k. */
static CB_CLONE_INLINE void load_bone4(const local_qpos *const *x, uint32_t j, v4df *v)
{
    const double *rows[4] = {(const double *)&x[0][j], (const double *)&x[1][j], (const double *)&x[2][j],
                             (const double *)&x[3][j]};
    load_lanes4(rows, 0, 8, v);
}

/* local_qpos_blend over four lanes, into x: y's quaternion flipped into x's hemisphere, every
 * term x (1 - f) + y f, the quaternion normalised. */
static CB_CLONE_INLINE void blend4(v4df *x, const v4df *y, const v4df *f)
{
    v4df dot = x[0] * y[0] + x[1] * y[1] + x[2] * y[2] + x[3] * y[3];
    v4df sign = CB_SELECT4(dot < CB_SPLAT4(0.0), CB_SPLAT4(-1.0), CB_SPLAT4(1.0)), keep = CB_SPLAT4(1.0) - *f, take = *f;
    #pragma GCC unroll 8
    for (int k = 0; k < 8; ++k) x[k] = x[k] * keep + (k < 4 ? sign * y[k] : y[k]) * take;
    cb_normalize4(x);
}

/* local_qpos_compose over four lanes: the parent's transform P (about its bind position bp)
 * after the local one L, into out (q not normalised). */
static CB_CLONE_INLINE void compose4(const v4df *P, cb_vec3 bp, const v4df *L, v4df *out)
{
    const v4df two = CB_SPLAT4(2.0);
    v4df qx = P[0], qy = P[1], qz = P[2], qw = P[3];
    v4df vx = L[4] - CB_SPLAT4(bp.x), vy = L[5] - CB_SPLAT4(bp.y), vz = L[6] - CB_SPLAT4(bp.z);
    v4df ux = qy * vz - qz * vy, uy = qz * vx - qx * vz, uz = qx * vy - qy * vx; /* cb_quat_rotate */
    v4df wx = qy * uz - qz * uy, wy = qz * ux - qx * uz, wz = qx * uy - qy * ux;
    v4df dx = vx + two * (qw * ux + wx), dy = vy + two * (qw * uy + wy), dz = vz + two * (qw * uz + wz);
    v4df bx = L[0], by = L[1], bz = L[2], bw = L[3]; /* cb_quat_mul(P.q, L.q) */
    out[0] = qw * bx + qx * bw + qy * bz - qz * by;
    out[1] = qw * by - qx * bz + qy * bw + qz * bx;
    out[2] = qw * bz + qx * by - qy * bx + qz * bw;
    out[3] = qw * bw - qx * bx - qy * by - qz * bz;
    out[4] = P[4] + P[7] * dx, out[5] = P[5] + P[7] * dy, out[6] = P[6] + P[7] * dz;
    out[7] = P[7] * L[7];
}

/* A row's matrix over four lanes (local_rate.c's qpos_matrix): cb_mat4_from_trs of its q and s,
 * the translation p - A b. */
static CB_CLONE_INLINE void matrix4(const v4df *r, cb_vec3 b, v4df *m)
{
    trs4(r + 4, r, &r[7], m); /* t = p for now */
    const v4df x = CB_SPLAT4(b.x), y = CB_SPLAT4(b.y), z = CB_SPLAT4(b.z);
    m[12] = r[4] - (m[0] * x + m[4] * y + m[8] * z);
    m[13] = r[5] - (m[1] * x + m[5] * y + m[9] * z);
    m[14] = r[6] - (m[2] * x + m[6] * y + m[10] * z);
}

CB_TARGET_CLONES
void local_points4(const local_skeleton *k, const float *compose_bind, const float *bind, const double *reach,
                   const local_qpos *const a[4], const local_qpos *const b[4], const double f[4],
                   const double *const *mats, const local_qpos *const exact[4], double *composed, double *diff,
                   cb_joint_error *joints, bool finite[4])
{
    v4df *out = (v4df *)composed, fraction;
    memcpy(&fraction, f, sizeof fraction);
    size_t stride = (size_t)k->bones * 16;
    bool ok[4] = {true, true, true, true};
    for (uint32_t i = 0; i < k->bones; ++i) {
        uint32_t j = k->order[i];
        int32_t p = k->parent[j];
        v4df x[8], y[8], *c = out + (size_t)j * 8;
        load_bone4(a, j, x), load_bone4(b, j, y);
        blend4(x, y, &fraction);
        if (p < 0) memcpy(c, x, sizeof x); /* parents come first in k->order: out[p] is composed */
        else compose4(out + (size_t)p * 8, bind_at(compose_bind, (uint32_t)p), x, c);
        cb_normalize4(c);
        if (reach[j] < 0) { /* it moves no vertex: no group reads its difference (its children are composed) */
            for (int l = 0; l < 4; ++l) {
                double *d = diff + l * stride + (size_t)j * 16;
                memset(d, 0, 16 * sizeof *d);
                joints[(size_t)l * k->bones + j] = (cb_joint_error){0, 0, 0, 0, d};
            }
            continue;
        }
        cb_vec3 bj = bind_at(bind, j);
        v4df m[15], e[16], d[12];
        matrix4(c, bj, m);
        if (mats) {
            load_lanes4(mats, (size_t)j * 16, 16, e);
        } else {
            v4df r[8];
            load_bone4(exact, j, r);
            matrix4(r, bj, e);
        }
        #pragma GCC unroll 16
        for (int col = 0; col < 4; ++col)
            for (int row = 0; row < 3; ++row) d[3 * col + row] = e[4 * col + row] - m[4 * col + row];
        store_differences4(d, diff + (size_t)j * 16, stride);
        v4df t[4], sum;
        joint_error_terms4(d, bj.x, bj.y, bj.z, sqrt(bj.x * bj.x + bj.y * bj.y + bj.z * bj.z), t, &sum);
        for (int l = 0; l < 4; ++l) {
            double *dl = diff + l * stride + (size_t)j * 16;
            joints[(size_t)l * k->bones + j] = (cb_joint_error){t[0][l], t[1][l], t[2][l], t[3][l], dl};
            ok[l] &= isfinite(sum[l]);
        }
    }
    memcpy(finite, ok, sizeof ok);
}
#else
/* The scalar operations, one lane at a time. */
static void qpos_matrix(const local_qpos *r, cb_vec3 b, double m[16])
{
    cb_mat4_from_trs(m, (cb_vec3){0, 0, 0}, r->q, (cb_vec3){r->s, r->s, r->s});
    cb_vec3 rb = cb_mat4_transform_dir(m, b);
    m[12] = r->p.x - rb.x, m[13] = r->p.y - rb.y, m[14] = r->p.z - rb.z;
}

void local_points4(const local_skeleton *k, const float *compose_bind, const float *bind, const double *reach,
                   const local_qpos *const a[4], const local_qpos *const b[4], const double f[4],
                   const double *const *mats, const local_qpos *const exact[4], double *composed, double *diff,
                   cb_joint_error *joints, bool finite[4])
{
    local_qpos *out = (local_qpos *)composed;
    for (int l = 0; l < 4; ++l) {
        double *dl = diff + (size_t)l * k->bones * 16;
        for (uint32_t i = 0; i < k->bones; ++i) {
            uint32_t j = k->order[i];
            int32_t p = k->parent[j];
            local_qpos x = local_qpos_blend(a[l][j], b[l][j], f[l]);
            out[j] = p < 0 ? x : local_qpos_compose(out[p], bind_at(compose_bind, (uint32_t)p), x);
            out[j].q = cb_quat_normalize(out[j].q);
        }
        for (uint32_t j = 0; j < k->bones; ++j) {
            double e[16], m[16];
            memset(dl + 16 * (size_t)j, 0, 16 * sizeof(double));
            if (reach[j] < 0) continue;
            if (mats) memcpy(e, mats[l] + 16 * (size_t)j, sizeof e);
            else qpos_matrix(&exact[l][j], bind_at(bind, j), e);
            qpos_matrix(&out[j], bind_at(bind, j), m);
            for (int n = 0; n < 16; ++n) dl[j * 16 + n] = e[n] - m[n];
        }
        finite[l] = cb_joint_errors(dl, k->bones, bind, joints + (size_t)l * k->bones);
    }
}
#endif
