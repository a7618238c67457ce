/* test_clip_ends.c - cb_clip_analyze reads the root's position at a clip's ends from the
 * globals its joint matrices were sampled through there, and works the rest pose's extent out
 * once per sampler (src/core/clip.c). Held bit for bit to the plain way: the root displacement
 * from cb_sample_globals at t0 and t1 (every node sampled), and every field of the analysis on a
 * sampler that has analyzed every other clip first against one on a fresh sampler. On Cow,
 * Husky, Fox, the robot and the 200-joint bench rig. */
#include "testutil.h"

#include <string.h>

#include "../../src/core/sampler.h"

static const char *const models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb", "assets/fox-bevy/Fox.glb",
                                     "assets/robot-quaternius-raylib/robot.glb"};

static cb_model *bench_rig(void)
{
    char gen[1100], cmd[2400];
    snprintf(gen, sizeof gen, "%s", crowdbake_exe());
    *strrchr(gen, '/') = 0;
    snprintf(cmd, sizeof cmd, "mkdir -p " TEST_TMP "/clip_ends && %s/gen_samples --bench " TEST_TMP "/clip_ends 200 4 2 >/dev/null", gen);
    assert_int_equal(system(cmd), 0);
    cb_error err = {0};
    cb_model *m = cb_gltf_load(TEST_TMP "/clip_ends/bench_j200_c4_s2.glb", NULL, &err);
    if (!m) fail_msg("%s", err.message);
    return m;
}

static void check_model(cb_model *m, const char *name)
{
    cb_error err = {0};
    cb_sampler *reused = cb_sampler_create(m, 0, &err);
    assert_non_null(reused);
    uint32_t root = cb_skin_root_joint(m, 0), node = m->skins[0].joints[root], moving = 0;
    for (uint32_t pass = 0; pass < 2; ++pass) /* the second pass: every clip analyzed before */
        for (uint32_t a = 0; a < m->animation_count; ++a) {
            cb_clip_info got, want;
            cb_sampler *fresh = cb_sampler_create(m, 0, &err);
            assert_int_equal(cb_clip_analyze(reused, (int32_t)a, 30, -1, NULL, &got, &err), CB_OK);
            assert_int_equal(cb_clip_analyze(fresh, (int32_t)a, 30, -1, NULL, &want, &err), CB_OK);
            if (memcmp(&got, &want, sizeof got)) fail_msg("%s clip %u: the analysis differs on a sampler used before", name, a);
            cb_sampler_open_clip(fresh, (int32_t)a);
            double p0[3], p1[3];
            memcpy(p0, cb_sample_globals(fresh, (int32_t)a, got.t0) + (size_t)node * 16 + 12, sizeof p0);
            memcpy(p1, cb_sample_globals(fresh, (int32_t)a, got.t1) + (size_t)node * 16 + 12, sizeof p1);
            for (int k = 0; k < 3; ++k) {
                double d = p1[k] - p0[k];
                if (memcmp(&d, &got.root_displacement[k], sizeof d))
                    fail_msg("%s clip %u: root displacement %d is %.17g, every node sampled gives %.17g", name, a, k,
                             got.root_displacement[k], d);
            }
            moving += pass == 0 && (got.root_displacement[0] != 0 || got.root_displacement[2] != 0);
            cb_sampler_free(fresh);
        }
    printf("  %s: %u clips, %u with root travel\n", name, m->animation_count, moving);
    cb_sampler_free(reused);
}

static void test_ends_read_from_the_joint_sampling(void **state)
{
    (void)state;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        check_model(m, models[mi]);
        cb_model_free(m);
    }
    cb_model *rig = bench_rig();
    check_model(rig, "the 200-joint bench rig");
    cb_model_free(rig);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ends_read_from_the_joint_sampling),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
