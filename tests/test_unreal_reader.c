/* test_unreal_reader.c - the Unreal plugin's engine-free part, proven outside Unreal: its .pal
 * reading (runtimes/unreal/.../CrowdbakePalReader.cpp, the factory's and the palette asset's, through
 * the C reader crowdbake_pal.h) and its herd logic (CrowdbakeHerdLogic.cpp, the herd component's)
 * compile with g++ -Wall -Wextra -Werror, and tests/runtimes/unreal/reader_check.cpp holds them to
 * the C reader on Fox and Cow in every layout x precision: texels byte for byte, bind positions,
 * clip table, a herd's bone matrices mid-fade and after, SetSpeed without a pop. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#define TMP TEST_TMP "/unreal_reader"
#define SRC "runtimes/unreal/Crowdbake/Source/Crowdbake"

static void run_or_fail(const char *cmd, char *log, size_t size)
{
    if (run_command(cmd, log, size) != 0) fail_msg("%s:\n%s", cmd, log);
}

static void test_reader_and_herd_equal_the_c_reader(void **state)
{
    (void)state;
    static char log[8192];
    char cmd[4096], model[1024];
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && g++ -std=c++17 -O1 -Wall -Wextra -Werror -I%s/Public -Iinclude -Iformats -o %s/reader_check "
             "tests/runtimes/unreal/reader_check.cpp %s/Private/CrowdbakePalReader.cpp %s/Private/CrowdbakeHerdLogic.cpp 2>&1",
             TMP, SRC, TMP, SRC, SRC);
    run_or_fail(cmd, log, sizeof log);
    const char *models[] = {"assets/fox-bevy/Fox.glb", "assets/quaternius-cow/Cow.glb"};
    const char *layouts[] = {"mat4", "affine", "qpos"}, *precisions[] = {"float", "half", "u16"};
    for (int m = 0; m < 2; ++m) {
        shared_path(model, sizeof model, models[m]);
        for (int l = 0; l < 3; ++l)
            for (int p = 0; p < 3; ++p) {
                snprintf(cmd, sizeof cmd, "%s bake %s -o %s/x.pal --layout %s --precision %s -q 2>&1 && %s/reader_check %s/x.pal 2>&1",
                         crowdbake_exe(), model, TMP, layouts[l], precisions[p], TMP, TMP);
                run_or_fail(cmd, log, sizeof log);
                printf("  %s %s/%s: %s", models[m] + 7, layouts[l], precisions[p], strstr(log, ": ") ? strstr(log, ": ") + 2 : log);
            }
    }
}

/* A damaged file: the factory's message is the C reader's, with the file's name. */
static void test_bad_file_message(void **state)
{
    (void)state;
    static char log[8192];
    run_or_fail("mkdir -p " TMP " && printf 'CBPAL\\r\\n\\032\\377\\377\\377\\377' > " TMP "/bad.pal", log, sizeof log);
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s/reader_check %s/bad.pal 2>&1", TMP, TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), 1);
    if (!strstr(log, "bad.pal: palette format version 4294967295 is newer than this reader")) fail_msg("%s", log);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reader_and_herd_equal_the_c_reader),
        cmocka_unit_test(test_bad_file_message),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
