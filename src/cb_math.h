/* cb_math.h - small double-precision vector, quaternion and 4x4 matrix helpers.
 *
 * Matrices are column-major like glTF: m[col * 4 + row]; m[12..14] is the translation.
 * Quaternions are stored x, y, z, w like glTF.
 */
#ifndef CB_MATH_H
#define CB_MATH_H

#include <math.h>
#include <stdbool.h>

typedef struct { double x, y, z; } cb_vec3;
typedef struct { double x, y, z, w; } cb_quat;

void cb_mat4_identity(double out[16]);
/* out = a * b (out may alias neither a nor b). */
void cb_mat4_mul(double out[16], const double a[16], const double b[16]);
/* Affine multiply: assumes the last row of both is 0,0,0,1. */
void cb_mat4_mul_affine(double out[16], const double a[16], const double b[16]);
void cb_mat4_from_trs(double out[16], cb_vec3 t, cb_quat r, cb_vec3 s);
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

cb_quat cb_quat_normalize(cb_quat q);
cb_quat cb_quat_mul(cb_quat a, cb_quat b);
cb_quat cb_quat_conjugate(cb_quat q);
static inline double cb_quat_dot(cb_quat a, cb_quat b) { return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w; }
/* Spherical interpolation along the shorter arc; plain lerp for angles below 1e-6 rad. */
cb_quat cb_quat_slerp(cb_quat a, cb_quat b, double t);
cb_vec3 cb_quat_rotate(cb_quat q, cb_vec3 v);
/* Rotation quaternion of an orthonormal, right-handed 3x3 (upper-left of m). */
cb_quat cb_quat_from_mat4(const double m[16]);

static inline cb_vec3 cb_vec3_add(cb_vec3 a, cb_vec3 b) { cb_vec3 r = {a.x + b.x, a.y + b.y, a.z + b.z}; return r; }
static inline cb_vec3 cb_vec3_sub(cb_vec3 a, cb_vec3 b) { cb_vec3 r = {a.x - b.x, a.y - b.y, a.z - b.z}; return r; }
static inline cb_vec3 cb_vec3_scale(cb_vec3 a, double s) { cb_vec3 r = {a.x * s, a.y * s, a.z * s}; return r; }
static inline double cb_vec3_dot(cb_vec3 a, cb_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline double cb_vec3_length(cb_vec3 a) { return sqrt(cb_vec3_dot(a, a)); }

#endif
