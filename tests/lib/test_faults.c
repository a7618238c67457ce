/* test_faults.c - faults during a bake and hostile sizes: in every case the old file or the
 * complete new one remains, never a partial one, and the message says what happened. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include "crowdbake_pal.h"

#define TMP TEST_TMP "/faults"

static char fish[512], quad[512];

static int setup(void **state)
{
    (void)state;
    snprintf(fish, sizeof fish, "%s/fish.glb", samples_dir());
    snprintf(quad, sizeof quad, "%s/quadruped.glb", samples_dir());
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

static int crowdbake(const char *args, char *out, size_t size)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s %s 2>&1", crowdbake_exe(), args);
    return run_command(cmd, out, size);
}

static int temporaries(const char *dir)
{
    char cmd[1024], out[64];
    snprintf(cmd, sizeof cmd, "ls -a %s | grep -c '\\.tmp\\.'", dir);
    run_command(cmd, out, sizeof out);
    return atoi(out);
}

/* The file at path is a complete palette (its checksum verifies); returns its payload hash. */
static uint64_t complete_palette(const char *path)
{
    cbpal_file f;
    char err[256];
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &f, err, sizeof err) != 0) fail_msg("%s", err);
    uint64_t h = f.header.checksum;
    cbpal_close(&f);
    return h;
}

static void test_unwritable_outputs(void **state)
{
    (void)state;
    char args[1024], out[1024];
    snprintf(args, sizeof args, "bake %s --fps 30 -o " TMP "/missing/x.pal", fish);
    assert_int_equal(crowdbake(args, out, sizeof out), EXIT_IO);
    assert_non_null(strstr(out, "does not exist (create it first)"));
    /* /proc refuses new files even to root: a read-only place. */
    snprintf(args, sizeof args, "bake %s --fps 30 -o /proc/crowdbake-test.pal", fish);
    assert_int_equal(crowdbake(args, out, sizeof out), EXIT_IO);
    assert_non_null(strstr(out, "/proc/crowdbake-test.pal: cannot write"));
    /* A device is never replaced by a file. */
    snprintf(args, sizeof args, "bake %s --fps 30 -o /dev/full", fish);
    assert_int_equal(crowdbake(args, out, sizeof out), EXIT_IO);
    assert_non_null(strstr(out, "not a regular file"));
    struct stat st;
    assert_int_equal(stat("/dev/full", &st), 0);
    assert_true(S_ISCHR(st.st_mode));
}

static void test_disk_full_keeps_the_old_file(void **state)
{
    (void)state;
    mkdir(TMP "/full", 0777);
    if (mount("tmpfs", TMP "/full", "tmpfs", 0, "size=64k") != 0) {
        printf("  (no permission to mount a tmpfs here: disk-full test skipped)\n");
        skip();
    }
    char args[1024], out[1024];
    snprintf(args, sizeof args, "bake %s --fps 30 -o " TMP "/full/animal.pal", fish); /* 10 KiB: fits */
    assert_int_equal(crowdbake(args, out, sizeof out), 0);
    uint64_t before = complete_palette(TMP "/full/animal.pal");
    snprintf(args, sizeof args, "bake %s --fps 30 -o " TMP "/full/animal.pal", quad); /* 174 KiB: does not */
    int rc = crowdbake(args, out, sizeof out);
    uint64_t after = complete_palette(TMP "/full/animal.pal");
    int temps = temporaries(TMP "/full");
    umount(TMP "/full");
    assert_int_equal(rc, EXIT_IO);
    if (!strstr(out, "write failed: No space left on device") || !strstr(out, "the previous file, if any, is unchanged"))
        fail_msg("%s", out);
    assert_true(before == after);
    assert_int_equal(temps, 0);
}

static void file_hash(const char *path, char *hash, size_t size)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "sha256sum %s", path);
    assert_int_equal(run_command(cmd, hash, size), 0);
}

/* Bakes quad over an existing bake of fish at out_path, stops the process at `point` of writing
 * it (a test hook in cli/signals.c; no race with the short-lived temporary), sends it
 * `signal`: the temporary must have existed, be gone, and the old file be unchanged. */
static void interrupt(const char *signal, const char *point, const char *out_path)
{
    char cmd[2048], out[2048], old[1024], now[1024];
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o %s -q", crowdbake_exe(), fish, out_path); /* the old file */
    assert_int_equal(system(cmd), 0);
    file_hash(out_path, old, sizeof old);
    snprintf(cmd, sizeof cmd, "python3 tests/tools/interrupt_mid_write.py %s %s %s %s bake %s --fps 30 -o %s -q 2>&1", signal,
             point, out_path, crowdbake_exe(), quad, out_path);
    int rc = run_command(cmd, out, sizeof out);
    printf("  %s at %s of %s: %s", signal, point, out_path, out);
    assert_int_equal(rc, 0);
    if (!strstr(out, ".tmp.")) fail_msg("no temporary file while stopped: %s", out);
    const char *status = strcmp(signal, "SIGINT") == 0 ? "status -2;" : strcmp(signal, "SIGTERM") == 0 ? "status -15;"
                                                                                                       : "status -1;";
    assert_non_null(strstr(out, status));
    assert_non_null(strstr(out, "removed the partial output; the previous files are unchanged"));
    file_hash(out_path, now, sizeof now);
    assert_string_equal(old, now);
    assert_int_equal(temporaries(TMP), 0);
}

static void test_interrupted_mid_write(void **state)
{
    (void)state;
    interrupt("SIGINT", "mid-write", TMP "/animal.pal");
    interrupt("SIGTERM", "before-rename", TMP "/animal.pal");
    interrupt("SIGHUP", "before-rename", TMP "/animal.exr"); /* OpenEXR writes this temporary itself */
}

/* Two bakes started together: whichever renames last wins, and the file is always complete
 * (no timing is assumed; both orders are valid outcomes). */
static void test_two_bakes_racing_for_one_output(void **state)
{
    (void)state;
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/a.pal -q --layout mat4 && %s bake %s --fps 30 -o " TMP "/b.pal -q --layout affine",
             crowdbake_exe(), quad, crowdbake_exe(), quad);
    assert_int_equal(system(cmd), 0);
    uint64_t a = complete_palette(TMP "/a.pal"), b = complete_palette(TMP "/b.pal");
    for (int round = 0; round < 5; ++round) {
        snprintf(cmd, sizeof cmd, "(%s bake %s --fps 30 -o " TMP "/race.pal -q --layout mat4 & %s bake %s --fps 30 -o " TMP
                 "/race.pal -q --layout affine & wait)", crowdbake_exe(), quad, crowdbake_exe(), quad);
        assert_int_equal(system(cmd), 0);
        uint64_t r = complete_palette(TMP "/race.pal"); /* complete, and one of the two */
        assert_true(r == a || r == b);
    }
    assert_int_equal(temporaries(TMP), 0);
}

/* ---- hostile sizes: a clear error, fast, before anything big is allocated ---- */

static void expect_refused(const char *json, const char *needle, const char *extra_args)
{
    FILE *f = fopen(TMP "/hostile.gltf", "w");
    assert_non_null(f);
    fputs(json, f);
    fclose(f);
    char args[1024], out[2048];
    snprintf(args, sizeof args, "bake " TMP "/hostile.gltf -o " TMP "/hostile.pal %s", extra_args);
    int rc = crowdbake(args, out, sizeof out);
    if (rc != EXIT_INPUT || !strstr(out, needle)) fail_msg("exit %d, '%s' lacks '%s'", rc, out, needle);
    struct stat st;
    assert_int_not_equal(stat(TMP "/hostile.pal", &st), 0);
}

/* The file size limit, on the model and on a buffer it names: an error with the limit's flag
 * (the core says which limit, the command line names the flag), nothing written. */
static void test_file_size_limit_names_its_flag(void **state)
{
    (void)state;
    char fox[1024], gltf[1024], args[4096], out[2048];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    shared_path(gltf, sizeof gltf, "assets/derived-fox/separate/Fox.gltf"); /* 34 KB, its Fox.bin 120 KB */
    snprintf(args, sizeof args, "bake %s --fps 30 -o " TMP "/limited.pal --max-file-size 1K", fox);
    int rc = crowdbake(args, out, sizeof out);
    if (rc != EXIT_IO || !strstr(out, "larger than the 1024-byte file size limit; raise the limit [--max-file-size]"))
        fail_msg("exit %d: %s", rc, out);
    snprintf(args, sizeof args, "bake %s --fps 30 -o " TMP "/limited.pal --max-file-size 50K", gltf);
    rc = crowdbake(args, out, sizeof out);
    if (rc != EXIT_INPUT || !strstr(out, "Fox.bin : larger than the 51200-byte file size limit; raise the limit [--max-file-size]"))
        fail_msg("exit %d: %s", rc, out);
    struct stat st;
    assert_int_not_equal(stat(TMP "/limited.pal", &st), 0);
    snprintf(args, sizeof args, "bake %s --fps 30 -o " TMP "/limited.pal --max-file-size 200K", gltf); /* both fit */
    rc = crowdbake(args, out, sizeof out);
    if (rc != 0) fail_msg("exit %d: %s", rc, out);
}

#define BUF "\"buffers\":[{\"byteLength\":8,\"uri\":\"data:application/octet-stream;base64,AAAAAAAAgD8=\"}]," \
            "\"bufferViews\":[{\"buffer\":0,\"byteLength\":8}],"

static void test_hostile_sizes(void **state)
{
    (void)state;
    expect_refused("{\"asset\":{\"version\":\"2.0\"}," BUF "\"nodes\":[{\"name\":\"a\"}],\"skins\":[{\"joints\":[0],"
                   "\"inverseBindMatrices\":0}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,"
                   "\"count\":2147483648,\"type\":\"MAT4\"}]}",
                   "claims 2147483648 elements, over the limit", "");
    /* A skin of 100,000 joints. */
    static char big[1 << 20];
    int n = snprintf(big, sizeof big, "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"a\"}],\"skins\":[{\"joints\":[0");
    for (int i = 1; i < 100000; ++i) n += snprintf(big + n, sizeof big - n, ",0");
    snprintf(big + n, sizeof big - n, "]}]}");
    expect_refused(big, "has 100000 joints, over the limit of 4096 [--max-joints]", "");
    /* A clip a billion frames long at 30 fps (key times 0 and 3.3e7 s). */
    expect_refused("{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":32,\"uri\":\"data:application/octet-stream;"
                   "base64,AAAAACtQ/ksAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA=\"}],\"bufferViews\":[{\"buffer\":0,"
                   "\"byteLength\":8},{\"buffer\":0,\"byteOffset\":8,\"byteLength\":24}],\"accessors\":[{\"bufferView\":0,"
                   "\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\"},{\"bufferView\":1,\"componentType\":5126,"
                   "\"count\":2,\"type\":\"VEC3\"}],\"nodes\":[{\"name\":\"a\"}],\"scenes\":[{\"nodes\":[0]}],"
                   "\"skins\":[{\"joints\":[0]}],\"animations\":[{\"samplers\":[{\"input\":0,\"output\":1}],"
                   "\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}]}]}",
                   "over the limit of 1048576 frames [--max-frames]", "");
    /* The same clip is allowed with a larger limit, and then the palette is past its size limit. */
    expect_refused("{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":32,\"uri\":\"data:application/octet-stream;"
                   "base64,AAAAAAAASEMAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA=\"}],\"bufferViews\":[{\"buffer\":0,"
                   "\"byteLength\":8},{\"buffer\":0,\"byteOffset\":8,\"byteLength\":24}],\"accessors\":[{\"bufferView\":0,"
                   "\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\"},{\"bufferView\":1,\"componentType\":5126,"
                   "\"count\":2,\"type\":\"VEC3\"}],\"nodes\":[{\"name\":\"a\"}],\"scenes\":[{\"nodes\":[0]}],"
                   "\"skins\":[{\"joints\":[0]}],\"animations\":[{\"samplers\":[{\"input\":0,\"output\":1}],"
                   "\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}]}]}",
                   "over the limit of 4096; lower the fps, bake fewer clips, use a smaller encoding or raise the limit [--max-palette-size]",
                   "--max-palette-size 4K");
}

static void test_broken_hierarchies(void **state)
{
    (void)state;
    expect_refused("{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"a\",\"children\":[1]},{\"name\":\"b\","
                   "\"children\":[0]}],\"skins\":[{\"joints\":[0]}]}",
                   "is part of a cycle in the node hierarchy", ""); /* each node claims the other */
    expect_refused("{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"a\",\"children\":[2]},{\"name\":\"b\","
                   "\"children\":[2]},{\"name\":\"c\"}],\"skins\":[{\"joints\":[2]}]}",
                   "node 2 has two parents (0 and 1)", "");
    expect_refused("{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"name\":\"a\"},{\"name\":\"b\"}],"
                   "\"skins\":[{\"joints\":[1]}]}",
                   "joint 0 (b) is not in scene 0", "");
    expect_refused("{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"a\"},{\"name\":\"b\"}],\"skins\":[{\"joints\":[0,1]}]}",
                   "joints have no common root", "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unwritable_outputs),
        cmocka_unit_test(test_disk_full_keeps_the_old_file),
        cmocka_unit_test(test_interrupted_mid_write),
        cmocka_unit_test(test_two_bakes_racing_for_one_output),
        cmocka_unit_test(test_hostile_sizes),
        cmocka_unit_test(test_file_size_limit_names_its_flag),
        cmocka_unit_test(test_broken_hierarchies),
    };
    return cmocka_run_group_tests_name("faults", tests, setup, NULL);
}
