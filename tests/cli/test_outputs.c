/* test_outputs.c - the table of output formats (crowdbake/outputs.h) is the one list: every
 * format's name and extension are what --format, OUT's extension and a catalog accept, and what
 * `bake --help`, the man page, docs/usage.md and both completions offer (so none can drift from
 * it); a catalog writes every format a single bake can: with format = "pal,ktx2" its .ktx2 holds
 * the single bake's palette (read back by the KTX2 reader: the same texels, rows and clips), the
 * manifest names it (palette_ktx2, valid against docs/roster.schema.json), the depfile lists it,
 * and a missing or torn one is baked again. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <limits.h>

#include "crowdbake/bake.h"
#include "crowdbake/ktx2.h"
#include "internal/bake_words.h"

#define TMP TEST_TMP "/outputs"
#define CATALOG TMP "/catalog"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " CATALOG);
}

static void test_the_table_answers_by_bit_name_and_extension(void **state)
{
    (void)state;
    uint32_t n = cb_output_format_count();
    assert_true(n >= 4 && n <= CB_OUTPUT_MAX);
    char all[256] = "", path[64];
    unsigned bits = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        assert_ptr_equal(cb_output_format_of(f->format), f);
        assert_ptr_equal(cb_output_format_named(f->name, strlen(f->name)), f);
        snprintf(path, sizeof path, "dir.x/fox%s", f->extension);
        assert_ptr_equal(cb_output_format_for_path(path), f);
        assert_int_equal(bits & f->format, 0); /* one bit each */
        bits |= f->format;
        snprintf(all + strlen(all), sizeof all - strlen(all), "%s%s", i ? "," : "", f->name);
        assert_true(f->layouts && f->precisions && f->manifest_key[0] && f->summary[0]);
    }
    assert_int_equal(cb_formats_parse(all), bits);
    assert_null(cb_output_format_at(n));
    assert_null(cb_output_format_for_path("fox.json"));
    assert_null(cb_output_format_for_path("dir.pal/fox"));
    assert_ptr_equal(cb_output_format_for_path("fox.bvat.json"), cb_output_format_of(CB_FORMAT_BABYLON));
}

/* Each format's name and extension in a file (the extension without its dot for a glob). */
static void offers_every_format(const char *path, bool names, bool extensions)
{
    size_t size;
    char *text = read_whole_file(path, &size);
    for (uint32_t i = 0; i < cb_output_format_count(); ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        if (names && !strstr(text, f->name)) fail_msg("%s does not offer the format %s (outputs.c)", path, f->name);
        const char *ext = strrchr(f->extension, '.') + 1;
        if (extensions && !strstr(text, ext)) fail_msg("%s does not offer the extension %s (outputs.c)", path, ext);
    }
    free(text);
}

static void test_help_man_page_usage_and_completions_offer_every_format(void **state)
{
    (void)state;
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s bake --help > " TMP "/help.txt", crowdbake_exe());
    assert_int_equal(system(cmd), 0);
    offers_every_format(TMP "/help.txt", true, true);
    offers_every_format("docs/crowdbake.1", true, true);
    offers_every_format("docs/usage.md", true, true);
    offers_every_format("completions/crowdbake.bash", true, true);
    offers_every_format("completions/_crowdbake", true, true);
}

static void write_catalog(const char *cow, const char *format)
{
    char text[8192];
    snprintf(text, sizeof text,
             "[bake]\nfps = 30\nroot_motion = \"keep\"\nformat = \"%s\"\nout_dir = \"out\"\n\n"
             "[animal.cow]\nmodel = \"%s\"\n"
             "states = { wander = [\"walk\"], flee = [\"gallop\"], graze = [\"eating\"], die = [\"death\"] }\n"
             /* every clip, as the single bake it is compared with (a catalog bakes its states' clips
              * and extra_clips) */
             "extra_clips = [\"Attack_Headbutt\", \"Attack_Kick\", \"Gallop_Jump\", \"Idle\", \"Idle_2\", "
             "\"Idle_Headlow\", \"Idle_HitReact_Left\", \"Jump_toIdle\"]\n",
             format, cow);
    write_text(CATALOG "/catalog.toml", text);
}

static void bake_catalog(const char *expect)
{
    static char out[1 << 16]; /* the bake's warnings come first */
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s bake " CATALOG "/catalog.toml --depfile " CATALOG "/cow.d 2>&1", crowdbake_exe());
    int rc = run_command(cmd, out, sizeof out);
    if (rc != 0 || !strstr(out, expect)) fail_msg("%s: exit %d, wanted '%s':\n%s", cmd, rc, expect, out);
}

/* The same palette: geometry, layout, precision, clips and every texel. */
static void same_ktx2_palette(const char *a_path, const char *b_path)
{
    cb_ktx2_palette a, b;
    cb_error err = {0};
    assert_int_equal(cb_ktx2_read_palette(a_path, &a, &err), CB_OK);
    assert_int_equal(cb_ktx2_read_palette(b_path, &b, &err), CB_OK);
    assert_int_equal(a.palette.rows, b.palette.rows);
    assert_int_equal(a.palette.width, b.palette.width);
    assert_int_equal(a.palette.height, b.palette.height);
    assert_int_equal(a.palette.layout, b.palette.layout);
    assert_int_equal(a.palette.precision, b.palette.precision);
    assert_int_equal(a.palette.clip_count, b.palette.clip_count);
    for (uint32_t c = 0; c < a.palette.clip_count; ++c) {
        assert_string_equal(a.palette.clips[c].name, b.palette.clips[c].name);
        assert_int_equal(a.palette.clips[c].frames, b.palette.clips[c].frames);
    }
    assert_int_equal(a.palette.texel_bytes, b.palette.texel_bytes);
    assert_memory_equal(a.palette.texels, b.palette.texels, a.palette.texel_bytes);
    assert_true(a.input_hash != b.input_hash); /* each records its own bake: a single model's, a catalog type's */
    cb_ktx2_palette_free(&a), cb_ktx2_palette_free(&b);
}

static void test_a_catalog_writes_ktx2_as_a_single_bake_does(void **state)
{
    (void)state;
    char rel[1024], cow[PATH_MAX], cmd[8192], out[4096];
    shared_path(rel, sizeof rel, "assets/quaternius-cow/Cow.glb");
    assert_non_null(realpath(rel, cow));
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 --root-motion keep --format ktx2 -o " TMP "/single.ktx2 -q",
             crowdbake_exe(), cow);
    assert_int_equal(system(cmd), 0);
    write_catalog(cow, "pal,ktx2");
    bake_catalog("crowdbake: 1 baked, 0 up to date");
    same_ktx2_palette(CATALOG "/out/cow.ktx2", TMP "/single.ktx2");
    size_t n;
    char *manifest = read_whole_file(CATALOG "/out/roster.json", &n), *dep = read_whole_file(CATALOG "/cow.d", &n);
    assert_non_null(strstr(manifest, "\"palette\": \"cow.pal\""));
    assert_non_null(strstr(manifest, "\"palette_ktx2\": \"cow.ktx2\""));
    assert_non_null(strstr(dep, CATALOG "/out/cow.ktx2:"));
    free(manifest), free(dep);
    require_node_validators();
    assert_int_equal(run_command("node tests/tools/validator/validate_schema.mjs docs/roster.schema.json " CATALOG
                                 "/out/roster.json 2>&1", out, sizeof out), 0);
    bake_catalog("crowdbake: 0 baked, 1 up to date");
    /* The .ktx2 is in the up-to-date check: missing or torn, it is baked again. */
    assert_int_equal(system("rm " CATALOG "/out/cow.ktx2"), 0);
    bake_catalog("crowdbake: 1 baked, 0 up to date");
    assert_int_equal(system("head -c 4000 " TMP "/single.ktx2 > " CATALOG "/out/cow.ktx2"), 0);
    bake_catalog("crowdbake: 1 baked, 0 up to date");
    same_ktx2_palette(CATALOG "/out/cow.ktx2", TMP "/single.ktx2");
    /* KTX2 alone: the manifest's palette facts are the .ktx2's (half: a KTX2's default beside the .pal's u16). */
    write_catalog(cow, "ktx2");
    bake_catalog("crowdbake: 1 baked, 0 up to date");
    manifest = read_whole_file(CATALOG "/out/roster.json", &n);
    assert_null(strstr(manifest, "\"palette\":"));
    assert_non_null(strstr(manifest, "\"precision\": \"half\""));
    free(manifest);
    bake_catalog("crowdbake: 0 baked, 1 up to date");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_table_answers_by_bit_name_and_extension),
        cmocka_unit_test(test_help_man_page_usage_and_completions_offer_every_format),
        cmocka_unit_test(test_a_catalog_writes_ktx2_as_a_single_bake_does),
    };
    return cmocka_run_group_tests_name("outputs", tests, setup, NULL);
}
