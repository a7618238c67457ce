/* test_timed_bake.c - the bake's choice of timed rows (docs/pal-format.md "Timed rows", issue 43
 * item 1) for local rows, on Fox (Run keys 1/24 s apart but for one gap off that grid: uniform
 * rows need 120 fps there) and Husky, in memory (cb_bake_job_plan, then cb_palette_bake of its plan):
 * - auto (the default) takes rows on the keys where they cost fewer rows than the uniform rate,
 *   map rows counted, and says so in the clip's reason; off never; on wherever the keys allow;
 * - the timed palette's every clip within the 1 mm/m budget: its own measurement, cb_verify_clip
 *   (exact skinning halfway between rows and at random times, through the map), and at the
 *   one-shots' reference times (../shared/reference, another implementation's joint matrices)
 *   the runtime's matrices (cb_runtime_matrices, which follows the map) to within the encoding. */
#include "testutil.h"

#include <math.h>
#include <unistd.h>

#include "crowdbake_pal.h"
#include "crowdbake/bake.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"
#include "internal/bake_words.h"

typedef struct baked {
    cb_model *m;
    cb_bake_job job;
    cb_palette p;
    uint32_t timed, rows;
} baked;

static void bake_local(const char *asset, cb_timed_rows timed, baked *b)
{
    char path[1024];
    cb_error err = {0};
    shared_path(path, sizeof path, asset);
    b->m = load_or_fail(path);
    cb_bake_job_init(&b->job);
    b->job.model = b->m, b->job.skin = 0, b->job.threads = 2;
    b->job.settings.bone_space = CB_BONE_SPACE_LOCAL;
    b->job.settings.timed_rows = timed;
    if (cb_bake_job_plan(&b->job, &err)) fail_msg("%s", err.message);
    cb_sampler *s = cb_sampler_create(b->m, 0, &err);
    assert_non_null(s);
    cb_bake_options o = cb_bake_settings_options(&b->job.settings, CB_FORMAT_PAL, NULL, 2);
    if (cb_palette_bake(s, &o, b->job.plan, b->job.plan_count, &b->p, &err)) fail_msg("%s", err.message);
    b->timed = 0;
    for (uint32_t c = 0; c < b->p.clip_count; ++c) b->timed += b->p.clips[c].timed;
    b->rows = b->p.rows;
    cb_sampler_free(s);
}

static void baked_free(baked *b)
{
    cb_palette_free(&b->p);
    cb_bake_job_free(&b->job);
    cb_model_free(b->m);
}

/* Every clip's error by cb_verify_clip (model units): the worst of its rows and between them. */
static double verified(const baked *b)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(b->m, 0, &err);
    double worst = 0;
    for (uint32_t c = 0; c < b->p.clip_count; ++c) {
        cb_clip_error e;
        assert_int_equal(cb_verify_clip(s, &b->p, b->p.texels, c, b->job.plan[c].animation, 16, &e, &err), CB_OK);
        worst = fmax(worst, fmax(e.interp_max, e.quant_max));
    }
    cb_sampler_free(s);
    return worst;
}

/* The worst distance, at the reference times where the clip has rows (a loop's end aside: the row
 * there is its first), between where the runtime's matrices and
 * the reference's put each joint's bind position and points 0.1 model heights from it. */
static double against_reference(const baked *b, const char *reference, bool loops, uint32_t *compared)
{
    char path[1024], line[4096];
    shared_path(path, sizeof path, reference);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    double worst = 0, reach = 0.1 * b->p.model_height, *mats = malloc((size_t)b->p.bone_count * 16 * sizeof *mats);
    bool header = false;
    *compared = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#' || !header) {
            header = header || line[0] != '#';
            continue;
        }
        char *p = strchr(line, ',') + 1, *end = strchr(p, ','), clip[96];
        bool quoted = *p == '"';
        snprintf(clip, sizeof clip, "%.*s", (int)(end - p) - 2 * quoted, p + quoted);
        strtol(end + 1, &p, 10), strtol(p + 1, &p, 10);
        double t = strtod(p + 1, &p), m[16];
        int skin = (int)strtol(p + 1, &p, 10), joint = (int)strtol(p + 1, &p, 10);
        for (int k = 0; k < 16; ++k) m[k] = strtod(p + 1, &p);
        for (uint32_t c = 0; skin == 0 && c < b->p.clip_count; ++c) {
            const cb_palette_clip *pc = &b->p.clips[c];
            if (strcmp(pc->name, clip) != 0 || (pc->loops && (!loops || t >= pc->start + pc->duration - 1e-6)))
                continue; /* a travelling loop is closed: its poses move */
            cb_instance in = cb_instance_of(pc);
            uint32_t r0, r1;
            double fr;
            cb_runtime_frame_in(&b->p, b->p.texels, &in, t - pc->start, &r0, &r1, &fr);
            if (fr > 1e-4 && fr < 1 - 1e-4) continue; /* at its rows: between them cb_verify_clip measures */
            cb_runtime_matrices(&b->p, b->p.texels, &in, t - pc->start, mats);
            const float *bind = b->p.bind_positions + 3 * joint;
            const double *a = mats + 16 * joint;
            for (int i = 0; i < 7; ++i) {
                double q[3] = {bind[0], bind[1], bind[2]}, d2 = 0;
                if (i) q[(i - 1) / 2] += i % 2 ? reach : -reach;
                for (int r = 0; r < 3; ++r) {
                    double x = a[12 + r] - m[12 + r];
                    for (int k = 0; k < 3; ++k) x += (a[k * 4 + r] - m[k * 4 + r]) * q[k];
                    d2 += x * x;
                }
                worst = fmax(worst, sqrt(d2));
            }
            ++*compared;
        }
    }
    fclose(f);
    free(mats);
    return worst;
}

static void check_rig(const char *asset, const char *reference, bool loops, const char *timed_clip)
{
    baked aut, off, on;
    bake_local(asset, CB_TIMED_ROWS_AUTO, &aut);
    bake_local(asset, CB_TIMED_ROWS_OFF, &off);
    bake_local(asset, CB_TIMED_ROWS_ON, &on);
    double h = aut.p.model_height, budget = 1e-3 * h;
    char why[512];
    printf("  %s: rows auto %u (%u timed clips), off %u, on %u (%u timed)\n", asset, aut.rows, aut.timed, off.rows,
           on.rows, on.timed);
    for (uint32_t c = 0; c < aut.p.clip_count; ++c) {
        cb_bake_clip_reason(&aut.job, c, why, sizeof why);
        printf("    %s: %s\n", aut.p.clips[c].name, why);
        bool stated = strstr(why, "rows on its keys (a map of") != NULL;
        assert_int_equal(stated, aut.p.clips[c].timed); /* the choice is stated */
        if (!strcmp(aut.p.clips[c].name, timed_clip)) assert_true(aut.p.clips[c].timed);
        if (aut.p.clips[c].timed) { /* fewer rows, its map's counted */
            assert_true(aut.p.clips[c].frames + aut.p.clips[c].map_rows < off.p.clips[c].frames);
            assert_int_equal(aut.p.clips[c].map_rows, cb_timed_map_rows(aut.p.clips[c].cells, aut.p.row_texels));
        }
        cb_bake_clip_reason(&off.job, c, why, sizeof why);
        assert_null(strstr(why, "rows on its keys (a map of"));
        assert_non_null(strstr(why, "not weighed (timed rows off)"));
    }
    assert_true(aut.timed > 0);
    assert_int_equal(off.timed, 0);
    assert_true(on.timed >= aut.timed);
    assert_true(aut.rows < off.rows);
    double v = verified(&aut);
    uint32_t compared = 0;
    double ref = against_reference(&aut, reference, loops, &compared);
    printf("    auto: visible error %.3g mm/m (bake), %.3g mm/m (cb_verify_clip); vs the reference at %u joint-times "
           "%.3g mm/m\n", 1000 * aut.p.visible_error / h, 1000 * v / h, compared, 1000 * ref / h);
    assert_true(aut.p.visible_error <= budget * 1.05); /* the bake's own measurement: float64 choice, u16 rows */
    assert_true(v <= budget * 1.05);
    uint32_t compared_off = 0;
    double ref_off = against_reference(&off, reference, loops, &compared_off);
    printf("    off: vs the reference %.3g mm/m (%u)\n", 1000 * ref_off / h, compared_off);
    assert_true(compared > 100);
    /* At its rows a timed clip is as close to the reference as the uniform bake's rows (the same
     * poses, encoded alike): Fox's 0.078 mm/m both; Husky's one-shots 1.72 mm/m both, points a tenth
     * of the height off each joint (not its vertices) at 24 fps rows of a 30 fps reference. */
    assert_true(ref <= 1.05 * ref_off + 0.05 * budget);
    baked_free(&aut), baked_free(&off), baked_free(&on);
}

/* A .pal file read back as a game reads it (cb_palette_view, left open in *view for the caller's checks) and
 * every clip verified (cb_verify_clip: its rows, halfway and at 16 random times, through a timed clip's map):
 * the worst error (model units), and how many clips are timed. */
static double verified_file(const char *model_path, const cbpal_file *f, cb_palette *view, uint32_t *timed)
{
    cb_model *m = load_or_fail(model_path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    assert_int_equal(cb_palette_view(f, view, &err), CB_OK);
    double worst = 0;
    *timed = 0;
    for (uint32_t c = 0; c < view->clip_count; ++c) {
        cb_clip_error e;
        assert_int_equal(cb_verify_clip(s, view, f->texels, c, cb_model_find_animation(m, view->clips[c].name), 16, &e, &err),
                         CB_OK);
        worst = fmax(worst, fmax(e.interp_max, e.quant_max));
        *timed += view->clips[c].timed;
    }
    cb_sampler_free(s);
    cb_model_free(m);
    return worst;
}

/* The files: `crowdbake bake --bone-space local` writes Fox's timed Run (.pal version 7, flag bit
 * 6; --timed-rows off: version 6, no timed clip), and the file read back verifies within the budget
 * (cb_palette_view, cb_verify_clip: every clip's rows and between them through the file's map). */
static void test_fox_timed_file(void **state)
{
    (void)state;
    char model[1024], log[8192], errs[256];
    shared_path(model, sizeof model, "assets/fox-bevy/Fox.glb");
    const char *modes[2] = {"auto", "off"};
    for (int i = 0; i < 2; ++i) {
        char out[256];
        snprintf(out, sizeof out, TEST_TMP "/timed_fox_%s.pal", modes[i]);
        int rc = run_crowdbake(log, sizeof log, "bake %s -o %s --bone-space local --timed-rows %s", model, out, modes[i]);
        if (rc) fail_msg("bake failed (%d): %s", rc, log);
        assert_true((strstr(log, "25 rows on its keys (a map of 139 cells at 120 Hz, 3 rows) instead of 139 at 120 fps") != NULL) == (i == 0));
        cbpal_file f;
        if (cbpal_open(out, CBPAL_VERIFY_CHECKSUM, &f, errs, sizeof errs)) fail_msg("%s", errs);
        assert_int_equal(f.header.version, i == 0 ? 7 : 6);
        assert_int_equal((f.header.flags & CBPAL_FLAG_TIMED_ROWS) != 0, i == 0);
        cb_palette view;
        uint32_t timed;
        double worst = verified_file(model, &f, &view, &timed), budget = 1e-3 * view.model_height;
        printf("  Fox, --timed-rows %s: %u rows, %u timed clips, verified %.3g mm/m\n", modes[i], view.rows, timed,
               1000 * worst / view.model_height);
        assert_int_equal(timed, i == 0 ? 1 : 0);
        assert_true(worst <= 1.05 * budget);
        cb_palette_view_free(&view);
        cbpal_close(&f);
    }
}

/* The catalog's timed_rows: Fox's roster manifest says Run's map (cells, cell rate, map rows) and
 * places its rows after the map (first_row 99 + 3); timed_rows = "off" bakes it uniform. */
static void test_fox_timed_catalog(void **state)
{
    (void)state;
    char relative[1024], cwd[1024], model[2100], tmp[1100], log[8192];
    shared_path(relative, sizeof relative, "assets/fox-bevy/Fox.glb");
    assert_non_null(getcwd(cwd, sizeof cwd)); /* a catalog's paths are relative to it: absolute ones */
    snprintf(model, sizeof model, "%s%s%s", relative[0] == '/' ? "" : cwd, relative[0] == '/' ? "" : "/", relative);
    snprintf(tmp, sizeof tmp, "%s%s%s", TEST_TMP[0] == '/' ? "" : cwd, TEST_TMP[0] == '/' ? "" : "/", TEST_TMP);
    const char *modes[2] = {"auto", "off"};
    for (int i = 0; i < 2; ++i) {
        char catalog[256], manifest[256], text[1 << 16];
        snprintf(catalog, sizeof catalog, TEST_TMP "/timed_%s.toml", modes[i]);
        FILE *f = fopen(catalog, "w");
        assert_non_null(f);
        fprintf(f, "[bake]\nbone_space = \"local\"\ntimed_rows = \"%s\"\nout_dir = \"%s/timed_roster_%s\"\n"
                   "[animal.fox]\nmodel = \"%s\"\n", modes[i], tmp, modes[i], model);
        fclose(f);
        int rc = run_crowdbake(log, sizeof log, "bake %s", catalog);
        if (rc) fail_msg("catalog bake failed (%d): %s", rc, log);
        snprintf(manifest, sizeof manifest, TEST_TMP "/timed_roster_%s/roster.json", modes[i]);
        f = fopen(manifest, "r");
        assert_non_null(f);
        size_t n = fread(text, 1, sizeof text - 1, f);
        text[n] = 0;
        fclose(f);
        const char *run = strstr(text, "\"name\": \"Run\"");
        assert_non_null(run);
        assert_int_equal(strstr(run, "\"timed_rows\"") != NULL, i == 0);
        assert_non_null(strstr(run, i == 0 ? "\"first_row\": 102" : "\"first_row\": 99"));
    }
}

/* Global rows on their keys (--timed-rows on; global_timed.c), as a user bakes them: Cow and Husky's
 * files hold fewer rows than their uniform global bake's, each timed clip's reason says so and each clip
 * that keeps its uniform rate what its keys would take; the file read back verifies within the
 * budget (cb_verify_clip through the file's map, at its rows, halfway and at random times) and
 * its clips' errors are the bake's; -j 1 and -j 4 write the same bytes. */
static void global_timed_file(const char *asset, uint32_t least_timed)
{
    char model[1024], log[1 << 16], errs[256], out[2][256], dflt[256];
    shared_path(model, sizeof model, asset);
    const char *threads[2] = {"1", "4"};
    for (int i = 0; i < 2; ++i) {
        snprintf(out[i], sizeof out[i], TEST_TMP "/global_timed_j%s.pal", threads[i]);
        int rc = run_crowdbake(log, sizeof log, "bake %s -o %s --timed-rows on --bone-space global -j %s", model, out[i], threads[i]);
        if (rc) fail_msg("bake failed (%d): %s", rc, log);
    }
    snprintf(dflt, sizeof dflt, TEST_TMP "/global_default.pal");
    char dlog[1 << 14];
    assert_int_equal(run_crowdbake(dlog, sizeof dlog, "bake %s -o %s -q --bone-space global", model, dflt), 0);
    size_t a_size, b_size;
    char *a = read_whole_file(out[0], &a_size), *b = read_whole_file(out[1], &b_size);
    assert_non_null(a), assert_non_null(b);
    assert_int_equal(a_size, b_size);
    assert_memory_equal(a, b, a_size);
    free(a), free(b);
    cbpal_file f, d;
    if (cbpal_open(out[0], CBPAL_VERIFY_CHECKSUM, &f, errs, sizeof errs) || cbpal_open(dflt, 0, &d, errs, sizeof errs))
        fail_msg("%s", errs);
    assert_int_equal(f.header.version, 7);
    assert_true(f.header.flags & CBPAL_FLAG_TIMED_ROWS);
    assert_true(f.header.rows < d.header.rows); /* fewer rows, the maps' counted */
    cb_palette view;
    uint32_t timed;
    double worst = verified_file(model, &f, &view, &timed), budget = 1e-3 * view.model_height;
    assert_int_equal(view.bone_space, CB_BONE_SPACE_GLOBAL);
    for (uint32_t c = 0; c < view.clip_count; ++c) {
        /* its line: taken where fewer bytes, else what its keys would take (or nothing, where no split of 4 meets it) */
        char line[160];
        snprintf(line, sizeof line, "%s ", view.clips[c].name);
        const char *at = strstr(log, line);
        assert_non_null(at);
        const char *eol = strchr(at, '\n');
        bool said = strstr(at, "rows on its keys (a map of") && strstr(at, "rows on its keys (a map of") < eol;
        assert_int_equal(said, view.clips[c].timed);
        if (said) assert_true(strstr(at, "sampled rows: fewer bytes within its budget") < eol);
    }
    printf("  %s --timed-rows on: %u rows (%u timed clips) against the default's %u; verified %.3g mm/m\n", asset,
           f.header.rows, timed, d.header.rows, 1000 * worst / view.model_height);
    assert_true(timed >= least_timed);
    assert_true(worst <= 1.05 * budget);
    assert_non_null(strstr(log, "no fewer bytes")); /* an idle at its key rate keeps it */
    cb_palette_view_free(&view);
    cbpal_close(&f), cbpal_close(&d);
    /* Beside an EXR (no place for a map): the EXR holds the timed clips uniform at their cell rate, within the budget */
    assert_int_equal(run_crowdbake(log, sizeof log, "bake %s -o " TEST_TMP "/global_timed_both.pal --format pal,exr "
                                   "--precision half --timed-rows on -q", model), 0);
    assert_int_equal(run_crowdbake(log, sizeof log, "verify %s " TEST_TMP "/global_timed_both.exr --max-error 1", model), 0);
    assert_int_equal(run_crowdbake(log, sizeof log, "verify %s " TEST_TMP "/global_timed_both.pal --max-error 1", model), 0);
}

static void test_global_timed_rows(void **state)
{
    (void)state;
    global_timed_file("assets/quaternius-cow/Cow.glb", 7);
    global_timed_file("assets/quaternius-husky/Husky.glb", 3);
    /* Rows fitted to the blend (--fit-rows) are kept: timed rows are sampled, so none is timed */
    char model[1024], log[1 << 14], errs[256];
    shared_path(model, sizeof model, "assets/quaternius-cow/Cow.glb");
    assert_int_equal(run_crowdbake(log, sizeof log, "bake %s -o " TEST_TMP "/global_fitted.pal --fit-rows --timed-rows on -q",
                                   model), 0);
    cbpal_file f;
    if (cbpal_open(TEST_TMP "/global_fitted.pal", 0, &f, errs, sizeof errs)) fail_msg("%s", errs);
    assert_false(f.header.flags & CBPAL_FLAG_TIMED_ROWS);
    cbpal_close(&f);
}

/* A catalog's timed_rows = "on" with global rows: the manifest places a timed clip's rows after its map (Cow's
 * Death: 49 rows on 288 cells at 288 Hz, a map of 4 rows), and an idle at its key rate keeps its uniform rows. */
static void test_global_timed_catalog(void **state)
{
    (void)state;
    char relative[1024], cwd[1024], model[2100], tmp[1100], log[8192], text[1 << 16];
    shared_path(relative, sizeof relative, "assets/quaternius-cow/Cow.glb");
    assert_non_null(getcwd(cwd, sizeof cwd)); /* a catalog's paths are relative to it: absolute ones */
    snprintf(model, sizeof model, "%s%s%s", relative[0] == '/' ? "" : cwd, relative[0] == '/' ? "" : "/", relative);
    snprintf(tmp, sizeof tmp, "%s%s%s", TEST_TMP[0] == '/' ? "" : cwd, TEST_TMP[0] == '/' ? "" : "/", TEST_TMP);
    FILE *f = fopen(TEST_TMP "/global_timed.toml", "w");
    assert_non_null(f);
    fprintf(f, "[bake]\ntimed_rows = \"on\"\nbone_space = \"global\"\nout_dir = \"%s/global_timed_roster\"\n[animal.cow]\nmodel = \"%s\"\n"
               "clips = [\"Death\", \"Idle\"]\n", tmp, model);
    fclose(f);
    int rc = run_crowdbake(log, sizeof log, "bake " TEST_TMP "/global_timed.toml");
    if (rc) fail_msg("catalog bake failed (%d): %s", rc, log);
    f = fopen(TEST_TMP "/global_timed_roster/roster.json", "r");
    assert_non_null(f);
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = 0;
    fclose(f);
    const char *death = strstr(text, "\"name\": \"AnimalArmature|Death\""), *idle = strstr(text, "\"name\": \"AnimalArmature|Idle\"");
    assert_non_null(death), assert_non_null(idle);
    assert_true(death < idle); /* in row order: the map's 4 rows, Death's 49, then Idle's */
    assert_non_null(strstr(death, "\"timed_rows\""));
    assert_true(strstr(death, "\"timed_rows\"") < idle);
    assert_null(strstr(idle, "\"timed_rows\""));
    assert_non_null(strstr(idle, "\"first_row\": 53"));
}

static void test_fox_timed_rows(void **state)
{
    (void)state;
    check_rig("assets/fox-bevy/Fox.glb", "reference/Fox.fps24.csv", true, "Run");
}

static void test_husky_timed_rows(void **state)
{
    (void)state;
    check_rig("assets/quaternius-husky/Husky.glb", "reference/Husky.fps30.csv", false, "AnimalArmature|Jump_ToIdle");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fox_timed_rows),
        cmocka_unit_test(test_husky_timed_rows),
        cmocka_unit_test(test_fox_timed_file),
        cmocka_unit_test(test_fox_timed_catalog),
        cmocka_unit_test(test_global_timed_rows),
        cmocka_unit_test(test_global_timed_catalog),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
