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

void cb_mat4_mul_affine(double out[16], const double a[16], const double b[16])
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

void cb_mat4_from_trs(double m[16], cb_vec3 t, cb_quat q, cb_vec3 s)
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

cb_quat cb_quat_normalize(cb_quat q)
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

cb_quat cb_quat_mul(cb_quat a, cb_quat b)
{
    cb_quat r = {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                 a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
    return r;
}

cb_quat cb_quat_conjugate(cb_quat q)
{
    cb_quat r = {-q.x, -q.y, -q.z, q.w};
    return r;
}


/* sin(x) for 0 <= x < 0.21 by its Taylor series to x^7: the next term is below 2e-12, far
 * under float32 key precision; libm's sin costs several times more. */
static double small_sin(double x)
{
    double x2 = x * x;
    return x * (1 - x2 * (1.0 / 6) * (1 - x2 * (1.0 / 20) * (1 - x2 * (1.0 / 42))));
}

/* asin(x) for 0 <= x < 0.1 by its series to x^9 (next term below 3e-13). */
static double small_asin(double x)
{
    double x2 = x * x;
    return x * (1 + x2 * (1.0 / 6 + x2 * (3.0 / 40 + x2 * (15.0 / 336 + x2 * (105.0 / 3456)))));
}

cb_quat cb_quat_slerp(cb_quat a, cb_quat b, double t)
{
    double d = cb_quat_dot(a, b);
    if (d < 0) { /* shorter arc */
        d = -d;
        b.x = -b.x;
        b.y = -b.y;
        b.z = -b.z;
        b.w = -b.w;
    }
    double wa, wb;
    /* The angle from its sine (|a - b| = 2 sin(angle / 2)) is accurate where acos(d) is not. */
    double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z, dw = a.w - b.w;
    double half_chord = 0.5 * sqrt(dx * dx + dy * dy + dz * dz + dw * dw);
    double angle = half_chord < 0.1 ? 2 * small_asin(half_chord) : acos(d > 1.0 ? 1.0 : d);
    if (angle < 1e-6) {
        wa = 1 - t;
        wb = t;
    } else if (half_chord < 0.1) { /* angle < 0.2003 */
        double inv = 1 / small_sin(angle);
        wa = small_sin((1 - t) * angle) * inv;
        wb = small_sin(t * angle) * inv;
    } else {
        double inv = 1 / sin(angle);
        wa = sin((1 - t) * angle) * inv;
        wb = sin(t * angle) * inv;
    }
    cb_quat r = {wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z, wa * a.w + wb * b.w};
    return cb_quat_normalize(r);
}

cb_vec3 cb_quat_rotate(cb_quat q, cb_vec3 v)
{
    /* v + 2w(u x v) + 2 u x (u x v), u = q.xyz */
    cb_vec3 u = {q.x, q.y, q.z};
    cb_vec3 uv = {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    cb_vec3 uuv = {u.y * uv.z - u.z * uv.y, u.z * uv.x - u.x * uv.z, u.x * uv.y - u.y * uv.x};
    cb_vec3 r = {v.x + 2 * (q.w * uv.x + uuv.x), v.y + 2 * (q.w * uv.y + uuv.y), v.z + 2 * (q.w * uv.z + uuv.z)};
    return r;
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
