/* test_clip_select.c - one broken clip does not block a model: the real Fox (its .gltf + .bin
 * form) with an empty animation added loads in info, bake, vat and catalogs, the clip skipped
 * with a warning (in --json output too, as docs/bake.schema.json says), and is an error only
 * where the user names it; --clip and --exclude-clip choose clips for bake, vat and verify. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <unistd.h>

#include "crowdbake_pal.h"

#define TMP TEST_TMP "/clip_select"

static char exe[PATH_MAX], shared[PATH_MAX];

/* Fox.gltf with {"name":"Broken","channels":[]} first among its animations; its .bin and
 * texture linked beside it from ../shared. */
static int setup(void **state)
{
    (void)state;
    char cmd[4 * PATH_MAX];
    if (!realpath(crowdbake_exe(), exe) || !realpath(shared_dir(), shared)) return -1;
    snprintf(cmd, sizeof cmd,
             "rm -rf " TMP " && mkdir -p " TMP " && cd " TMP " && ln -s %s/assets/derived-fox/separate/Fox.bin . && "
             "ln -s %s/assets/derived-fox/separate/baseColor.png . && "
             "sed 's/\"animations\": *\\[/\"animations\": [{\"name\":\"Broken\",\"channels\":[],\"samplers\":[]},/' "
             "%s/assets/derived-fox/separate/Fox.gltf > Fox-broken.gltf && grep -q '\"name\":\"Broken\"' Fox-broken.gltf",
             shared, shared, shared);
    return system(cmd);
}

/* Runs crowdbake in TMP; stdout (and stderr when `with_stderr`) into out. */
static int cli(const char *args, bool with_stderr, char *out, size_t size)
{
    char cmd[2 * PATH_MAX + 1024];
    snprintf(cmd, sizeof cmd, "cd " TMP " && %s %s %s", exe, args, with_stderr ? "2>&1" : "2>/dev/null");
    return run_command(cmd, out, size);
}

static void expect(const char *args, int status, const char *needle)
{
    static char out[65536];
    int rc = cli(args, true, out, sizeof out);
    if (rc != status || !strstr(out, needle))
        fail_msg("crowdbake %s: exit %d (expected %d), output lacks '%s':\n%s", args, rc, status, needle, out);
}

static void expect_clips(const char *pal, uint32_t clips, uint32_t rows, const char *first)
{
    char path[PATH_MAX], msg[256];
    snprintf(path, sizeof path, TMP "/%s", pal);
    cbpal_file f;
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg)) fail_msg("%s", msg);
    assert_int_equal(f.header.clip_count, clips);
    assert_int_equal(f.header.rows, rows);
    cbpal_clip c;
    assert_int_equal(cbpal_get_clip(&f, 0, &c), 0);
    assert_string_equal(c.name, first);
    cbpal_close(&f);
}

static void validate(const char *schema, const char *json_text)
{
    FILE *f = fopen(TMP "/out.json", "w");
    assert_non_null(f);
    fputs(json_text, f);
    fclose(f);
    assert_schema_valid(schema, TMP "/out.json");
}

static const char warning[] = "Fox-broken.gltf: clip 'Broken' has no channels (remove it or give it keys); the clip is "
                              "skipped, the others are baked";

static void test_info_and_bake_skip_the_broken_clip(void **state)
{
    (void)state;
    static char out[65536];
    expect("info Fox-broken.gltf", 0, "crowdbake: warning: Fox-broken.gltf: clip 'Broken' has no channels");
    assert_int_equal(cli("info Fox-broken.gltf --json", false, out, sizeof out), 0);
    if (!strstr(out, "\"skipped_clips\": [\n    {\n      \"name\": \"Broken\"") || !strstr(out, warning)) fail_msg("%s", out);
    /* Fox's three clips, 159 rows at 30 fps, as from Fox.glb itself. */
    expect("bake Fox-broken.gltf --fps 30 -o all.pal", 0, warning);
    expect_clips("all.pal", 3, 159, "Survey");
    assert_int_equal(cli("bake Fox-broken.gltf --fps 30 -o all.pal --json", false, out, sizeof out), 0);
    if (!strstr(out, "\"warnings\": [\n    {\n      \"kind\": \"warning\",\n      \"message\": \"Fox-broken.gltf: clip 'Broken'"))
        fail_msg("%s", out);
    validate("docs/bake.schema.json", out);
    /* The palette's texels are those of the untouched file (only the input hash differs). */
    char cmd[PATH_MAX + 512], a[128], b[128];
    snprintf(cmd, sizeof cmd, "bake %s/assets/derived-fox/separate/Fox.gltf --fps 30 -o fox.pal -q", shared);
    assert_int_equal(cli(cmd, true, out, sizeof out), 0);
    assert_int_equal(run_command("tail -c +4097 " TMP "/all.pal | md5sum", a, sizeof a), 0);
    assert_int_equal(run_command("tail -c +4097 " TMP "/fox.pal | md5sum", b, sizeof b), 0);
    assert_string_equal(a, b);
}

static void test_clip_selection(void **state)
{
    (void)state;
    static char out[65536];
    /* Asked for by name: an error with the reason. */
    expect("bake Fox-broken.gltf --fps 30 -o x.pal --clip Broken", 4, "clip 'Broken' has no channels");
    expect("bake Fox-broken.gltf --fps 30 -o x.pal --clip Walk,Nope", 2, "--clip Nope: no clip 'Nope'; the clips are: "
           "Survey, Walk, Run");
    expect("bake Fox-broken.gltf --fps 30 -o x.pal --exclude-clip Jump", 2, "--exclude-clip Jump: no clip 'Jump'; the clips are: Survey");
    expect("bake Fox-broken.gltf --fps 30 -o x.pal --exclude-clip Survey,Walk,Run", 2, "no clip left to bake");
    expect("bake Fox-broken.gltf --fps 30 -o x.pal --clip Walk --exclude-clip Run", 2, "give --clip or --exclude-clip, not both");
    expect("verify Fox-broken.gltf all.pal --clip Walk --exclude-clip Run", 2, "give --clip or --exclude-clip, not both");
    /* In the order given: Run's 35 rows then Walk's 21; the broken clip not mentioned. */
    assert_int_equal(cli("bake Fox-broken.gltf --fps 30 -o sel.pal --clip Run,Walk --json", true, out, sizeof out), 0);
    /* The only warnings: the fixed 30 fps's misses of the default max_error (item 4 of issue 42). */
    int warnings = 0, fixed = 0;
    for (const char *p = out; (p = strstr(p, "\"kind\": \"warning\"")); ++p) ++warnings;
    for (const char *p = out; (p = strstr(p, "which a fixed fps is not held to")); ++p) ++fixed;
    if (strstr(out, "Broken") || warnings != fixed) fail_msg("%s", out);
    expect_clips("sel.pal", 2, 56, "Run");
    expect("bake Fox-broken.gltf --fps 30 -o ex.pal --exclude-clip Survey", 0, warning);
    expect_clips("ex.pal", 2, 56, "Walk");
    /* vat: 21 frames of Walk alone. */
    assert_int_equal(cli("vat Fox-broken.gltf -o walk.exr --clip Walk --json", false, out, sizeof out), 0);
    if (!strstr(out, "\"rows\": 21") || !strstr(out, "\"warnings\": []")) fail_msg("%s", out);
    assert_int_equal(cli("vat Fox-broken.gltf -o all.exr --json", false, out, sizeof out), 0);
    if (!strstr(out, "\"rows\": 159") || !strstr(out, warning)) fail_msg("%s", out);
    /* verify: the palette's clips named, or all but those. */
    assert_int_equal(cli("verify Fox-broken.gltf all.pal --clip Walk --random 2 --json", false, out, sizeof out), 0);
    if (!strstr(out, "\"name\": \"Walk\"") || strstr(out, "\"name\": \"Run\"") || strstr(out, "\"name\": \"Survey\""))
        fail_msg("%s", out);
    assert_int_equal(cli("verify Fox-broken.gltf all.pal --exclude-clip Walk --random 2 --json", false, out, sizeof out), 0);
    if (strstr(out, "\"name\": \"Walk\"") || !strstr(out, "\"name\": \"Run\"") || !strstr(out, "\"name\": \"Survey\""))
        fail_msg("%s", out);
    expect("verify Fox-broken.gltf all.pal --clip Gallop", 2, "all.pal: --clip Gallop: no clip 'Gallop'; the clips are: ");
}

/* A catalog takes every clip but the broken one (a warning in the log and in --json), and
 * names it as the error when its clip list asks for it. */
static void test_catalog_skips_or_names_the_broken_clip(void **state)
{
    (void)state;
    static char out[65536];
    FILE *f = fopen(TMP "/all.toml", "w");
    assert_non_null(f);
    fputs("[bake]\nout_dir = \"out\"\nfps = 30\n[animal.fox]\nmodel = \"Fox-broken.gltf\"\n", f);
    fclose(f);
    f = fopen(TMP "/named.toml", "w");
    assert_non_null(f);
    fputs("[bake]\nout_dir = \"out-named\"\n\n[animal.fox]\nmodel = \"Fox-broken.gltf\"\nclips = [\"Walk\", \"Broken\"]\n", f);
    fclose(f);
    expect("bake all.toml", 0, warning);
    expect_clips("out/fox.pal", 3, 159, "Survey");
    expect("bake all.toml -q --force", 0, "crowdbake: warning: Fox-broken.gltf: clip 'Broken'");
    assert_int_equal(cli("bake all.toml --json --force", false, out, sizeof out), 0);
    if (!strstr(out, warning)) fail_msg("%s", out);
    validate("docs/bake.schema.json", out);
    expect("bake named.toml", 4, "named.toml:6:18: [animal.fox] Fox-broken.gltf: clip 'Broken' has no channels");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_info_and_bake_skip_the_broken_clip),
        cmocka_unit_test(test_clip_selection),
        cmocka_unit_test(test_catalog_skips_or_names_the_broken_clip),
    };
    return cmocka_run_group_tests_name("clip_select", tests, setup, NULL);
}
