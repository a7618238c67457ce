/* test_cli.c - what an artist with one GLB meets on the command line: a single-model report,
 * verify and preview reading the .exr that bake writes (MODEL PALETTE, in that order, with
 * a message naming the order when swapped), --format pal,exr keeping each format's default
 * precision, unknown output extensions refused, did-you-mean for commands and options,
 * singular counts, distinct verify column titles, in-place root velocity in inspect, --loop and
 * --one-shot, and catalog.example.toml's stated defaults against the parser's. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <unistd.h>

#include <math.h>

#include "catalog/catalog_toml.h"
#include "crowdbake_pal.h"
#include "crowdbake/exr.h"
#include "report/report.h"

#define TMP TEST_TMP "/cli"

static char fox[1024];

static int setup(void **state)
{
    (void)state;
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

static void assert_contains(const char *hay, const char *needle)
{
    if (!strstr(hay, needle)) fail_msg("expected \"%s\" in:\n%s", needle, hay);
}

static void test_report_of_one_model(void **state)
{
    (void)state;
    static char out[1 << 16];
    /* The report's temporary folders go to a TMPDIR of this test's own, so that other programs
     * using /tmp at the same time cannot change what is counted at the end. */
    assert_int_equal(run_command("mkdir -p " TMP "/tmpdir", NULL, 0), 0);
    setenv("TMPDIR", TMP "/tmpdir", 1);
    /* It used to parse the GLB as TOML ("expected '=', saw '\u0002'"). */
    assert_int_equal(run_crowdbake(out, sizeof out, "report %s --target steam-deck --json > " TMP "/fox.json", fox), 0);
    size_t n;
    char *json = read_whole_file(TMP "/fox.json", &n);
    assert_contains(json, "\"target\": \"Steam Deck\"");
    assert_contains(json, "\"name\": \"Fox\"");
    /* Fox: 24 bones x 2 texels x 127 rows x 8 bytes (qpos/u16 local rows, the default bake: error-bounded, Survey
     * 82 rows and Walk 17 at their 24 fps keys, Run 25 on its keys and a 3-row map; 159 rows at a fixed 30 fps). */
    assert_contains(json, "\"bytes\": 48768");
    free(json);
    assert_int_equal(run_crowdbake(out, sizeof out, "report %s", fox), 0);
    assert_contains(out, "no budget to check (give --target NAME)");
    assert_int_equal(run_crowdbake(out, sizeof out, "report %s --target toaster", fox), EXIT_USAGE);
    assert_contains(out, "--target \"toaster\" is not a built-in profile");
    /* A broken model is reported as itself, not as an entry of a catalog, and not as TOML. */
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "head -c 3000 %s > " TMP "/broken.glb && echo hello > " TMP "/text.glb", fox);
    assert_int_equal(run_command(cmd, NULL, 0), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "report " TMP "/broken.glb"), EXIT_INPUT);
    assert_contains(out, "crowdbake: " TMP "/broken.glb: truncated GLB");
    assert_true(strstr(out, "[animal") == NULL && strstr(out, "type ") == NULL);
    assert_int_equal(run_crowdbake(out, sizeof out, "report " TMP "/text.glb"), EXIT_INPUT);
    assert_contains(out, "text.glb: not a GLB file");
    /* TMPDIR is relative here, as it is for every test: the bake went to MODEL'S FOLDER/TMPDIR
     * (the catalog made for the model resolves out_dir from there) and stayed there, which left
     * build/tmp-tests/cli/tmpdir/crowdbake-report-* folders in ../shared/assets/fox-bevy. */
    snprintf(cmd, sizeof cmd, "rm -rf " TMP "/model && mkdir " TMP "/model && cp %s " TMP "/model/", fox);
    assert_int_equal(run_command(cmd, NULL, 0), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "report " TMP "/model/Fox.glb"), 0);
    assert_int_equal(run_command("ls -A " TMP "/model", out, sizeof out), 0);
    assert_string_equal(out, "Fox.glb\n");
    /* Nothing is left in the temporary folder's place, and nothing beside the model. */
    assert_int_equal(run_command("ls -A " TMP "/tmpdir | wc -l", out, sizeof out), 0);
    assert_int_equal(atoi(out), 0);
    unsetenv("TMPDIR");
}

static void test_verify_and_preview_take_the_exr(void **state)
{
    (void)state;
    static char out[1 << 16];
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/fox.exr -q", fox), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "verify %s " TMP "/fox.exr --json > " TMP "/v.json", fox), 0);
    /* The EXR's float texels (global rows: no place for the parents) verify as the global float .pal of the same
     * bake does. */
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/foxf.pal --precision float --bone-space global -q",
                                   fox), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "verify %s " TMP "/foxf.pal --json > " TMP "/vp.json", fox), 0);
    char *a = read_whole_file(TMP "/v.json", NULL), *b = read_whole_file(TMP "/vp.json", NULL);
    assert_string_equal(strstr(a, "\"clips\""), strstr(b, "\"clips\""));
    free(a), free(b);
    assert_int_equal(run_crowdbake(out, sizeof out, "preview %s " TMP "/fox.exr -o " TMP "/sheet.png --cell 64", fox), 0);
    assert_contains(out, "3 clips x 6 frames");
    /* The old order (PALETTE MODEL) still works, with a note; the wrong kinds of file are named. */
    assert_int_equal(run_crowdbake(out, sizeof out, "preview " TMP "/fox.exr %s -o " TMP "/old.png --cell 64", fox), 0);
    assert_contains(out, "is the old order, still accepted; write 'crowdbake preview MODEL PALETTE'");
    assert_contains(out, "3 clips x 6 frames");
    assert_int_equal(run_crowdbake(out, sizeof out, "preview %s %s -o " TMP "/x.png", fox, fox), EXIT_USAGE);
    assert_contains(out, "is a glTF model, not a palette");
    assert_int_equal(run_crowdbake(out, sizeof out, "verify %s catalog.example.toml", fox), EXIT_USAGE);
    assert_contains(out, "catalog.example.toml: is neither a palette nor glTF, not a palette");
    /* An EXR that is not a crowdbake palette header. */
    assert_int_equal(run_crowdbake(out, sizeof out, "vat %s -o " TMP "/vat.exr", fox), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "verify %s " TMP "/vat.exr", fox), EXIT_INPUT);
    assert_contains(out, "vat.exr: not a crowdbake palette");
}

/* The EXR's clip table reads back as the .pal's. */
static void test_exr_palette_matches_the_pal(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/both.pal --format pal,exr --precision half -q "
                                                "--root-motion in-place", fox), 0);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/both.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    cb_exr_palette e;
    cb_error err = {0};
    assert_int_equal(cb_exr_read_palette(TMP "/both.exr", &e, &err), CB_OK);
    const cb_palette *p = &e.palette;
    assert_int_equal(p->layout, (cb_layout)f.header.layout);
    assert_int_equal(p->precision, CB_PRECISION_HALF);
    assert_int_equal(p->bone_count, f.header.bone_count);
    assert_int_equal(p->rows, f.header.rows);
    assert_int_equal(p->clip_count, f.header.clip_count);
    assert_true(p->texel_bytes == f.texels_size && memcmp(p->texels, f.texels, f.texels_size) == 0);
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        cbpal_clip pc;
        cbpal_get_clip(&f, c, &pc);
        assert_string_equal(p->clips[c].name, pc.name);
        assert_int_equal(p->clips[c].first_row, pc.first_row);
        assert_int_equal(p->clips[c].frames, pc.frames);
        assert_true(p->clips[c].loops == ((pc.flags & CBPAL_CLIP_LOOPS) != 0));
        assert_true(fabs(p->clips[c].start - pc.start) < 1e-6);
    }
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        cbpal_bone b;
        cbpal_get_bone(&f, j, &b);
        assert_memory_equal(p->bind_positions + 3 * j, b.bind_position, sizeof b.bind_position);
    }
    cb_exr_palette_free(&e);
    cbpal_close(&f);
}

static void test_format_pal_exr_keeps_each_precision(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/one.pal -q", fox), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/one.exr -q", fox), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/two.pal --format pal,exr", fox), 0);
    assert_contains(out, "two.pal: 59.6 KiB texture, 63.6 KiB file"); /* was 123.2 KiB: the EXR's float */
    assert_contains(out, "qpos/u16");
    /* Byte for byte the files each single-format bake writes. */
    assert_int_equal(run_command("cmp " TMP "/one.pal " TMP "/two.pal && cmp " TMP "/one.exr " TMP "/two.exr", NULL, 0), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/fox.png", fox), EXIT_USAGE);
    assert_contains(out, "unknown output extension '.png'");
    assert_int_equal(run_command("test ! -e " TMP "/fox.png", NULL, 0), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/f --format pal,exrs", fox), EXIT_USAGE);
    assert_contains(out, "--format is pal, exr or pal,exr");
}

static void test_messages(void **state)
{
    (void)state;
    char out[8192];
    assert_int_equal(run_crowdbake(out, sizeof out, "bakee x.glb"), EXIT_USAGE);
    assert_contains(out, "unknown command 'bakee'; did you mean 'bake'?");
    assert_int_equal(run_crowdbake(out, sizeof out, "verfy"), EXIT_USAGE);
    assert_contains(out, "did you mean 'verify'?");
    assert_int_equal(run_crowdbake(out, sizeof out, "zebra"), EXIT_USAGE);
    assert_true(strstr(out, "did you mean") == NULL);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s -o x.pal --precison half", fox), EXIT_USAGE);
    assert_contains(out, "did you mean '--precision'?");
    /* One clip, one type: no "1 clips". */
    char fish[1024];
    sample_path(fish, sizeof fish, "fish");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/fish.pal", fish), 0);
    assert_contains(out, " 1 clip, ");
    assert_int_equal(run_crowdbake(out, sizeof out, "report %s", fish), 0);
    assert_contains(out, "type ");
    FILE *f = fopen(TMP "/one.toml", "w");
    assert_non_null(f);
    char fish_abs[PATH_MAX];
    assert_non_null(realpath(fish, fish_abs)); /* the catalog's folder is as deep as the build's */
    fprintf(f, "[bake]\nout_dir = \"one\"\nfps = 30\n[animal.fish]\nmodel = \"%s\"\n", fish_abs);
    fclose(f);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake " TMP "/one.toml"), 0);
    assert_contains(out, "baking 1 animal type from");
    assert_contains(out, "1 type in 1 palette");
    /* verify: the two mm/m columns say which is which. */
    assert_int_equal(run_crowdbake(out, sizeof out, "verify %s " TMP "/fish.pal", fish), 0);
    assert_contains(out, "rows mm/m");
    assert_contains(out, "between mm/m");
}

/* The sample quadruped walks forward at 1.2 units/s and runs at 4 (samples/gen). */
static void test_inspect_in_place_velocity(void **state)
{
    (void)state;
    static char out[1 << 14];
    char q[1024];
    sample_path(q, sizeof q, "quadruped");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/q.pal --root-motion in-place -q", q), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "inspect " TMP "/q.pal"), 0);
    assert_contains(out, "root velocity removed (units/s)");
    assert_contains(out, "(0, 0, 1.2), speed 1.2");
    assert_contains(out, "(0, 0, 4), speed 4");
    const char *table = strstr(out, "idle"); /* no float noise (-9.797e-18) as velocities */
    assert_true(strstr(table, "e-0") == NULL && strstr(table, "e-1") == NULL && strstr(table, "e-2") == NULL);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/qk.pal --root-motion keep -q", q), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "inspect " TMP "/qk.pal"), 0);
    assert_contains(out, "walk");
    assert_contains(out, "in the rows");
    assert_true(strstr(out, "(0, 0, 0)") == NULL); /* a kept walk does not claim to stand still */
    /* A bare bake: its loops travel, so they go in place; the one-shot (death) keeps its travel. */
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/qd.pal -q", q), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "inspect " TMP "/qd.pal"), 0);
    assert_contains(out, "(0, 0, 1.2), speed 1.2");
    const char *death = strstr(out, "death");
    assert_non_null(death);
    assert_non_null(strstr(death, "in the rows"));
}

/* A single-model bake records a speed reference, as a catalog animal's is decided: the ground
 * speed of its slowest locomotion clip (Husky's Walk, all four paws: 1.405 units/s; it wrote 0),
 * saying so in a note; --speed-reference overrides it. */
static void test_single_model_speed_reference(void **state)
{
    (void)state;
    static char out[1 << 14];
    char husky[1024];
    shared_path(husky, sizeof husky, "assets/quaternius-husky/Husky.glb");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/husky.pal", husky), 0);
    assert_contains(out, "speed reference 1.405 units/s recorded: the slowest locomotion clip 'AnimalArmature|Walk'");
    assert_int_equal(run_crowdbake(out, sizeof out, "inspect " TMP "/husky.pal"), 0);
    assert_contains(out, "speed reference 1.40");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/husky2.pal --speed-reference 2 -q", husky), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "inspect " TMP "/husky2.pal"), 0);
    assert_contains(out, "speed reference 2 units/s");
}

/* Clip names as exporters write them ("AnimalArmature|Attack_Headbutt", 30 characters) keep
 * inspect's table aligned: each clip's "first row" number ends under its column title. */
static void test_inspect_aligns_long_clip_names(void **state)
{
    (void)state;
    static char out[1 << 14];
    char cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/cow.pal -q", cow), 0);
    assert_int_equal(run_crowdbake(out, sizeof out, "inspect " TMP "/cow.pal"), 0);
    const char *title = strstr(out, "first row");
    assert_non_null(title);
    const char *line = title;
    while (line > out && line[-1] != '\n') --line;
    long column_end = (title - line) + (long)strlen("first row");
    int rows = 0;
    for (const char *l = strchr(title, '\n'); l && *++l; l = strchr(l, '\n')) {
        if (!strstr(l, "AnimalArmature|") || strstr(l, "AnimalArmature|") > strchr(l, '\n')) continue;
        const char *p = l + column_end; /* the number's last digit sits just before the column end */
        assert_true(p[-1] >= '0' && p[-1] <= '9');
        assert_true(p[0] == ' ');
        ++rows;
    }
    assert_int_equal(rows, 12); /* the Cow's 12 clips */
}

/* Whether clip `name` of the palette at path loops (its flag in the clip table); -1 when absent. */
static int clip_loops(const char *path, const char *name)
{
    cbpal_file f;
    char err[256];
    if (cbpal_open(path, 0, &f, err, sizeof err) != 0) fail_msg("%s", err);
    int loops = -1;
    for (uint32_t c = 0; c < f.header.clip_count; ++c) {
        cbpal_clip clip;
        assert_int_equal(cbpal_get_clip(&f, c, &clip), 0);
        if (strcmp(clip.name, name) == 0) loops = (clip.flags & CBPAL_CLIP_LOOPS) != 0;
    }
    cbpal_close(&f);
    return loops;
}

/* --loop and --one-shot overrule what crowdbake decides, as a catalog's `loop` does: the Cow's
 * Attack_Headbutt ends on its first pose but is an attack (decided a one-shot, issue 45), its
 * Death ends lying down (a one-shot), its Walk loops. Names that are not clips, not baked or given
 * to both are usage errors, and nothing is written. */
static void test_loop_and_one_shot_overrule_the_poses(void **state)
{
    (void)state;
    static char out[1 << 14];
    char cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    const char *headbutt = "AnimalArmature|Attack_Headbutt", *death = "AnimalArmature|Death", *walk = "AnimalArmature|Walk";
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/found.pal -q", cow), 0);
    assert_int_equal(clip_loops(TMP "/found.pal", headbutt), 0);
    assert_int_equal(clip_loops(TMP "/found.pal", death), 0);
    assert_int_equal(clip_loops(TMP "/found.pal", walk), 1);
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/told.pal -q --one-shot '%s' --loop '%s,%s'", cow, walk,
                               headbutt, death), 0);
    assert_int_equal(clip_loops(TMP "/told.pal", headbutt), 1);
    assert_int_equal(clip_loops(TMP "/told.pal", death), 1);
    assert_int_equal(clip_loops(TMP "/told.pal", walk), 0);
    assert_int_equal(clip_loops(TMP "/told.pal", "AnimalArmature|Gallop"), 1); /* the others as decided */
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/some.pal -q --clip '%s,%s' --one-shot '%s'", cow, walk,
                               headbutt, headbutt), 0);
    assert_int_equal(clip_loops(TMP "/some.pal", headbutt), 0);
    assert_int_equal(clip_loops(TMP "/some.pal", death), -1);

    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/bad.pal -q --loop Gallopp", cow), EXIT_USAGE);
    assert_contains(out, "--loop Gallopp: no clip 'Gallopp'; did you mean 'AnimalArmature|Gallop'?");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/bad.pal -q --loop '%s' --one-shot '%s'", cow, death,
                               death), EXIT_USAGE);
    assert_contains(out, "'AnimalArmature|Death' is given to both --loop and --one-shot");
    assert_int_equal(run_crowdbake(out, sizeof out, "bake %s --fps 30 -o " TMP "/bad.pal -q --clip '%s' --one-shot '%s'", cow, walk,
                               death), EXIT_USAGE);
    assert_contains(out, "the clip is not among those baked");
    assert_int_equal(access(TMP "/bad.pal", F_OK), -1);
}

/* Each [bake] and [budget] value catalog.example.toml shows is what the parser uses when the
 * key is left out (the file says "every key ... with its default"). */
static void test_example_catalog_states_the_defaults(void **state)
{
    (void)state;
    size_t size;
    char *text = read_whole_file("catalog.example.toml", &size);
    char *stripped = calloc(2 * size + 1, 1); /* room for a '#' a line */
    /* The same file with every key of [bake] and [budget] commented out, except the target. */
    const char *section = "";
    size_t used = 0;
    for (char *line = text; *line;) {
        char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line + 1) : strlen(line);
        if (line[0] == '[') section = strncmp(line, "[bake]", 6) == 0 ? "bake" : strncmp(line, "[budget]", 8) == 0 ? "budget" : "";
        bool key = line[0] >= 'a' && line[0] <= 'z';
        if (*section && key && strncmp(line, "target", 6) != 0) stripped[used++] = '#';
        memcpy(stripped + used, line, len);
        used += len;
        line += len;
    }
    cb_catalog shown, defaults;
    cb_error err = {0};
    if (cb_catalog_parse(text, size, "catalog.example.toml", &shown, &err)) fail_msg("%s", err.message);
    if (cb_catalog_parse(stripped, used, "catalog.example.toml", &defaults, &err)) fail_msg("%s", err.message);
    const cb_bake_settings *a = &shown.defaults, *b = &defaults.defaults;
    assert_true(a->fps == b->fps);
    assert_true(a->fps_auto == b->fps_auto && a->max_error_mm == b->max_error_mm && a->max_fps == b->max_fps);
    assert_true(a->fit_rows == b->fit_rows && a->allow_over_budget == b->allow_over_budget);
    assert_true(a->measure_all == b->measure_all && a->plant_feet == b->plant_feet);
    assert_true(a->row_travel_off == b->row_travel_off);
    assert_int_equal(a->layout, b->layout);
    assert_int_equal(a->precision, b->precision);
    assert_int_equal(a->formats, b->formats);
    assert_string_equal(a->out_dir, b->out_dir);
    assert_int_equal(a->max_texture_size, b->max_texture_size);
    assert_int_equal(a->root_motion, b->root_motion);
    /* The budget as the report resolves it (profile values included). */
    cb_roster none = {0};
    cb_report ra, rb;
    assert_int_equal(cb_report_build(&shown, &none, &ra, &err), CB_OK);
    assert_int_equal(cb_report_build(&defaults, &none, &rb, &err), CB_OK);
    assert_true(ra.crowd_share == rb.crowd_share); /* it said 0.25; the default is 1 */
    assert_true(ra.vram_bytes == rb.vram_bytes);
    assert_int_equal(ra.max_texture_size, rb.max_texture_size);
    assert_int_equal(ra.max_bones, rb.max_bones);
    cb_report_free(&ra), cb_report_free(&rb);
    cb_catalog_free(&shown), cb_catalog_free(&defaults);
    free(stripped), free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_report_of_one_model),
        cmocka_unit_test(test_verify_and_preview_take_the_exr),
        cmocka_unit_test(test_exr_palette_matches_the_pal),
        cmocka_unit_test(test_format_pal_exr_keeps_each_precision),
        cmocka_unit_test(test_messages),
        cmocka_unit_test(test_inspect_in_place_velocity),
        cmocka_unit_test(test_single_model_speed_reference),
        cmocka_unit_test(test_inspect_aligns_long_clip_names),
        cmocka_unit_test(test_loop_and_one_shot_overrule_the_poses),
        cmocka_unit_test(test_example_catalog_states_the_defaults),
    };
    return cmocka_run_group_tests_name("cli", tests, setup, NULL);
}
