/* test_layers.c - the layers look only down (CONTRIBUTING.md): src/core, formats/, src/bake, cli/.
 * tests/tools/layers.py reads every #include of their files and, with nm, the undefined symbols
 * of every src/core and formats/ object in this build: none may be a src/bake or cli/ one (the
 * knot this test was written after: the core and the KTX2 writer called cb_root_motion_name,
 * defined in the bake job). It also catches one made on purpose. */
#include "testutil.h"

static void test_no_include_or_call_runs_up_a_layer(void **state)
{
    (void)state;
    char out[16384];
    int rc = run_command("python3 tests/tools/layers.py " BUILD_DIR " 2>&1", out, sizeof out);
    if (rc != 0) fail_msg("%s", out);
    assert_non_null(strstr(out, "no include and no call runs up"));
}

/* An object of the core that calls the bake job: the check names it. */
static void test_a_knot_is_caught(void **state)
{
    (void)state;
    char out[16384];
    int rc = run_command("rm -rf " TEST_TMP "/layers && mkdir -p " TEST_TMP "/layers && cp -r " BUILD_DIR "/obj "
                         TEST_TMP "/layers/ && printf '#include \"crowdbake/bake.h\"\\nvoid knot(void) "
                         "{ cb_bake_job_init(0); }\\n' > " TEST_TMP "/layers/knot.c && cc -Iinclude -c " TEST_TMP
                         "/layers/knot.c -o " TEST_TMP "/layers/obj/src/core/knot.o && python3 tests/tools/layers.py "
                         TEST_TMP "/layers 2>&1", out, sizeof out);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(out, "knot.o calls cb_bake_job_init, defined only in"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_no_include_or_call_runs_up_a_layer),
        cmocka_unit_test(test_a_knot_is_caught),
    };
    return cmocka_run_group_tests_name("layers", tests, NULL, NULL);
}
