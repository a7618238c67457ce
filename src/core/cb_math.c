/* cb_math.c - see cb_math.h. */
#include "cb_math.h"

#include <math.h>
#include <string.h>

void cb_mat4_identity(double out[16])
{
    memset(out, 0, 16 * sizeof(double));
    out[0] = out[5] = out[10] = out[15] = 1.0;
}

void cb_mat4_mul(double out[16], const double a[16], const double b[16])
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            out[c * 4 + r] = a[0 * 4 + r] * b[c * 4 + 0] + a[1 * 4 + r] * b[c * 4 + 1] +
                             a[2 * 4 + r] * b[c * 4 + 2] + a[3 * 4 + r] * b[c * 4 + 3];
}

double cb_mat4_determinant3(const double m[16])
{
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
           m[8] * (m[1] * m[6] - m[5] * m[2]);
}


bool cb_mat4_decompose(const double m[16], cb_vec3 *t, cb_quat *r, cb_vec3 *s, double tolerance)
{
    cb_vec3 c0 = {m[0], m[1], m[2]}, c1 = {m[4], m[5], m[6]}, c2 = {m[8], m[9], m[10]};
    cb_vec3 scale = {cb_vec3_length(c0), cb_vec3_length(c1), cb_vec3_length(c2)};
    if (cb_mat4_determinant3(m) < 0) scale.x = -scale.x; /* one axis carries the mirror */
    t->x = m[12];
    t->y = m[13];
    t->z = m[14];
    *s = scale;
    if (scale.x == 0 || scale.y == 0 || scale.z == 0) {
        r->x = r->y = r->z = 0;
        r->w = 1;
        return false;
    }
    double rot[16];
    memcpy(rot, m, sizeof rot);
    for (int i = 0; i < 3; ++i) {
        rot[0 + i] /= scale.x;
        rot[4 + i] /= scale.y;
        rot[8 + i] /= scale.z;
    }
    *r = cb_quat_from_mat4(rot);
    /* Shear shows up as non-orthogonal columns. */
    cb_vec3 r0 = {rot[0], rot[1], rot[2]}, r1 = {rot[4], rot[5], rot[6]}, r2 = {rot[8], rot[9], rot[10]};
    return fabs(cb_vec3_dot(r0, r1)) <= tolerance && fabs(cb_vec3_dot(r0, r2)) <= tolerance &&
           fabs(cb_vec3_dot(r1, r2)) <= tolerance;
}

cb_quat cb_quat_from_mat4(const double m[16])
{
    /* Shepperd's method: pick the largest diagonal term for stability. */
    double m00 = m[0], m11 = m[5], m22 = m[10];
    double trace = m00 + m11 + m22;
    cb_quat q;
    if (trace > 0) {
        double s = sqrt(trace + 1.0) * 2, inv = 1 / s;
        q.w = 0.25 * s;
        q.x = (m[6] - m[9]) * inv;
        q.y = (m[8] - m[2]) * inv;
        q.z = (m[1] - m[4]) * inv;
    } else if (m00 > m11 && m00 > m22) {
        double s = sqrt(1.0 + m00 - m11 - m22) * 2, inv = 1 / s;
        q.w = (m[6] - m[9]) * inv;
        q.x = 0.25 * s;
        q.y = (m[4] + m[1]) * inv;
        q.z = (m[8] + m[2]) * inv;
    } else if (m11 > m22) {
        double s = sqrt(1.0 + m11 - m00 - m22) * 2, inv = 1 / s;
        q.w = (m[8] - m[2]) * inv;
        q.x = (m[4] + m[1]) * inv;
        q.y = 0.25 * s;
        q.z = (m[9] + m[6]) * inv;
    } else {
        double s = sqrt(1.0 + m22 - m00 - m11) * 2, inv = 1 / s;
        q.w = (m[1] - m[4]) * inv;
        q.x = (m[8] + m[2]) * inv;
        q.y = (m[9] + m[6]) * inv;
        q.z = 0.25 * s;
    }
    return cb_quat_normalize(q);
}
