/* test_samples.c - the generated sample animals: what they hold, that the gait really moves
 * the feet, and that the Khronos glTF validator finds no error in them. */
#include "testutil.h"

#include <math.h>

static cb_model *load_sample(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.glb", samples_dir(), name);
    return load_or_fail(path);
}

static int find_joint(const cb_model *m, const char *name)
{
    for (uint32_t j = 0; j < m->skins[0].joint_count; ++j)
        if (strcmp(m->nodes[m->skins[0].joints[j]].name, name) == 0) return (int)j;
    fail_msg("no joint %s", name);
    return -1;
}

static void test_quadruped_rig_and_clips(void **state)
{
    (void)state;
    cb_model *m = load_sample("quadruped");
    assert_true(m->skins[0].joint_count >= 40);
    const char *clips[] = {"idle", "walk", "run", "eat", "death"};
    for (int i = 0; i < 5; ++i) assert_true(cb_model_find_animation(m, clips[i]) >= 0);
    cb_model_free(m);
    m = load_sample("fish");
    assert_true(cb_model_find_animation(m, "swim") >= 0);
    assert_true(m->skins[0].joint_count >= 8);
    cb_model_free(m);
    m = load_sample("bird");
    assert_true(cb_model_find_animation(m, "flap") >= 0 && cb_model_find_animation(m, "glide") >= 0);
    find_joint(m, "wing_tip_l");
    cb_model_free(m);
}

/* Height of a foot joint above the root, and its forward position relative to the root. */
static void foot_position(cb_sampler *s, const cb_model *m, int clip, double t, int joint, double *up, double *fwd)
{
    const double *g = cb_sample_globals(s, clip, t);
    const double *f = g + (size_t)m->skins[0].joints[joint] * 16, *r = g + (size_t)m->skins[0].joints[0] * 16;
    *up = f[13] - r[13];
    *fwd = f[14] - r[14];
}

static void test_walk_and_run_move_the_feet_in_a_diagonal_gait(void **state)
{
    (void)state;
    cb_model *m = load_sample("quadruped");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    int lf = find_joint(m, "front_l_foot"), rf = find_joint(m, "front_r_foot"), rh = find_joint(m, "hind_r_foot");
    const char *gaits[] = {"walk", "run"};
    for (int g = 0; g < 2; ++g) {
        int clip = cb_model_find_animation(m, gaits[g]);
        double d = m->animations[clip].t1, lo = INFINITY, hi = -INFINITY, f1[40], f2[40], f3[40], mean[3] = {0, 0, 0};
        for (int i = 0; i < 40; ++i) {
            double t = d * i / 40, up;
            foot_position(s, m, clip, t, lf, &up, &f1[i]);
            foot_position(s, m, clip, t, rf, &up, &f2[i]);
            foot_position(s, m, clip, t, rh, &up, &f3[i]);
            lo = fmin(lo, f1[i]), hi = fmax(hi, f1[i]);
            mean[0] += f1[i] / 40, mean[1] += f2[i] / 40, mean[2] += f3[i] / 40;
        }
        double corr = 0, anti = 0; /* covariances: diagonal pair in phase, same-end pair out of phase */
        for (int i = 0; i < 40; ++i) {
            corr += (f1[i] - mean[0]) * (f3[i] - mean[2]);
            anti += (f1[i] - mean[0]) * (f2[i] - mean[1]);
        }
        printf("  %s: front-left foot swings %.3f m fore-aft\n", gaits[g], hi - lo);
        assert_true(hi - lo > 0.1);     /* the foot really swings */
        assert_true(corr > 0 && anti < 0);
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, clip, 30, -1, NULL, &info, &err), CB_OK);
        assert_true(info.loops);
        assert_true(info.ground_speed > 1.0); /* and the animal travels */
    }
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_khronos_validator_reports_no_errors(void **state)
{
    (void)state;
    char cmd[2048], out[8192];
    require_node_validators();
    snprintf(cmd, sizeof cmd, "node tests/tools/validator/validate.mjs %s/quadruped.glb %s/fish.glb %s/bird.glb 2>&1",
             samples_dir(), samples_dir(), samples_dir());
    int rc = run_command(cmd, out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "quadruped.glb: 0 errors"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quadruped_rig_and_clips),
        cmocka_unit_test(test_walk_and_run_move_the_feet_in_a_diagonal_gait),
        cmocka_unit_test(test_khronos_validator_reports_no_errors),
    };
    return cmocka_run_group_tests_name("samples", tests, NULL, NULL);
}
