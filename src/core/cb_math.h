/* cb_math.h - small double-precision vector, quaternion and 4x4 matrix helpers.
 *
 * Matrices are column-major like glTF: m[col * 4 + row]; m[12..14] is the translation.
 * Quaternions are stored x, y, z, w like glTF.
 */
#ifndef CB_MATH_H
#define CB_MATH_H

#include <math.h>
#include <stdbool.h>

/* Hot loops written to vectorize are compiled twice, for AVX2 and for the x86-64 baseline
 * (SSE2), and the loader picks one for the CPU. Both run the same IEEE operations in the same
 * order (no FMA: contraction is off and AVX2 does not imply FMA), so the output is the same
 * bits on every machine. CB_CLONE_INLINE makes a helper part of each copy. GCC only: clang 14
 * gives the dispatcher another name than the one callers link to. CB_GENERIC_ONLY compiles the
 * baseline alone: `make generic` builds a crowdbake that never takes the AVX2 path, which
 * tests/tools/hermetic.py holds to the same bytes (the loader's choice cannot be steered from a
 * run's options without global state: the ifunc resolver runs before main). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && !defined(CB_GENERIC_ONLY)
#define CB_TARGET_CLONES __attribute__((target_clones("avx2", "default")))
#define CB_CLONE_INLINE inline __attribute__((always_inline))
#define CB_CLONES 1 /* an AVX2 copy exists: code that dispatches by hand (fit.c) takes it too */
#else
#define CB_TARGET_CLONES
#define CB_CLONE_INLINE inline
#define CB_CLONES 0
#endif

typedef struct { double x, y, z; } cb_vec3;
typedef struct { double x, y, z, w; } cb_quat;

void cb_mat4_identity(double out[16]);
/* out = a * b (out may alias neither a nor b). */
void cb_mat4_mul(double out[16], const double a[16], const double b[16]);
/* Affine multiply: assumes the last row of both is 0,0,0,1. Inline, as is cb_mat4_from_trs:
 * both run for every joint of every frame (the matrix sampler, qpos rows to matrices). */
static inline void cb_mat4_mul_affine(double out[16], const double a[16], const double b[16])
{
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 3; ++r)
            out[c * 4 + r] = a[r] * b[c * 4] + a[4 + r] * b[c * 4 + 1] + a[8 + r] * b[c * 4 + 2];
        out[c * 4 + 3] = 0.0;
    }
    out[12] += a[12];
    out[13] += a[13];
    out[14] += a[14];
    out[15] = 1.0;
}

/* The matrix of translation t, rotation r (a unit quaternion) and scale s; writes all 16. */
static inline void cb_mat4_from_trs(double m[16], cb_vec3 t, cb_quat q, cb_vec3 s)
{
    double x = q.x, y = q.y, z = q.z, w = q.w;
    double xx = x * x, yy = y * y, zz = z * z;
    double xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
    m[0] = (1 - 2 * (yy + zz)) * s.x;
    m[1] = (2 * (xy + wz)) * s.x;
    m[2] = (2 * (xz - wy)) * s.x;
    m[3] = 0;
    m[4] = (2 * (xy - wz)) * s.y;
    m[5] = (1 - 2 * (xx + zz)) * s.y;
    m[6] = (2 * (yz + wx)) * s.y;
    m[7] = 0;
    m[8] = (2 * (xz + wy)) * s.z;
    m[9] = (2 * (yz - wx)) * s.z;
    m[10] = (1 - 2 * (xx + yy)) * s.z;
    m[11] = 0;
    m[12] = t.x;
    m[13] = t.y;
    m[14] = t.z;
    m[15] = 1;
}
static inline cb_vec3 cb_mat4_transform_point(const double m[16], cb_vec3 p)
{
    cb_vec3 r = {m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12], m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
                 m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]};
    return r;
}

static inline cb_vec3 cb_mat4_transform_dir(const double m[16], cb_vec3 d)
{
    cb_vec3 r = {m[0] * d.x + m[4] * d.y + m[8] * d.z, m[1] * d.x + m[5] * d.y + m[9] * d.z,
                 m[2] * d.x + m[6] * d.y + m[10] * d.z};
    return r;
}
/* Splits an affine matrix into translation, rotation and (signed) scale.
 * Returns false when the upper 3x3 has shear beyond `tolerance` (relative). */
bool cb_mat4_decompose(const double m[16], cb_vec3 *t, cb_quat *r, cb_vec3 *s, double tolerance);
double cb_mat4_determinant3(const double m[16]);

/* a * b: rotation by b, then by a. Inline: the similarity sampler's inner loop. */
static inline cb_quat cb_quat_mul(cb_quat a, cb_quat b)
{
    cb_quat r = {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                 a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
    return r;
}
static inline double cb_quat_dot(cb_quat a, cb_quat b) { return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w; }

static inline cb_quat cb_quat_normalize(cb_quat q)
{
    double len2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
    if (len2 == 0) {
        cb_quat id = {0, 0, 0, 1};
        return id;
    }
    double inv = 1 / sqrt(len2);
    cb_quat r = {q.x * inv, q.y * inv, q.z * inv, q.w * inv};
    return r;
}

/* sin(x) for 0 <= x < 0.21 by its Taylor series to x^7: the next term is below 2e-12, far
 * under float32 key precision; libm's sin costs several times more. */
static inline double cb_small_sin(double x)
{
    double x2 = x * x;
    return x * (1 - x2 * (1.0 / 6) * (1 - x2 * (1.0 / 20) * (1 - x2 * (1.0 / 42))));
}

/* asin(x) for 0 <= x < 0.1 by its series to x^9 (next term below 3e-13). */
static inline double cb_small_asin(double x)
{
    double x2 = x * x;
    return x * (1 + x2 * (1.0 / 6 + x2 * (3.0 / 40 + x2 * (15.0 / 336 + x2 * (105.0 / 3456)))));
}

/* Spherical interpolation along the shorter arc; plain lerp for angles below 1e-6 rad. Inline,
 * with what it calls: the sampler's inner loop, a chain of sqrt and division latencies that
 * the compiler interleaves across joints only when it sees them. */
static inline cb_quat cb_quat_slerp(cb_quat a, cb_quat b, double t)
{
    double d = cb_quat_dot(a, b);
    double sign = copysign(1.0, d); /* the shorter arc; branch-free, as the sign is unpredictable */
    d *= sign;
    b.x *= sign, b.y *= sign, b.z *= sign, b.w *= sign;
    double wa, wb;
    /* The angle from its sine (|a - b| = 2 sin(angle / 2)) is accurate where acos(d) is not. */
    double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z, dw = a.w - b.w;
    double half_chord = 0.5 * sqrt(dx * dx + dy * dy + dz * dz + dw * dw);
    double angle = half_chord < 0.1 ? 2 * cb_small_asin(half_chord) : acos(d > 1.0 ? 1.0 : d);
    /* The weights sin((1 - t) angle) / sin(angle) and sin(t angle) / sin(angle) without their
     * common divisor: the result is normalized below anyway. */
    if (angle < 1e-6) {
        wa = 1 - t;
        wb = t;
    } else if (half_chord < 0.1) { /* angle < 0.2003 */
        wa = cb_small_sin((1 - t) * angle);
        wb = cb_small_sin(t * angle);
    } else {
        wa = sin((1 - t) * angle);
        wb = sin(t * angle);
    }
    cb_quat r = {wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z, wa * a.w + wb * b.w};
    return cb_quat_normalize(r);
}

/* v rotated by the unit quaternion q: v + 2w(u x v) + 2 u x (u x v), u = q.xyz. */
static inline cb_vec3 cb_quat_rotate(cb_quat q, cb_vec3 v)
{
    cb_vec3 uv = {q.y * v.z - q.z * v.y, q.z * v.x - q.x * v.z, q.x * v.y - q.y * v.x};
    cb_vec3 uuv = {q.y * uv.z - q.z * uv.y, q.z * uv.x - q.x * uv.z, q.x * uv.y - q.y * uv.x};
    cb_vec3 r = {v.x + 2 * (q.w * uv.x + uuv.x), v.y + 2 * (q.w * uv.y + uuv.y), v.z + 2 * (q.w * uv.z + uuv.z)};
    return r;
}
/* Rotation quaternion of an orthonormal, right-handed 3x3 (upper-left of m). */
cb_quat cb_quat_from_mat4(const double m[16]);

static inline cb_vec3 cb_vec3_add(cb_vec3 a, cb_vec3 b) { cb_vec3 r = {a.x + b.x, a.y + b.y, a.z + b.z}; return r; }
static inline cb_vec3 cb_vec3_sub(cb_vec3 a, cb_vec3 b) { cb_vec3 r = {a.x - b.x, a.y - b.y, a.z - b.z}; return r; }
static inline cb_vec3 cb_vec3_scale(cb_vec3 a, double s) { cb_vec3 r = {a.x * s, a.y * s, a.z * s}; return r; }
static inline double cb_vec3_dot(cb_vec3 a, cb_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline double cb_vec3_length(cb_vec3 a) { return sqrt(cb_vec3_dot(a, a)); }

#endif
