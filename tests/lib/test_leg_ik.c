/* test_leg_ik.c - the two-bone leg solve (src/core/leg_ik.h) against geometry worked by hand:
 * the ankle reaches the target, both bones keep their lengths, and the knee keeps its plane. A
 * target in the leg's plane leaves the plane where it was; one off it turns the plane by the
 * angle the hip-target line leaves it (asin of its part along the old normal), no more. The
 * shortest swing of the whole bent chain (the solve before) turns it further when the target
 * also moves within the plane (6.16 deg against 5.94 in the second case below). */
#include "testutil.h"

#include <math.h>

#include "../../src/core/leg_ik.h"

static const double DEG = 57.29577951308232;

static cb_vec3 v3(double x, double y, double z) { return (cb_vec3){x, y, z}; }

static cb_vec3 cross(cb_vec3 a, cb_vec3 b) { return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }

static cb_vec3 unit(cb_vec3 v) { return cb_vec3_scale(v, 1 / cb_vec3_length(v)); }

/* The chain after the solve: the knee and the ankle moved by the turns it returns. */
typedef struct solved {
    cb_vec3 knee, ankle, reached;
} solved;

static solved solve(cb_vec3 a, cb_vec3 b, cb_vec3 c, cb_vec3 target, cb_vec3 pole)
{
    cb_quat hip, knee;
    solved s;
    s.reached = leg_ik_solve(a, b, c, target, pole, &hip, &knee);
    s.knee = cb_vec3_add(a, cb_quat_rotate(hip, cb_vec3_sub(b, a)));
    s.ankle = cb_vec3_add(s.knee, cb_quat_rotate(cb_quat_mul(knee, hip), cb_vec3_sub(c, b)));
    return s;
}

/* The angle between the planes of (a, b, c) and (a, b', c'), degrees. */
static double plane_turn(cb_vec3 a, cb_vec3 b, cb_vec3 c, solved s)
{
    cb_vec3 n0 = unit(cross(cb_vec3_sub(b, a), cb_vec3_sub(c, a)));
    cb_vec3 n1 = unit(cross(cb_vec3_sub(s.knee, a), cb_vec3_sub(s.ankle, a)));
    return atan2(cb_vec3_length(cross(n0, n1)), fabs(cb_vec3_dot(n0, n1))) * DEG; /* exact near 0, as acos is not */
}

/* Lengths kept, the ankle on the target (when in reach) and at the place returned. */
static void assert_chain(cb_vec3 a, cb_vec3 b, cb_vec3 c, cb_vec3 target, solved s)
{
    assert_float_equal(cb_vec3_length(cb_vec3_sub(s.knee, a)), cb_vec3_length(cb_vec3_sub(b, a)), 1e-12);
    assert_float_equal(cb_vec3_length(cb_vec3_sub(s.ankle, s.knee)), cb_vec3_length(cb_vec3_sub(c, b)), 1e-12);
    assert_true(cb_vec3_length(cb_vec3_sub(s.ankle, s.reached)) < 1e-12);
    assert_true(cb_vec3_length(cb_vec3_sub(s.ankle, target)) < 1e-12);
}

/* A leg hanging from the hip at the origin, its knee bent forward (+z) in the plane x = 0. */
static const cb_vec3 HIP = {0, 0, 0}, KNEE = {0, -0.5, 0.2}, ANKLE = {0, -1.0, 0.05}, FORWARD = {0, 0, 1};

static void test_target_in_the_plane(void **state)
{
    (void)state;
    /* Back and up along the leg's own plane: the plane stays exactly, the knee stays in front. */
    cb_vec3 target = v3(0, -0.8, -0.35);
    solved s = solve(HIP, KNEE, ANKLE, target, FORWARD);
    assert_chain(HIP, KNEE, ANKLE, target, s);
    assert_true(fabs(s.knee.x) < 1e-12 && fabs(s.ankle.x) < 1e-12);
    assert_true(plane_turn(HIP, KNEE, ANKLE, s) < 1e-9);
    /* The knee on the side it bent to: in front of the hip-target line. */
    cb_vec3 t = unit(target), side = cb_vec3_sub(s.knee, cb_vec3_scale(t, cb_vec3_dot(s.knee, t)));
    assert_true(cb_vec3_dot(cross(t, side), v3(1, 0, 0)) * cb_vec3_dot(cross(unit(ANKLE), KNEE), v3(1, 0, 0)) > 0);
}

static void test_target_off_the_plane(void **state)
{
    (void)state;
    /* Back along the plane and out to the side: the plane turns by the angle the target leaves
     * it, asin(0.1 / |t|) (the old normal is x). */
    cb_vec3 target = v3(0.1, -0.85, -0.45);
    solved s = solve(HIP, KNEE, ANKLE, target, FORWARD);
    assert_chain(HIP, KNEE, ANKLE, target, s);
    double leaves = asin(0.1 / cb_vec3_length(target)) * DEG, turn = plane_turn(HIP, KNEE, ANKLE, s);
    print_message("target %.3f deg off the plane: the plane turns %.6f deg\n", leaves, turn);
    assert_float_equal(turn, leaves, 1e-9);
    /* Straight out to the side (no in-plane move): the same rule. */
    target = v3(0.05, -1.0, 0.05);
    s = solve(HIP, KNEE, ANKLE, target, FORWARD);
    assert_chain(HIP, KNEE, ANKLE, target, s);
    assert_float_equal(plane_turn(HIP, KNEE, ANKLE, s), asin(0.05 / cb_vec3_length(target)) * DEG, 1e-9);
}

static void test_straight_leg_and_reach(void **state)
{
    (void)state;
    /* A straight leg bends in the plane that holds the pole, its knee toward it. */
    cb_vec3 knee = v3(0, -0.5, 0), ankle = v3(0, -1, 0), target = v3(0, -0.9, 0);
    solved s = solve(HIP, knee, ankle, target, FORWARD);
    assert_chain(HIP, knee, ankle, target, s);
    assert_true(fabs(s.knee.x) < 1e-12 && s.knee.z > 0);
    /* Past the straight leg: met as nearly as the chain allows, along the hip-target line. */
    target = v3(0, -1.5, -0.5);
    s = solve(HIP, KNEE, ANKLE, target, FORWARD);
    double reach = cb_vec3_length(s.reached);
    assert_true(reach < cb_vec3_length(KNEE) + cb_vec3_length(cb_vec3_sub(ANKLE, KNEE)));
    assert_true(cb_vec3_length(cb_vec3_sub(cb_vec3_scale(unit(target), reach), s.reached)) < 1e-12);
    assert_true(cb_vec3_length(cb_vec3_sub(s.ankle, s.reached)) < 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_target_in_the_plane),
        cmocka_unit_test(test_target_off_the_plane),
        cmocka_unit_test(test_straight_leg_and_reach),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
