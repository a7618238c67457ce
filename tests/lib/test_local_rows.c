/* test_local_rows.c - local rows (.pal version 6, header flag bit 5; docs/pal-format.md "Local rows")
 * on real rigs, Cow and Husky at 30 fps, u16:
 * - at the rows, the composed bone matrices (cbpal_bone_matrix, the one-header reader composing in
 *   float) equal the joint matrices another implementation sampled (../shared/reference) to within
 *   the u16 encoding, as the global bake's do;
 * - between the rows, at the keys' rate (24 fps) the composed blend errs a fraction of the global
 *   bake's blend at the same rate; at 30 fps, off the keys, about as much (both measured on every
 *   skinned vertex against exact skinning, cb_verify_clip);
 * - the header says version 6 only with bit 5; a global bake keeps its version;
 * - local rows refuse half, mat4 and an EXR alone with a one-line error and write nothing;
 * - they are the default, stated as such, and one catalog may mix them with global rows on one model;
 * - a u16 bake's codes are its float bake's local values encoded by the spec's rule, in the box of them;
 * - a float bake's local rows (a matrix rig's converted from its global rows, a similarity rig's
 *   sampled local from the double poses) are the spec's conversion of the global float bake's rows
 *   to within their float rounding, each clip's first row with w >= 0 and each row's quaternion on
 *   the side of the row before's. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <limits.h>
#include <math.h>

#include "crowdbake_pal.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"

typedef struct ref_row {
    char clip[96];
    int frame, joint;
    double t, m[16];
} ref_row;

/* Every row of a reference CSV (see ../shared/reference/README.md); skin 0 only. */
static ref_row *read_reference(const char *path, size_t *count)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t cap = 4096, n = 0;
    ref_row *rows = malloc(cap * sizeof *rows);
    char line[4096];
    bool header = false;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#' || !header) {
            header = header || line[0] != '#';
            continue;
        }
        if (n == cap) rows = realloc(rows, (cap *= 2) * sizeof *rows);
        ref_row *r = &rows[n];
        char *p = strchr(line, ',') + 1, *end = strchr(p, ',');
        bool quoted = *p == '"'; /* names are quoted */
        snprintf(r->clip, sizeof r->clip, "%.*s", (int)(end - p) - 2 * quoted, p + quoted);
        r->frame = (int)strtol(end + 1, &p, 10);
        strtol(p + 1, &p, 10);   /* frames */
        r->t = strtod(p + 1, &p);
        int skin = (int)strtol(p + 1, &p, 10);
        r->joint = (int)strtol(p + 1, &p, 10);
        for (int k = 0; k < 16; ++k) r->m[k] = strtod(p + 1, &p);
        n += skin == 0;
    }
    fclose(f);
    *count = n;
    return rows;
}

/* Largest distance between where two matrices put the joint's bind position and points `reach`
 * from it on each axis (bind space). */
static double point_distance(const float *a, const double *b, const float *bind, double reach)
{
    double worst = 0;
    for (int i = 0; i < 7; ++i) {
        double p[3] = {bind[0], bind[1], bind[2]};
        if (i) p[(i - 1) / 2] += (i % 2 ? reach : -reach);
        double d2 = 0;
        for (int r = 0; r < 3; ++r) {
            double x = a[12 + r] - b[12 + r];
            for (int c = 0; c < 3; ++c) x += (a[c * 4 + r] - b[c * 4 + r]) * p[c];
            d2 += x * x;
        }
        worst = fmax(worst, sqrt(d2));
    }
    return worst;
}

/* The worst point distance at every row of every one-shot the reference holds at the same time, as the
 * header reader gives the rows. */
static double worst_at_rows(const cbpal_file *f, const ref_row *ref, size_t count)
{
    double worst = 0, reach = 0.1 * f->header.model_height;
    size_t compared = 0;
    for (size_t i = 0; i < count; ++i) {
        for (uint32_t c = 0; c < f->header.clip_count; ++c) {
            cbpal_clip clip;
            cbpal_get_clip(f, c, &clip);
            /* one-shots, whose rows lie at the reference's times (a loop is closed: its poses move by the
             * mismatch spread over it, docs/usage.md), at the same time */
            if (strcmp(clip.name, ref[i].clip) != 0 || (clip.flags & CBPAL_CLIP_LOOPS) || (uint32_t)ref[i].frame >= clip.frames ||
                fabs(clip.start + ref[i].frame / (double)clip.fps - ref[i].t) > 1e-5)
                continue;
            float m[16];
            cbpal_bone bone;
            cbpal_get_bone(f, (uint32_t)ref[i].joint, &bone);
            assert_int_equal(cbpal_bone_matrix(f, c, ((double)ref[i].frame + 1e-9) / clip.fps, (uint32_t)ref[i].joint, m), 0);
            const double *c0 = ref[i].m; /* a tenth of the height in bind space: the rigs scale their bind space */
            double d = point_distance(m, ref[i].m, bone.bind_position, reach / sqrt(c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2]));
            worst = fmax(worst, d);
            ++compared;
        }
    }
    assert_true(compared > 1000);
    return worst;
}

/* The worst vertex error halfway between rows and at random times, every clip (cb_verify_clip). */
static double worst_between(const char *model_path, const cbpal_file *f)
{
    cb_model *m = load_or_fail(model_path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_palette view;
    assert_non_null(s);
    assert_int_equal(cb_palette_view(f, &view, &err), CB_OK);
    double worst = 0;
    for (uint32_t c = 0; c < view.clip_count; ++c) {
        int32_t a = -1;
        for (uint32_t k = 0; k < m->animation_count; ++k)
            if (!strcmp(m->animations[k].name, view.clips[c].name)) a = (int32_t)k;
        assert_true(a >= 0);
        cb_clip_error e;
        assert_int_equal(cb_verify_clip(s, &view, f->texels, c, a, 16, &e, &err), CB_OK);
        worst = fmax(worst, e.interp_max);
    }
    cb_palette_view_free(&view);
    cb_sampler_free(s);
    cb_model_free(m);
    return worst;
}

static void bake(const char *model, const char *options, const char *out, cbpal_file *f)
{
    char log[8192], err[256];
    int rc = run_crowdbake(log, sizeof log, "bake %s -o %s --layout qpos --precision u16 -q %s", model, out, options);
    if (rc) fail_msg("bake failed (%d): %s", rc, log);
    if (cbpal_open(out, CBPAL_VERIFY_CHECKSUM, f, err, sizeof err)) fail_msg("%s", err);
}

/* Between rows at `fps`: the worst vertex error of the local and the global bake (model units). */
static void between_rows(const char *model, const char *stem, int fps, double *local_error, double *global_error)
{
    char path[2][256], options[2][64];
    for (int i = 0; i < 2; ++i) {
        cbpal_file f;
        snprintf(path[i], sizeof path[i], TEST_TMP "/local_rows_%s_%s%d.pal", stem, i ? "global" : "local", fps);
        snprintf(options[i], sizeof options[i], "--fps %d%s", fps, i ? " --bone-space global" : "");
        bake(model, options[i], path[i], &f);
        assert_int_equal(f.header.version >= 6, i == 0); /* version 6 only with local rows, */
        assert_int_equal((f.header.flags & CBPAL_FLAG_LOCAL_ROWS) != 0, i == 0); /* which bit 5 says */
        *(i ? global_error : local_error) = worst_between(model, &f);
        cbpal_close(&f);
    }
}

static void check_model(const char *asset, const char *reference, const char *stem)
{
    char model[1024], csv[1024], local_path[256], global_path[256];
    shared_path(model, sizeof model, asset);
    shared_path(csv, sizeof csv, reference);
    snprintf(local_path, sizeof local_path, TEST_TMP "/local_rows_%s_local.pal", stem);
    snprintf(global_path, sizeof global_path, TEST_TMP "/local_rows_%s_global.pal", stem);
    cbpal_file local, global;
    bake(model, "--fps 30 --bone-space local", local_path, &local);
    bake(model, "--fps 30", global_path, &global);
    assert_int_equal(local.header.rows, global.header.rows); /* the same rate, the same rows */
    size_t count = 0;
    ref_row *ref = read_reference(csv, &count);
    double h = local.header.model_height;
    double rows_local = worst_at_rows(&local, ref, count), rows_global = worst_at_rows(&global, ref, count);
    double mid30[2], mid24[2];
    between_rows(model, stem, 30, &mid30[0], &mid30[1]);
    between_rows(model, stem, 24, &mid24[0], &mid24[1]);
    printf("  %s: at the rows vs the reference (30 fps): local %.3g mm/m, global %.3g mm/m; between rows, local vs "
           "global: 30 fps %.3g vs %.3g mm/m, 24 fps (the keys' rate) %.3g vs %.3g mm/m\n", stem, 1000 * rows_local / h,
           1000 * rows_global / h, 1000 * mid30[0] / h, 1000 * mid30[1] / h, 1000 * mid24[0] / h, 1000 * mid24[1] / h);
    assert_true(rows_local < 1e-3 * h);        /* the u16 encoding composed down the chain: under 1 mm/m */
    assert_true(rows_local < 10 * rows_global); /* and of the order of the global rows' */
    /* At the keys' rate the local blend is the source's own interpolation: a fraction of the global
     * blend's chords. Off it (30 fps over 24 fps keys) both cut the keys' kinks, about alike. */
    assert_true(mid24[0] < 0.2 * mid24[1]);
    assert_true(mid30[0] < 1.5 * mid30[1]);
    free(ref);
    cbpal_close(&local);
    cbpal_close(&global);
}

static void test_cow_local_rows(void **state)
{
    (void)state;
    check_model("assets/quaternius-cow/Cow.glb", "reference/Cow.fps30.csv", "cow");
}

static void test_husky_local_rows(void **state)
{
    (void)state;
    check_model("assets/quaternius-husky/Husky.glb", "reference/Husky.fps30.csv", "husky");
}

/* Local rows need qpos and u16 or float, and a .pal: each refusal one line, exit 2, nothing written. */
static void test_local_rows_refuse_what_cannot_hold_them(void **state)
{
    (void)state;
    char model[1024], log[4096];
    sample_path(model, sizeof model, "quadruped");
    static const char *const refused[][2] = {{"--precision half", "half"}, {"--layout mat4", "qpos"},
                                             {"--format exr", "only a .pal"}};
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; ++i) {
        remove(TEST_TMP "/local_refused.pal"), remove(TEST_TMP "/local_refused.exr");
        int rc = run_crowdbake(log, sizeof log, "bake %s --bone-space local %s -o " TEST_TMP "/local_refused.pal", model,
                               refused[i][0]);
        printf("  %s: %s", refused[i][0], log);
        assert_int_equal(rc, EXIT_USAGE);
        assert_non_null(strstr(log, refused[i][1]));
        assert_non_null(strstr(log, "--bone-space"));
        assert_null(strchr(log, '\n') == log + strlen(log) - 1 ? NULL : log); /* one line */
        assert_false(exists(TEST_TMP "/local_refused.pal") || exists(TEST_TMP "/local_refused.exr"));
    }
}

/* The decision said: inspect's line and range table, bake --json's bone_space and its reason (local: the
 * default; global: asked for); a global bake's inspect says no local rows. */
static void test_local_rows_are_stated(void **state)
{
    (void)state;
    char model[1024], log[16384];
    sample_path(model, sizeof model, "quadruped");
    assert_int_equal(run_crowdbake(log, sizeof log, "bake %s --fps 30 -o " TEST_TMP "/stated.pal --json", model), 0);
    assert_non_null(strstr(log, "\"bone_space\": \"local\""));
    assert_non_null(strstr(log, "\"bone_space_why\": \"local rows (the default for a .pal of qpos rows): each bone in its "
                                "parent's frame"));
    assert_int_equal(run_crowdbake(log, sizeof log, "inspect " TEST_TMP "/stated.pal"), 0);
    assert_non_null(strstr(log, "crowdbake palette v6"));
    assert_non_null(strstr(log, "bones: local (composed by the runtime); range table: 41 bones"));
    assert_int_equal(run_crowdbake(log, sizeof log, "inspect " TEST_TMP "/stated.pal --json"), 0);
    assert_non_null(strstr(log, "\"bone_ranges\""));
    assert_int_equal(run_crowdbake(log, sizeof log, "bake %s --fps 30 --bone-space global -o " TEST_TMP "/stated.pal --json",
                                   model), 0);
    assert_non_null(strstr(log, "\"bone_space\": \"global\""));
    assert_non_null(strstr(log, "global rows (bone space global, asked for)"));
    assert_int_equal(run_crowdbake(log, sizeof log, "inspect " TEST_TMP "/stated.pal"), 0);
    assert_null(strstr(log, "bones: local"));
}

/* bake --json of a local bake with timed clips (Husky's Gallop and Jump_ToIdle: their rows on their keys, .pal
 * version 7) says each one's map (timed_rows, map_rows, cells), as docs/bake.schema.json defines them. */
static void test_timed_clips_json_is_valid(void **state)
{
    (void)state;
    char model[1024], log[16384];
    shared_path(model, sizeof model, "assets/quaternius-husky/Husky.glb");
    assert_int_equal(run_crowdbake(log, sizeof log, "bake %s --clip 'AnimalArmature|Gallop,AnimalArmature|Jump_ToIdle' "
                                   "--bone-space local -o " TEST_TMP "/timed.pal --json -q > " TEST_TMP "/timed.json", model), 0);
    size_t size = 0;
    char *json = read_whole_file(TEST_TMP "/timed.json", &size);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"timed_rows\": "));
    assert_non_null(strstr(json, "\"map_rows\": "));
    free(json);
    assert_schema_valid("docs/bake.schema.json", TEST_TMP "/timed.json");
}

/* One catalog, one model, two bone spaces: the goat takes the default (local rows), the sheep asks for global. Types
 * with equal plans share their rate search (roster_plans.c), so the bone space must keep them apart: each .pal holds
 * its own rows, the manifest says which and why, and a second run finds both up to date. */
static void catalog_bone_space(const char *name, const char *pal, cbpal_file *f)
{
    char path[512], err[256];
    snprintf(path, sizeof path, TEST_TMP "/spaces/out/%s", pal);
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, f, err, sizeof err)) fail_msg("%s: %s", name, err);
}

static void test_a_catalog_mixes_bone_spaces(void **state)
{
    (void)state;
    char model[1024], abs_model[PATH_MAX], text[2 * PATH_MAX + 256], log[1 << 16];
    sample_path(model, sizeof model, "quadruped");
    assert_non_null(realpath(model, abs_model));
    assert_int_equal(system("rm -rf " TEST_TMP "/spaces && mkdir -p " TEST_TMP "/spaces"), 0);
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out\"\nroot_motion = \"in-place\"\n[animal.goat]\nmodel = \"%s\"\n"
             "[animal.sheep]\nmodel = \"%s\"\nbone_space = \"global\"\n", abs_model, abs_model);
    write_text(TEST_TMP "/spaces/herd.toml", text);
    assert_int_equal(run_crowdbake(log, sizeof log, "bake " TEST_TMP "/spaces/herd.toml -q"), 0);
    cbpal_file goat, sheep;
    catalog_bone_space("goat", "goat.pal", &goat), catalog_bone_space("sheep", "sheep.pal", &sheep);
    assert_true(goat.header.flags & CBPAL_FLAG_LOCAL_ROWS);
    assert_false(sheep.header.flags & CBPAL_FLAG_LOCAL_ROWS);
    assert_true(goat.header.rows < sheep.header.rows); /* the same clips within 1 mm/m in fewer local rows */
    cbpal_close(&goat), cbpal_close(&sheep);
    char *manifest = read_whole_file(TEST_TMP "/spaces/out/roster.json", NULL);
    assert_non_null(manifest);
    const char *g = strstr(manifest, "\"bone_space\": \"local\""), *h = strstr(manifest, "\"bone_space\": \"global\"");
    assert_true(g && h);
    assert_non_null(strstr(manifest, "local rows (the default for a .pal of qpos rows)"));
    assert_non_null(strstr(manifest, "global rows (bone space global, asked for)"));
    free(manifest);
    assert_int_equal(run_crowdbake(log, sizeof log, "bake " TEST_TMP "/spaces/herd.toml"), 0);
    if (!strstr(log, "2 up to date")) fail_msg("%s", log);
}

/* The spec's u16 encoding of one local value (docs/pal-format.md "Local rows"): a quaternion
 * component snorm16, a position unorm16 over its bone's [pos_min, pos_max], the scale over
 * [0, scale_max]; rounded to nearest, ties to even. */
static uint16_t spec_code(float v, int i, const cbpal_bone *b)
{
    if (i < 4) return (uint16_t)(int16_t)lrint((v < -1 ? -1 : v > 1 ? 1 : (double)v) * 32767);
    double lo = i < 7 ? b->pos_min[i - 4] : 0, hi = i < 7 ? b->pos_max[i - 4] : b->scale_max;
    double x = hi > lo ? (v - lo) / (hi - lo) : 0;
    return (uint16_t)lrint((x < 0 ? 0 : x > 1 ? 1 : x) * 65535);
}

/* The float bake and the u16 bake at one rate hold the same local rows: every u16 code is the
 * float bake's value encoded by the spec's rule, and every bone's range table entry is the box of
 * its float values (the u16 file's own table, which it decodes with). */
static void check_u16_is_float_encoded(const char *asset, const char *stem)
{
    char model[1024], path[2][256];
    shared_path(model, sizeof model, asset);
    cbpal_file f[2];
    for (int i = 0; i < 2; ++i) {
        snprintf(path[i], sizeof path[i], TEST_TMP "/local_rows_%s_%s.pal", stem, i ? "u16" : "float");
        char log[8192], err[256];
        int rc = run_crowdbake(log, sizeof log, "bake %s -o %s --fps 30 --precision %s -q", model, path[i], i ? "u16" : "float");
        if (rc) fail_msg("bake failed (%d): %s", rc, log);
        if (cbpal_open(path[i], CBPAL_VERIFY_CHECKSUM, &f[i], err, sizeof err)) fail_msg("%s", err);
        assert_true(f[i].header.flags & CBPAL_FLAG_LOCAL_ROWS);
        assert_false(f[i].header.flags & CBPAL_FLAG_TIMED_ROWS); /* a fixed rate: every row holds bones */
    }
    assert_int_equal(f[0].header.rows, f[1].header.rows);
    uint64_t values = 0, codes_off = 0;
    for (uint32_t j = 0; j < f[1].header.bone_count; ++j) {
        cbpal_bone b, bf;
        assert_int_equal(cbpal_get_bone(&f[1], j, &b), 0);
        assert_int_equal(cbpal_get_bone(&f[0], j, &bf), 0);
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, smax = 0;
        for (uint32_t r = 0; r < f[1].header.rows; ++r) {
            uint32_t x, y, xf, yf;
            cbpal_texel_xy(&f[1].header, r, j, &x, &y);
            cbpal_texel_xy(&f[0].header, r, j, &xf, &yf);
            const unsigned char *code = (const unsigned char *)f[1].texels + ((size_t)y * f[1].header.width + x) * 8;
            const unsigned char *vf = (const unsigned char *)f[0].texels + ((size_t)yf * f[0].header.width + xf) * 16;
            for (int i = 0; i < 8; ++i, ++values) {
                float v;
                memcpy(&v, vf + i * 4, 4);
                uint16_t got = (uint16_t)(code[i * 2] | code[i * 2 + 1] << 8);
                codes_off += got != spec_code(v, i, &b);
                if (i >= 4 && i < 7) lo[i - 4] = fminf(lo[i - 4], v), hi[i - 4] = fmaxf(hi[i - 4], v);
                if (i == 7) smax = fmaxf(smax, v);
            }
        }
        for (int k = 0; k < 3; ++k) { /* the box of the float values, in both files */
            assert_true(b.pos_min[k] == lo[k] && b.pos_max[k] == hi[k]);
            assert_true(bf.pos_min[k] == lo[k] && bf.pos_max[k] == hi[k]);
        }
        assert_true(b.scale_max == smax && bf.scale_max == smax);
    }
    printf("  %s: %llu u16 values, %llu not the float value encoded\n", stem, (unsigned long long)values,
           (unsigned long long)codes_off);
    assert_true(values > 0);
    assert_int_equal(codes_off, 0);
    cbpal_close(&f[0]), cbpal_close(&f[1]);
}

/* A bone's 8 float values at row r (RGBA32F, two texels). */
static const float *float_values(const cbpal_file *f, uint32_t r, uint32_t j)
{
    uint32_t x, y;
    cbpal_texel_xy(&f->header, r, j, &x, &y);
    return (const float *)f->texels + ((size_t)y * f->header.width + x) * 4;
}

/* The local float bake against the spec's conversion (docs/pal-format.md "Row content"), done
 * here in double from the global float bake's rows at the same rate: the same transforms, to
 * within the rounding of the global floats the conversion starts from (the bake starts from the
 * double poses). The quaternion's sign is the bake's own choice, checked as the spec states it. */
static void check_local_is_global_converted(const char *asset, const char *stem)
{
    char model[1024], path[2][256];
    shared_path(model, sizeof model, asset);
    cbpal_file f[2]; /* global, local */
    for (int i = 0; i < 2; ++i) {
        snprintf(path[i], sizeof path[i], TEST_TMP "/convert_%s_%s.pal", stem, i ? "local" : "global");
        char log[8192], err[256];
        int rc = run_crowdbake(log, sizeof log, "bake %s -o %s --fps 30 --precision float --bone-space %s -q", model,
                               path[i], i ? "local" : "global");
        if (rc) fail_msg("bake failed (%d): %s", rc, log);
        if (cbpal_open(path[i], CBPAL_VERIFY_CHECKSUM, &f[i], err, sizeof err)) fail_msg("%s", err);
    }
    assert_int_equal(f[0].header.rows, f[1].header.rows);
    assert_int_equal(f[0].header.clip_count, f[1].header.clip_count);
    double worst_q = 0, worst_p = 0, worst_s = 0;
    uint32_t flips = 0, first_w_negative = 0;
    for (uint32_t c = 0; c < f[1].header.clip_count; ++c) {
        cbpal_clip clip;
        assert_int_equal(cbpal_get_clip(&f[1], c, &clip), 0);
        for (uint32_t r = clip.first_row; r < clip.first_row + clip.frames; ++r)
            for (uint32_t j = 0; j < f[1].header.bone_count; ++j) {
                cbpal_bone b;
                assert_int_equal(cbpal_get_bone(&f[1], j, &b), 0);
                const float *g = float_values(&f[0], r, j), *l = float_values(&f[1], r, j);
                double q[4] = {g[0], g[1], g[2], g[3]}, p[3] = {g[4], g[5], g[6]}, s = g[7];
                if (b.parent >= 0) { /* q_L = conj(q_p) q_j, s_L = s_j / s_p, p_L = b_p + rotate(conj(q_p), p_j - p_p) / s_p */
                    const float *a = float_values(&f[0], r, (uint32_t)b.parent);
                    cbpal_bone pb;
                    assert_int_equal(cbpal_get_bone(&f[1], (uint32_t)b.parent, &pb), 0);
                    double ix = -a[0], iy = -a[1], iz = -a[2], iw = a[3], v[3] = {g[4] - a[4], g[5] - a[5], g[6] - a[6]};
                    double qm[4] = {iw * g[0] + ix * g[3] + iy * g[2] - iz * g[1], iw * g[1] - ix * g[2] + iy * g[3] + iz * g[0],
                                    iw * g[2] + ix * g[1] - iy * g[0] + iz * g[3], iw * g[3] - ix * g[0] - iy * g[1] - iz * g[2]};
                    double u[3] = {iy * v[2] - iz * v[1], iz * v[0] - ix * v[2], ix * v[1] - iy * v[0]};
                    double uu[3] = {iy * u[2] - iz * u[1], iz * u[0] - ix * u[2], ix * u[1] - iy * u[0]};
                    for (int k = 0; k < 3; ++k) p[k] = pb.bind_position[k] + (v[k] + 2 * (iw * u[k] + uu[k])) / a[7];
                    memcpy(q, qm, sizeof q);
                    s = g[7] / a[7];
                }
                double dot = q[0] * l[0] + q[1] * l[1] + q[2] * l[2] + q[3] * l[3], sign = dot < 0 ? -1 : 1;
                for (int k = 0; k < 4; ++k) worst_q = fmax(worst_q, fabs(sign * q[k] - l[k]));
                for (int k = 0; k < 3; ++k) worst_p = fmax(worst_p, fabs(p[k] - l[4 + k]));
                worst_s = fmax(worst_s, fabs(s - l[7]) / fabs(s));
                if (r == clip.first_row) first_w_negative += l[3] < 0;
                else {
                    const float *before = float_values(&f[1], r - 1, j);
                    flips += l[0] * before[0] + l[1] * before[1] + l[2] * before[2] + l[3] * before[3] < 0;
                }
            }
    }
    printf("  %s: local rows against the converted global rows: quaternion %.3g, position %.3g units (model %.3g "
           "tall), scale %.3g relative; %u first rows with w < 0, %u rows off the side of the row before\n", stem,
           worst_q, worst_p, f[1].header.model_height, worst_s, first_w_negative, flips);
    assert_true(worst_q < 1e-6);                             /* a few float steps of a unit quaternion */
    assert_true(worst_p < 1e-6 * f[1].header.model_height);  /* a micrometre on a metre */
    assert_true(worst_s < 1e-6);
    assert_int_equal(first_w_negative, 0);
    assert_int_equal(flips, 0);
    cbpal_close(&f[0]), cbpal_close(&f[1]);
}

/* Both ways a bake makes local rows: Cow and Husky are matrix rigs (sampled global, then converted:
 * localize_clip), Fox a similarity rig (sampled local from the sampler's lanes: local_rows_from_lanes). */
static void test_float_local_rows_are_the_global_rows_converted(void **state)
{
    (void)state;
    check_local_is_global_converted("assets/quaternius-cow/Cow.glb", "cow");
    check_local_is_global_converted("assets/quaternius-husky/Husky.glb", "husky");
    check_local_is_global_converted("assets/fox-bevy/Fox.glb", "fox");
}

static void test_u16_local_rows_are_the_float_rows_encoded(void **state)
{
    (void)state;
    check_u16_is_float_encoded("assets/quaternius-cow/Cow.glb", "cow");
    check_u16_is_float_encoded("assets/quaternius-husky/Husky.glb", "husky");
}

int main(void)
{
    mkdir(TEST_TMP, 0755);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cow_local_rows),
        cmocka_unit_test(test_husky_local_rows),
        cmocka_unit_test(test_local_rows_refuse_what_cannot_hold_them),
        cmocka_unit_test(test_local_rows_are_stated),
        cmocka_unit_test(test_timed_clips_json_is_valid),
        cmocka_unit_test(test_a_catalog_mixes_bone_spaces),
        cmocka_unit_test(test_u16_local_rows_are_the_float_rows_encoded),
        cmocka_unit_test(test_float_local_rows_are_the_global_rows_converted),
    };
    return cmocka_run_group_tests_name("local_rows", tests, NULL, NULL);
}
