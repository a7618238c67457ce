/* leg_ik.c - analytic two-bone IK (leg_ik.h). */
#include "leg_ik.h"

static cb_vec3 cross(cb_vec3 a, cb_vec3 b) { return (cb_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

static cb_vec3 unit(cb_vec3 v)
{
    double n = cb_vec3_length(v);
    return n > 0 ? cb_vec3_scale(v, 1 / n) : v;
}

/* v with its part along the unit direction u taken off. */
static cb_vec3 across(cb_vec3 v, cb_vec3 u) { return cb_vec3_sub(v, cb_vec3_scale(u, cb_vec3_dot(v, u))); }

cb_quat leg_ik_turn(cb_vec3 u, cb_vec3 v)
{
    u = unit(u), v = unit(v);
    double d = cb_vec3_dot(u, v);
    if (d < -1 + 1e-12) { /* opposite: half a turn about any axis across u */
        cb_vec3 axis = unit(cross(u, fabs(u.x) < 0.9 ? (cb_vec3){1, 0, 0} : (cb_vec3){0, 1, 0}));
        return (cb_quat){axis.x, axis.y, axis.z, 0};
    }
    cb_vec3 w = cross(u, v);
    return cb_quat_normalize((cb_quat){w.x, w.y, w.z, 1 + d});
}

static double clamp(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

/* The turn about the unit axis t that takes p to q (both across t). */
static cb_quat turn_about(cb_vec3 t, cb_vec3 p, cb_vec3 q)
{
    double half = 0.5 * atan2(cb_vec3_dot(cross(p, q), t), cb_vec3_dot(p, q)), s = sin(half);
    return (cb_quat){t.x * s, t.y * s, t.z * s, cos(half)};
}

/* The knee's side in the new plane: of the planes that hold the hip-target line t, the one whose
 * normal is nearest the old plane's normal n (n with its part along t taken off), so the plane
 * turns by exactly the angle the target leaves it, and not at all for a target in it. A target
 * straight across the old plane leaves no nearest plane: the old side, taken across t, then. */
static cb_vec3 new_side(cb_vec3 n, cb_vec3 m, cb_vec3 t)
{
    cb_vec3 kept = across(n, t);
    if (cb_vec3_length(kept) > 1e-9) return unit(cross(kept, t));
    return unit(across(m, t));
}

cb_vec3 leg_ik_solve(cb_vec3 a, cb_vec3 b, cb_vec3 c, cb_vec3 target, cb_vec3 pole, cb_quat *hip, cb_quat *knee)
{
    double l1 = cb_vec3_length(cb_vec3_sub(b, a)), l2 = cb_vec3_length(cb_vec3_sub(c, b));
    cb_vec3 ac = cb_vec3_sub(c, a), at = cb_vec3_sub(target, a);
    double d = cb_vec3_length(ac);
    *hip = *knee = (cb_quat){0, 0, 0, 1};
    if (!(l1 > 0) || !(l2 > 0) || !(d > 0) || !(cb_vec3_length(at) > 0)) return c;
    /* The reach kept a hair inside straight and folded: at the limits the knee's angle changes
     * fastest with the reach (a pop), and its plane is undefined. */
    double slack = 1e-4 * (l1 + l2), reach = clamp(cb_vec3_length(at), fabs(l1 - l2) + slack, l1 + l2 - slack);
    cb_vec3 u = cb_vec3_scale(ac, 1 / d), t = unit(at);
    /* The knee's side of the hip-ankle line, in the plane it bends in (u, m; normal n). */
    cb_vec3 ab = cb_vec3_sub(b, a), side = across(ab, u);
    if (cb_vec3_length(side) < 1e-9 * l1) side = across(pole, u);
    cb_vec3 m = unit(side), n = cross(u, m);
    /* The bend in the old plane: the hip's angle to the ankle for the new reach (law of cosines). */
    double cos_hip = clamp((l1 * l1 + reach * reach - l2 * l2) / (2 * l1 * reach), -1, 1);
    double sin_hip = sqrt(1 - cos_hip * cos_hip);
    cb_vec3 b1 = cb_vec3_add(a, cb_vec3_add(cb_vec3_scale(u, l1 * cos_hip), cb_vec3_scale(m, l1 * sin_hip)));
    cb_vec3 c1 = cb_vec3_add(a, cb_vec3_scale(u, reach));
    cb_quat bend_hip = leg_ik_turn(ab, cb_vec3_sub(b1, a));
    cb_quat bend_knee = leg_ik_turn(cb_quat_rotate(bend_hip, cb_vec3_sub(c, b)), cb_vec3_sub(c1, b1));
    /* The swing: the bent chain's plane (u, m) carried onto the new one (t, its side): u onto t
     * by the shortest turn, then about t until the side is the new plane's. */
    cb_quat onto = leg_ik_turn(u, t);
    cb_quat swing = cb_quat_normalize(cb_quat_mul(turn_about(t, cb_quat_rotate(onto, m), new_side(n, m, t)), onto));
    *hip = cb_quat_normalize(cb_quat_mul(swing, bend_hip));
    *knee = cb_quat_normalize(cb_quat_mul(swing, cb_quat_mul(bend_knee, cb_quat_normalize((cb_quat){-swing.x, -swing.y, -swing.z, swing.w}))));
    return cb_vec3_add(a, cb_vec3_scale(t, reach));
}
