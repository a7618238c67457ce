/* test_bake_job.c - the one bake pipeline (include/crowdbake/bake.h): each format's precision,
 * the qpos -> affine fallback acted on by status code, per-clip rates from one settings struct,
 * a catalog type baking to the very texels of `bake MODEL` with the same settings (the two
 * paths share every decision; only the recorded input hash tells them apart), and what a rate
 * search keeps for its bake baking the bytes the bake makes without it. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <sys/wait.h>

#include "crowdbake_pal.h"
#include "crowdbake/bake.h"
#include "crowdbake/exr.h"
#include "internal/bake_words.h"
#include "internal/plumbing.h"
#include "../../src/core/palette_bake.h" /* search_keep, search_beside: the work beside a search */

#define TMP TEST_TMP "/bake_job"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

static cb_bake_job job_for(const cb_model *m)
{
    cb_bake_job job;
    cb_bake_job_init(&job);
    job.model = m, job.skin = 0;
    job.threads = 2;
    return job;
}

/* The bone space, decided in one place (cb_bake_settings_bone_space) for the options, the notes, the manifest and
 * the roster's keys: local in a .pal by default; global for the other formats, where the settings cannot hold local
 * rows (a layout other than qpos, half, fitted rows), and where asked for; local asked for stays local (and the job
 * refuses what cannot hold it). */
static void test_bone_space_is_decided_once(void **state)
{
    (void)state;
    cb_bake_settings s = cb_default_bake_settings();
    assert_int_equal(cb_bake_settings_bone_space(&s, CB_FORMAT_PAL), CB_BONE_SPACE_LOCAL);
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_PAL, NULL, 1).bone_space, CB_BONE_SPACE_LOCAL);
    for (unsigned f = CB_FORMAT_EXR; f <= CB_FORMAT_BABYLON; f <<= 1)
        assert_int_equal(cb_bake_settings_options(&s, f, NULL, 1).bone_space, CB_BONE_SPACE_GLOBAL);
    cb_bake_settings unfit[3] = {s, s, s};
    unfit[0].layout = CB_LAYOUT_AFFINE, unfit[1].precision = CB_PRECISION_HALF, unfit[2].fit_rows = true;
    char why[600];
    static const char *const reasons[3] = {"a layout other than qpos", "precision half", "fitted rows"};
    for (int i = 0; i < 3; ++i) {
        assert_int_equal(cb_bake_settings_bone_space(&unfit[i], CB_FORMAT_PAL), CB_BONE_SPACE_GLOBAL);
        cb_bake_bone_space_why(&unfit[i], CB_FORMAT_PAL, CB_BONE_SPACE_GLOBAL, NULL, why, sizeof why);
        assert_non_null(strstr(why, "global rows, not the default local: ")), assert_non_null(strstr(why, reasons[i]));
        unfit[i].bone_space_set = true; /* asked for: kept, for the job to refuse */
        assert_int_equal(cb_bake_settings_bone_space(&unfit[i], CB_FORMAT_PAL), CB_BONE_SPACE_LOCAL);
    }
    for (int set = 0; set < 2; ++set) { /* the command line sets both; a library caller may set bone_space alone */
        s.bone_space = CB_BONE_SPACE_GLOBAL, s.bone_space_set = set;
        assert_int_equal(cb_bake_settings_bone_space(&s, CB_FORMAT_PAL), CB_BONE_SPACE_GLOBAL);
        cb_bake_bone_space_why(&s, CB_FORMAT_PAL, CB_BONE_SPACE_GLOBAL, NULL, why, sizeof why);
        assert_non_null(strstr(why, "global rows (bone space global, asked for)"));
    }
}

/* u16 for .pal, half for .ktx2 and float for .exr unless a precision is set; set, it holds for all. */
static void test_each_format_gets_its_precision(void **state)
{
    (void)state;
    cb_bake_settings s = cb_default_bake_settings();
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_PAL, NULL, 1).precision, CB_PRECISION_U16);
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_EXR, NULL, 1).precision, CB_PRECISION_FLOAT);
    /* KTX2 takes the .pal's, half for its default u16 (its loaders refuse RGBA16UI) */
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_KTX2, NULL, 1).precision, CB_PRECISION_HALF);
    assert_true(cb_bake_settings_options(&s, CB_FORMAT_PAL, NULL, 1).affine_fallback);
    s.precision = CB_PRECISION_HALF, s.precision_set = true, s.layout = CB_LAYOUT_MAT4, s.layout_set = true;
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_PAL, NULL, 1).precision, CB_PRECISION_HALF);
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_EXR, NULL, 1).precision, CB_PRECISION_HALF);
    assert_false(cb_bake_settings_options(&s, CB_FORMAT_PAL, NULL, 1).affine_fallback);
    s.precision = CB_PRECISION_U16, s.formats = CB_FORMAT_PAL | CB_FORMAT_EXR;
    assert_false(cb_bake_settings_writable(&s));
    s.formats = CB_FORMAT_PAL | CB_FORMAT_BABYLON; /* u16 is the .pal's; a .bvat.json is always float mat4 */
    assert_true(cb_bake_settings_writable(&s));
    assert_int_equal(cb_bake_settings_options(&s, CB_FORMAT_BABYLON, NULL, 1).precision, CB_PRECISION_FLOAT);
    s.formats = CB_FORMAT_BABYLON; /* u16 for it alone: refused, never ignored */
    assert_false(cb_bake_settings_writable(&s));
    assert_int_equal(cb_formats_parse("both"), CB_FORMAT_PAL | CB_FORMAT_EXR);
    assert_int_equal(cb_formats_parse("exr,pal"), CB_FORMAT_PAL | CB_FORMAT_EXR);
    assert_int_equal(cb_formats_parse("png"), 0);
    cb_root_motion rm;
    assert_true(cb_root_motion_parse("in-place", &rm) && rm == CB_ROOT_MOTION_IN_PLACE);
    assert_false(cb_root_motion_parse("inplace", &rm));
    assert_true(cb_fps_valid(1000) && !cb_fps_valid(1000.5) && !cb_fps_valid(0));
}

/* A job that did not start from cb_bake_job_init (its size unset, or another header's) is
 * refused before the library reads it, with the function to call; with its size, it bakes. */
static void test_job_carries_its_size(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/spider-animated-luanti/gltf_spider_animated.gltf");
    cb_bake_job job = job_for(m);
    job.outputs = &(cb_output_path){CB_FORMAT_PAL, TMP "/sized.pal"}, job.output_count = 1;
    cb_error err = {0};
    for (size_t size = 0; size <= sizeof job + 8; size += sizeof job / 2 + 4) {
        job.size = size;
        memset(&err, 0, sizeof err);
        assert_int_equal(cb_bake_job_plan(&job, &err), CB_ERR_INTERNAL);
        assert_non_null(strstr(err.message, "cb_bake_job_init"));
        assert_false(job.planned);
    }
    job.size = sizeof job;
    memset(&err, 0, sizeof err);
    assert_int_equal(cb_bake_job_plan(&job, &err), CB_OK);
    assert_true(job.planned);
    cb_bake_job_free(&job);
    cb_model_free(m);
}

/* The spider's non-uniform scale: qpos reports CB_ERR_LAYOUT; a job without a layout set falls
 * back to affine with a note, one with qpos asked for fails with that status. */
static void test_fallback_acts_on_the_status(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/spider-animated-luanti/gltf_spider_animated.gltf");
    cb_bake_job job = job_for(m);
    job.outputs = &(cb_output_path){CB_FORMAT_PAL, TMP "/spider.pal"}, job.output_count = 1;
    cb_bake_result r;
    cb_error err = {0};
    assert_int_equal(cb_bake_job_run(&job, &r, &err), CB_OK);
    assert_int_equal(r.outputs[0].palette.layout, CB_LAYOUT_AFFINE);
    assert_int_equal(r.notes.count, 1);
    assert_non_null(strstr(r.notes.items[0].message, "baked with affine instead"));
    cb_bake_result_free(&r);
    cb_bake_job_free(&job);
    job = job_for(m);
    job.settings.layout_set = true; /* qpos, asked for */
    job.outputs = &(cb_output_path){CB_FORMAT_PAL, TMP "/spider-qpos.pal"}, job.output_count = 1;
    assert_int_equal(cb_bake_job_run(&job, &r, &err), CB_ERR_LAYOUT);
    assert_non_null(strstr(err.message, "non-uniform scale"));
    cb_bake_result_free(&r);
    cb_bake_job_free(&job);
    cb_model_free(m);
}

/* One settings struct: the job's fps = auto chooses every clip's rate except a clip that says
 * fps_auto = 0, which keeps its own fixed rate. */
static void test_clip_settings_override_the_job(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/fox-bevy/Fox.glb");
    cb_clip_plan clips[3] = {{0, NULL, -1, 0, false, false, 0, NULL}, {1, NULL, -1, 12, false, false, 0, NULL}, {2, NULL, -1, 0, false, false, 0, NULL}};
    cb_clip_request per_clip[3] = {{-1, 0}, {0, 0}, {-1, 0}};
    cb_bake_job job = job_for(m);
    job.clips = clips, job.clip_count = 3, job.clip_requests = per_clip;
    job.settings.fps_auto = true;
    cb_error err = {0};
    assert_int_equal(cb_bake_job_plan(&job, &err), CB_OK);
    assert_int_equal(job.plan_count, 3);
    assert_true(job.plan[1].fps == 12); /* kept: fps_auto = 0 */
    for (int i = 0; i < 3; i += 2) {    /* chosen: within 1 mm/m, or at the 120 fps ceiling */
        assert_true(job.plan[i].fps > 0 && job.plan[i].fps <= CB_AUTO_MAX_FPS);
        assert_true(job.rates[i].met ? job.rates[i].error_mm <= 1 : job.plan[i].fps == CB_AUTO_MAX_FPS);
    }
    assert_true(job.plan[0].fps != 30 || job.plan[2].fps != 30); /* the rates were really chosen */
    cb_bake_job_free(&job);
    cb_model_free(m);
}

/* The payload and every header field but the input hash (and so the checksum). */
static void assert_same_texels(const char *a, const char *b)
{
    cbpal_file fa, fb;
    char msg[256];
    if (cbpal_open(a, CBPAL_VERIFY_CHECKSUM, &fa, msg, sizeof msg)) fail_msg("%s", msg);
    if (cbpal_open(b, CBPAL_VERIFY_CHECKSUM, &fb, msg, sizeof msg)) fail_msg("%s", msg);
    assert_int_equal(fa.header.layout, fb.header.layout);
    assert_int_equal(fa.header.precision, fb.header.precision);
    assert_int_equal(fa.header.rows, fb.header.rows);
    assert_int_equal(fa.header.width, fb.header.width);
    assert_true(fa.header.input_hash != fb.header.input_hash); /* each path records its own inputs */
    assert_int_equal(fa.header.payload_raw_size, fb.header.payload_raw_size);
    assert_memory_equal(fa.texels, fb.texels, fa.header.payload_raw_size);
    cbpal_close(&fa);
    cbpal_close(&fb);
}

/* `bake MODEL --format pal,exr` and a catalog type with format = "both": the same texels, u16 in
 * the .pal and float in the .exr, for both. */
static void test_catalog_and_single_bake_agree(void **state)
{
    (void)state;
    char fish[PATH_MAX], cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "%s/fish.glb", samples_dir());
    assert_non_null(realpath(cmd, fish));
    char text[2 * PATH_MAX];
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"roster\"\nformat = \"both\"\nroot_motion = \"in-place\"\n"
             "[animal.fish]\nmodel = \"%s\"\nstates = { swim = [\"swim\"] }\n", fish);
    write_text(TMP "/catalog.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/catalog.toml -q && %s bake %s -o " TMP "/single.pal --format pal,exr "
             "--root-motion in-place -q", crowdbake_exe(), crowdbake_exe(), fish);
    assert_int_equal(system(cmd), 0);
    assert_same_texels(TMP "/roster/fish.pal", TMP "/single.pal");
    cb_exr_image a, b;
    cb_error err = {0};
    assert_int_equal(cb_exr_read(TMP "/roster/fish.exr", &a, &err), CB_OK);
    assert_int_equal(cb_exr_read(TMP "/single.exr", &b, &err), CB_OK);
    assert_int_equal(a.precision, CB_PRECISION_FLOAT);
    assert_int_equal(a.precision, b.precision);
    assert_int_equal(a.texel_bytes, b.texel_bytes);
    assert_memory_equal(a.texels, b.texels, a.texel_bytes);
    cb_exr_image_free(&a);
    cb_exr_image_free(&b);
}

/* --out-dir moves a catalog's palettes; --depfile-manifest-only writes the manifest's rule
 * alone (what Ninja's plain `depfile` and CMake's DEPFILE accept); both refused for one model. */
static void test_catalog_out_dir_and_manifest_depfile(void **state)
{
    (void)state;
    char fish[PATH_MAX], cmd[3 * PATH_MAX], text[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "%s/fish.glb", samples_dir());
    assert_non_null(realpath(cmd, fish));
    /* A fixed 30 fps: the fish's loop travels with root motion kept, which no rate bakes within 1 mm/m. */
    snprintf(text, sizeof text, "[bake]\nfps = 30\n[animal.fish]\nmodel = \"%s\"\nstates = { swim = [\"swim\"] }\n", fish);
    write_text(TMP "/one.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/one.toml -q --out-dir " TMP "/elsewhere --depfile " TMP "/one.d "
             "--depfile-manifest-only", crowdbake_exe());
    assert_int_equal(system(cmd), 0);
    char *deps = read_whole_file(TMP "/one.d", NULL);
    char want[5 * PATH_MAX], tool[PATH_MAX];
    assert_non_null(realpath(crowdbake_exe(), tool));
    snprintf(want, sizeof want, TMP "/elsewhere/roster.json: " TMP "/one.toml \\\n  %s \\\n  %s\n\n%s:\n\n%s:\n", tool, fish,
             fish, tool);
    if (strcmp(deps, want) != 0) fail_msg("depfile:\n%s\nwanted:\n%s", deps, want);
    free(deps);
    FILE *f = fopen(TMP "/elsewhere/fish.pal", "rb");
    assert_non_null(f);
    fclose(f);
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TMP "/x.pal --out-dir " TMP " 2>/dev/null", crowdbake_exe(), fish);
    assert_int_equal(WEXITSTATUS(system(cmd)), EXIT_USAGE);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/one.toml -q --depfile-manifest-only 2>/dev/null", crowdbake_exe());
    assert_int_equal(WEXITSTATUS(system(cmd)), EXIT_USAGE);
}

/* What a job's rate search keeps for its bake (the skin's facts, each clip's poses, a probe's
 * sampled and fitted rows: speed43j) stands in for making them again, bit for bit: the same job
 * with its search released before the bake (cb_bake_job_release_search, as the roster does) bakes
 * every row afresh, and writes the same bytes. Fox's rows come from its joints' similarities,
 * Husky's from their matrices; both global bakes have sampled and fitted answers, and their default (local)
 * bakes keep their searches' poses too. */
static void bake_bytes(const cb_model *m, cb_bone_space space, bool release, const char *path, char **bytes, size_t *size,
                       uint32_t *fitted)
{
    cb_bake_job job = job_for(m);
    job.settings.bone_space = space;
    job.outputs = &(cb_output_path){CB_FORMAT_PAL, path}, job.output_count = 1;
    cb_bake_result r;
    cb_error err = {0};
    assert_int_equal(cb_bake_job_plan(&job, &err), CB_OK);
    if (release) cb_bake_job_release_search(&job);
    assert_int_equal(cb_bake_job_run(&job, &r, &err), CB_OK);
    *fitted = 0;
    for (uint32_t i = 0; i < job.plan_count; ++i) *fitted += job.rates[i].fitted;
    cb_bake_result_free(&r);
    cb_bake_job_free(&job);
    *bytes = read_whole_file(path, size);
    assert_non_null(*bytes);
}

static void test_kept_search_bakes_the_same_bytes(void **state)
{
    (void)state;
    static const char *models[] = {"assets/fox-bevy/Fox.glb", "assets/quaternius-husky/Husky.glb"};
    for (int k = 0; k < 2; ++k) {
        cb_model *m = load_shared(models[k]);
        for (int space = CB_BONE_SPACE_GLOBAL; space <= CB_BONE_SPACE_LOCAL; ++space) { /* global, and the default */
            char *kept, *fresh;
            size_t kept_size, fresh_size;
            uint32_t kept_fitted, fresh_fitted;
            bake_bytes(m, (cb_bone_space)space, false, TMP "/kept.pal", &kept, &kept_size, &kept_fitted);
            bake_bytes(m, (cb_bone_space)space, true, TMP "/fresh.pal", &fresh, &fresh_size, &fresh_fitted);
            if (space == CB_BONE_SPACE_GLOBAL) assert_true(kept_fitted > 0); /* a fitted answer, and sampled ones */
            assert_int_equal(kept_fitted, fresh_fitted);
            assert_int_equal(kept_size, fresh_size);
            assert_memory_equal(kept, fresh, kept_size);
            free(kept), free(fresh);
        }
        cb_model_free(m);
    }
}

/* What a job decides beside its rate search (bake_beside.c: the speed reference, from the
 * clips whose names may say a gait, and their per-row travels) is what the run decides after it
 * alone: the same job with its search released before the run (nothing kept, the beside's work
 * with it) records the same reference and why, the same notes (the travels applied or not, with
 * their slides) and writes the same bytes (the travels' offsets are in the rows). Cow and Husky,
 * whose Walk and Gallop stride; at -j 1 the work beside runs on the search's one thread. */
static void test_work_beside_the_search_is_the_runs(void **state)
{
    (void)state;
    static const char *models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb"};
    for (int k = 0; k < 2; ++k) {
        cb_model *m = load_shared(models[k]);
        for (uint32_t threads = 1; threads <= 2; ++threads) {
            double speed[2];
            char from[2][256], *bytes[2];
            size_t size[2];
            cb_warnings notes[2];
            for (int release = 0; release < 2; ++release) {
                cb_bake_job job = job_for(m);
                job.threads = threads;
                job.settings.bone_space = CB_BONE_SPACE_GLOBAL; /* the work beside a global search */
                const char *path = release ? TMP "/after.pal" : TMP "/beside.pal";
                job.outputs = &(cb_output_path){CB_FORMAT_PAL, path}, job.output_count = 1;
                cb_bake_result r;
                cb_error err = {0};
                assert_int_equal(cb_bake_job_plan(&job, &err), CB_OK);
                const search_keep *keep = job.search_kept;
                assert_true(keep && keep->beside && atomic_load(&keep->beside->taken)); /* it ran beside the search */
                if (release) cb_bake_job_release_search(&job);
                assert_int_equal(cb_bake_job_run(&job, &r, &err), CB_OK);
                speed[release] = job.speed_reference;
                snprintf(from[release], sizeof from[release], "%s", job.speed_reference_from);
                notes[release] = r.notes, r.notes = (cb_warnings){0};
                cb_bake_result_free(&r);
                cb_bake_job_free(&job);
                bytes[release] = read_whole_file(path, &size[release]);
                assert_non_null(bytes[release]);
            }
            assert_true(speed[0] > 0);
            assert_true(speed[0] == speed[1]);
            assert_string_equal(from[0], from[1]);
            assert_int_equal(notes[0].count, notes[1].count);
            bool travel_noted = false;
            for (uint32_t i = 0; i < notes[0].count; ++i) {
                assert_string_equal(notes[0].items[i].message, notes[1].items[i].message);
                travel_noted |= strstr(notes[0].items[i].message, "per-row travel applied") != NULL;
            }
            assert_true(travel_noted); /* a gallop's travel, measured beside the search */
            assert_int_equal(size[0], size[1]);
            assert_memory_equal(bytes[0], bytes[1], size[0]);
            for (int i = 0; i < 2; ++i) free(bytes[i]), cb_warnings_free(&notes[i]);
        }
        cb_model_free(m);
    }
}

/* A clip's rows at a rate (cb_bake_clip_frames_at, the command line's "against N rows at a fixed
 * 30 fps"), from its rate search's kept analysis and, the search released, analyzed: what
 * cb_clip_analyze gives on a fresh sampler. */
static void test_clip_rows_at_a_rate_are_the_analyses(void **state)
{
    (void)state;
    static const char *models[] = {"assets/fox-bevy/Fox.glb", "assets/quaternius-cow/Cow.glb"};
    static const double rates[] = {30, 24, 60};
    for (int k = 0; k < 2; ++k) {
        cb_model *m = load_shared(models[k]);
        cb_bake_job job = job_for(m);
        job.outputs = &(cb_output_path){CB_FORMAT_PAL, TMP "/rows_at.pal"}, job.output_count = 1;
        cb_bake_result r;
        cb_error err = {0};
        assert_int_equal(cb_bake_job_run(&job, &r, &err), CB_OK);
        assert_non_null(job.search_kept); /* the stand-ins are there to take */
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        assert_non_null(s);
        for (int released = 0; released < 2; ++released, cb_bake_job_release_search(&job))
            for (uint32_t i = 0; i < job.plan_count; ++i)
                for (int f = 0; f < 3; ++f) {
                    uint32_t frames = 0;
                    cb_clip_info fresh;
                    cb_sampler *alone = cb_sampler_create(m, 0, &err);
                    assert_non_null(alone);
                    assert_int_equal(cb_bake_clip_frames_at(&job, s, i, rates[f], &frames, &err), CB_OK);
                    assert_int_equal(cb_clip_analyze(alone, job.plan[i].animation, rates[f], job.plan[i].loop, &job.limits,
                                                     &fresh, &err), CB_OK);
                    if (frames != fresh.frames)
                        fail_msg("%s clip %u at %g fps: %u rows, analyzed %u", models[k], i, rates[f], frames, fresh.frames);
                    cb_sampler_free(alone);
                }
        cb_sampler_free(s);
        cb_bake_result_free(&r);
        cb_bake_job_free(&job);
        cb_model_free(m);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bone_space_is_decided_once),
        cmocka_unit_test(test_each_format_gets_its_precision),
        cmocka_unit_test(test_job_carries_its_size),
        cmocka_unit_test(test_fallback_acts_on_the_status),
        cmocka_unit_test(test_clip_settings_override_the_job),
        cmocka_unit_test(test_catalog_and_single_bake_agree),
        cmocka_unit_test(test_catalog_out_dir_and_manifest_depfile),
        cmocka_unit_test(test_kept_search_bakes_the_same_bytes),
        cmocka_unit_test(test_work_beside_the_search_is_the_runs),
        cmocka_unit_test(test_clip_rows_at_a_rate_are_the_analyses),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
