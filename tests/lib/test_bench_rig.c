/* test_bench_rig.c - `gen_samples --bench` makes the rigs `make bench` measures, up to the 800
 * joints of issue 21's joint scaling (800 against 200): past 256 joints JOINTS_0 must hold
 * unsigned shorts, or the leaves' indices wrap onto other joints. */
#include "testutil.h"

#define TMP TEST_TMP "/bench_rig"

static cb_model *generate(int joints, const char *name)
{
    char gen[1100], cmd[2400];
    snprintf(gen, sizeof gen, "%s", crowdbake_exe());
    *strrchr(gen, '/') = 0;
    snprintf(cmd, sizeof cmd, "mkdir -p " TMP " && %s/gen_samples --bench " TMP " %d 2 1 >/dev/null", gen, joints);
    assert_int_equal(system(cmd), 0);
    char path[256];
    snprintf(path, sizeof path, TMP "/%s", name);
    cb_error err = {0};
    cb_model *m = cb_gltf_load(path, NULL, &err);
    if (!m) fail_msg("%s", err.message);
    return m;
}

/* The largest joint index any vertex uses with a weight: the rig's last joint, a leaf, skins
 * its cap; every joint drives some vertex. */
static void expect_every_joint_skins(const cb_model *m, uint32_t joints)
{
    assert_int_equal(m->skin_count, 1);
    assert_int_equal(m->skins[0].joint_count, joints);
    bool *used = calloc(joints, sizeof *used);
    assert_non_null(used);
    for (uint32_t p = 0; p < m->primitive_count; ++p)
        for (uint64_t v = 0; v < (uint64_t)m->primitives[p].vertex_count * 4; ++v)
            if (m->primitives[p].weights[v] > 0) {
                assert_true(m->primitives[p].joints[v] < joints);
                used[m->primitives[p].joints[v]] = true;
            }
    uint32_t unused = 0;
    for (uint32_t j = 1; j < joints; ++j) unused += !used[j]; /* joint 0 is the root, a ground marker */
    assert_int_equal(unused, 0);
    free(used);
}

static void test_800_joints_skin_every_joint(void **state)
{
    (void)state;
    cb_model *m = generate(800, "bench_j800_c2_s1.glb");
    expect_every_joint_skins(m, 800);
    assert_int_equal(m->animation_count, 2);
    cb_model_free(m);
    /* Independent of crowdbake's loader: the Khronos validator checks JOINTS_0 against the skin. */
    require_node_validators();
    char out[4096];
    int rc = run_command("node tests/tools/validator/validate.mjs " TMP "/bench_j800_c2_s1.glb 2>&1", out, sizeof out);
    if (rc != 0) fail_msg("%s", out);
}

static void test_200_joints_as_before(void **state)
{
    (void)state;
    cb_model *m = generate(200, "bench_j200_c2_s1.glb");
    expect_every_joint_skins(m, 200);
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_800_joints_skin_every_joint),
        cmocka_unit_test(test_200_joints_as_before),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
