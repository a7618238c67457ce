/* test_measure_bound.c - the bake measures its errors by branch and bound (src/core/error_bound.h):
 * the per-group bounds (src/core/vertex_groups.h) really bound what skinning computes, over a
 * partition of the skinned vertices, the maxima equal those of
 * skinning every vertex of every row (recomputed here row by row, bit for bit) on any thread
 * count (one job per clip or two), an error goal
 * only shortens measurements past it, and fps = "auto" chooses the same rates on any thread
 * count. Past the measuring budget, measure_all measures every row. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <math.h>

#include <limits.h>

#include "crowdbake_pal.h"
#include "../../src/core/error_bound.h"
#include "../../src/core/palette_bake.h" /* palette_choose_rates, palette_bake_with_facts */
#include "../../src/core/pose_cache.h"
#include "../../src/core/vertex_groups.h"
#include "crowdbake/palette.h"
#include "crowdbake/runtime.h"

/* The worst vertex displacement skinning `diff` gives. */
static double skinned_worst(const cb_model *m, int32_t skin, const double *diff, double *pos)
{
    double worst = 0;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin) continue;
        cb_skin_positions(prim, diff, pos);
        for (uint64_t v = 0; v < (uint64_t)prim->vertex_count * 3; v += 3)
            worst = fmax(worst, pos[v] * pos[v] + pos[v + 1] * pos[v + 1] + pos[v + 2] * pos[v + 2]);
    }
    return sqrt(worst);
}

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double uniform(void) /* -1..1 */
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) / (double)(1ull << 52) - 1;
}

/* Per joint: a random difference of the kind `kind` names: 0 a small rotation about the bind
 * position plus a small translation (an encoding's error), 1 a shrink towards the bind position
 * (a blend's chord), 2 any small 3x4 (a bound must not rely on the others' shape). */
static void random_differences(double *diff, uint32_t bones, const float *bind, int kind)
{
    for (uint32_t j = 0; j < bones; ++j) {
        double *D = diff + (size_t)j * 16, w[3] = {uniform(), uniform(), uniform()}, eps = 1e-3 * uniform();
        const float *b = bind + (size_t)j * 3;
        memset(D, 0, 16 * sizeof *D);
        if (kind == 0)
            D[1] = eps * w[2], D[2] = -eps * w[1], D[4] = -eps * w[2], D[6] = eps * w[0], D[8] = eps * w[1], D[9] = -eps * w[0];
        else if (kind == 1)
            D[0] = D[5] = D[10] = -fabs(eps);
        else
            for (int c = 0; c < 3; ++c)
                for (int r = 0; r < 3; ++r) D[c * 4 + r] = eps * uniform();
        for (int r = 0; r < 3; ++r)
            D[12 + r] = -(D[r] * b[0] + D[4 + r] * b[1] + D[8 + r] * b[2]) + (kind == 1 ? 0 : 1e-4 * uniform());
    }
}

/* The groups cover every skinned vertex with a non-zero weight exactly once; each group's bound
 * (both forms) is at least what skinning its vertices gives, which equals cb_skin_positions'
 * result bit for bit, and the row's cap (cb_row_error_cap) at least every group's cheap bound;
 * and the row's largest group bound stays close to the row's worst. */
static void expect_group_bounds(const char *rel, cb_layout layout)
{
    cb_model *m = load_shared(rel);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = layout;
    cb_palette p;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
    cb_vertex_groups g;
    assert_true(cb_vertex_groups_build(m, 0, p.bind_positions, &g));
    uint64_t verts = cb_model_skin_vertex_count(m, 0), covered = 0, moved = 0;
    uint32_t bones = p.bone_count, *first = calloc(m->primitive_count + 1, sizeof *first);
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) first[pi + 1] = first[pi] + m->primitives[pi].vertex_count;
    uint32_t *seen = calloc(first[m->primitive_count] + 1, sizeof *seen); /* groups holding each vertex */
    double *diff = calloc((size_t)bones * 16, sizeof *diff), *pos = malloc(verts * 3 * sizeof *pos);
    cb_joint_error *je = malloc(bones * sizeof *je);
    for (uint32_t k = 0; k < g.group_count; ++k) {
        assert_true(g.groups[k].count > 0 && g.groups[k].count <= CB_VERTEX_GROUP_SIZE);
        for (uint32_t n = 0; n < g.groups[k].count; ++n, ++covered)
            seen[first[g.groups[k].primitive] + g.vertices[g.groups[k].first + n]]++;
    }
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        for (uint32_t v = 0; v < prim->vertex_count; ++v) {
            const float *w = prim->weights + (size_t)v * 4;
            bool moves = prim->skin == 0 && (w[0] != 0 || w[1] != 0 || w[2] != 0 || w[3] != 0);
            moved += moves;
            if (seen[first[pi] + v] != (moves ? 1u : 0u)) fail_msg("%s: primitive %u vertex %u in %u groups", rel, pi, v, seen[first[pi] + v]);
        }
    }
    assert_true(covered == moved && moved > 0);
    double *reach = calloc(bones, sizeof *reach), weight_sum = 0; /* as palette_skin_facts_build takes them */
    for (uint32_t k = 0; k < g.group_count; ++k) {
        weight_sum = fmax(weight_sum, g.groups[k].weight_sum);
        for (uint32_t i = 0; i < g.groups[k].joint_count; ++i) {
            const cb_group_joint *gj = &g.joints[g.groups[k].joint_first + i];
            reach[gj->joint] = fmax(reach[gj->joint], gj->reach);
        }
    }
    double loosest[3] = {0, 0, 0};
    for (int trial = 0; trial < 90; ++trial) {
        random_differences(diff, bones, p.bind_positions, trial % 3);
        assert_true(cb_joint_errors(diff, bones, p.bind_positions, je));
        double row_bound = 0, row_worst = 0, cap = cb_row_error_cap(je, bones, reach, weight_sum);
        for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
            const cb_primitive *prim = &m->primitives[pi];
            if (prim->skin != 0) continue;
            cb_skin_positions(prim, diff, pos);
            for (uint32_t k = 0; k < g.group_count; ++k) {
                const cb_vertex_group *grp = &g.groups[k];
                if (grp->primitive != pi) continue;
                double brute = 0; /* from cb_skin_positions, as the bake measured before groups */
                for (uint32_t n = 0; n < grp->count; ++n) {
                    const double *e = pos + (size_t)g.vertices[grp->first + n] * 3;
                    brute = fmax(brute, e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                }
                double worst = cb_skin_group_worst(prim, g.vertices + grp->first, grp->count, diff);
                double tight = cb_group_error_bound(&g, k, je, 0), cheap = cb_group_error_bound(&g, k, je, INFINITY);
                if (worst != brute) fail_msg("%s: group %u skins to %.17g, cb_skin_positions %.17g", rel, k, worst, brute);
                if (!(tight >= sqrt(worst) && cheap >= tight))
                    fail_msg("%s trial %d group %u: bounds %.9g / %.9g under the skinned error %.9g", rel, trial, k, tight, cheap, sqrt(worst));
                if (!(cap >= cheap)) fail_msg("%s trial %d group %u: the row's cap %.17g under its bound %.17g", rel, trial, k, cap, cheap);
                row_bound = fmax(row_bound, tight), row_worst = fmax(row_worst, sqrt(worst));
            }
        }
        loosest[trial % 3] = fmax(loosest[trial % 3], row_bound / row_worst);
    }
    /* Loose bounds would skin everything: within 2.5x of the truth for these differences (Fox:
     * 1.64, 1.37, 1.81; Cow: 1.26, 1.97, 1.26 by kind). */
    for (int kind = 0; kind < 3; ++kind)
        if (loosest[kind] > 2.5) fail_msg("%s: a row's group bound up to %.2fx its skinned error", rel, loosest[kind]);
    free(first), free(seen), free(diff), free(pos), free(je), free(reach);
    cb_vertex_groups_free(&g);
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_group_bounds_hold(void **state)
{
    (void)state;
    expect_group_bounds("assets/fox-bevy/Fox.glb", CB_LAYOUT_QPOS);
    expect_group_bounds("assets/quaternius-cow/Cow.glb", CB_LAYOUT_QPOS);
    expect_group_bounds("assets/spider-animated-luanti/gltf_spider_animated.gltf", CB_LAYOUT_AFFINE);
}

/* Skins every measured row, as the bake did before branch and bound, and compares bit for bit. */
static void exhaustive(const cb_model *m, const cb_palette *p, const cb_bake_options *o, double *quant, double *blend)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    uint32_t bones = p->bone_count;
    double *exact = malloc((size_t)bones * 16 * sizeof *exact), *diff = malloc((size_t)bones * 16 * sizeof *diff);
    double *pos = malloc((size_t)cb_model_skin_vertex_count(m, 0) * 3 * sizeof *pos);
    cb_similarity *sims = malloc(bones * sizeof *sims);
    bool similar = p->layout == CB_LAYOUT_QPOS && cb_sampler_is_similarity(s);
    *quant = *blend = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *clip = &p->clips[c];
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, (int32_t)c, o->fps, -1, &o->limits, &info, &err), CB_OK);
        assert_int_equal(info.frames, clip->frames);
        if (info.loops) cb_sampler_set_period(s, info.animation, info.duration);
        for (int between = 0; between < 2; ++between) {
            cb_clip_info framing = info;
            if (between) framing.steps *= 2;
            uint32_t rows = between && !clip->loops ? clip->frames - 1 : clip->frames;
            for (uint32_t f = 0; f < rows; ++f) {
                uint32_t t = between ? 2 * f + 1 : f;
                if (similar) cb_clip_frame_similarities(s, &framing, &t, 1, o->root_motion, sims);
                else cb_clip_frame_matrices(s, &framing, t, o->root_motion, exact);
                for (uint32_t j = 0; j < bones; ++j) {
                    double *d = diff + (size_t)j * 16, *e = exact + (size_t)j * 16;
                    if (similar) cb_similarity_matrix(&sims[j], e);
                    if (between) cb_palette_blend(p, p->texels, clip->first_row + f, clip->first_row + (f + 1) % clip->frames, 0.5, j, d);
                    else cb_palette_decode(p, p->texels, clip->first_row + f, j, d);
                    for (int k = 0; k < 16; ++k) d[k] = e[k] - d[k];
                }
                double worst = skinned_worst(m, 0, diff, pos);
                if (between) *blend = fmax(*blend, worst);
                else *quant = fmax(*quant, worst);
            }
        }
    }
    free(exact), free(diff), free(pos), free(sims);
    cb_sampler_free(s);
}

static void expect_exhaustive_maxima(const char *rel, cb_layout layout, cb_precision precision)
{
    cb_model *m = load_shared(rel);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = layout, o.precision = precision, o.threads = 2;
    cb_palette p;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
    assert_int_equal(p.error_rows_measured, p.rows); /* small models: every row (the budget is not reached) */
    double quant, blend;
    exhaustive(m, &p, &o, &quant, &blend);
    if (!(p.max_error == quant && p.visible_error == fmax(quant, blend)))
        fail_msg("%s %s/%s: measured %.17g / %.17g, every row skinned %.17g / %.17g", rel, cb_layout_name(layout),
                 cb_precision_name(precision), p.max_error, p.visible_error, quant, fmax(quant, blend));
    /* One thread measures a clip's blends and its baked rows in one job, 64 in two (the clips
     * are few for them): the maxima are the same. */
    for (uint32_t threads = 1; threads <= 64; threads *= 64) {
        cb_palette q;
        o.threads = threads;
        assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &q, &err), CB_OK);
        if (!(q.max_error == quant && q.visible_error == fmax(quant, blend)))
            fail_msg("%s %s/%s, %u threads: measured %.17g / %.17g, every row skinned %.17g / %.17g", rel,
                     cb_layout_name(layout), cb_precision_name(precision), threads, q.max_error, q.visible_error, quant,
                     fmax(quant, blend));
        cb_palette_free(&q);
    }
    o.threads = 2;
    /* A goal above the visible error: the same visible error. Below it: past it, found early. */
    double visible = p.visible_error;
    cb_palette_free(&p);
    o.error_goal = visible * 1.5;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
    assert_true(p.visible_error == visible);
    cb_palette_free(&p);
    o.error_goal = visible / 4;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
    assert_true(p.visible_error > o.error_goal && p.visible_error <= visible);
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_maxima_equal_every_row_skinned(void **state)
{
    (void)state;
    expect_exhaustive_maxima("assets/fox-bevy/Fox.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16);
    expect_exhaustive_maxima("assets/fox-bevy/Fox.glb", CB_LAYOUT_MAT4, CB_PRECISION_HALF);
    expect_exhaustive_maxima("assets/quaternius-cow/Cow.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16);
    expect_exhaustive_maxima("assets/spider-animated-luanti/gltf_spider_animated.gltf", CB_LAYOUT_AFFINE, CB_PRECISION_U16);
}

/* The header's two errors, as the .pal at `path` records them (float32). */
static void header_errors(const char *path, float *encoding, float *visible)
{
    cbpal_file f;
    char msg[256];
    if (cbpal_open(path, 0, &f, msg, sizeof msg)) fail_msg("%s: %s", path, msg);
    *encoding = f.header.max_error, *visible = f.header.visible_error;
    cbpal_close(&f);
}

/* Cow.glb at 60 fps is past the measuring budget (1,485 rows x 4,970 skinned vertices): by
 * default its errors are measured at an even subset of the rows, which finds less than every
 * row (never more) and says so; measure_all (--measure-all, measure_all = true) finds what
 * skinning every vertex of every row finds, with the same texels, and counts in what is up to
 * date. robot.glb at 30 fps, past the vertex-rows but within the rows (589 x 7,218), is measured
 * at every row by default. */
static void test_measure_all_past_the_budget(void **state)
{
    (void)state;
    cb_error err = {0};
    cb_bake_options o = cb_default_bake_options();
    o.threads = 2;
    cb_palette subset, all;
    cb_model *robot = load_shared("assets/robot-quaternius-raylib/robot.glb");
    cb_sampler *s = cb_sampler_create(robot, 0, &err);
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &all, &err), CB_OK);
    assert_true(all.rows <= CB_ERROR_ROWS && (uint64_t)all.rows * cb_model_skin_vertex_count(robot, 0) > CB_ERROR_BUDGET);
    assert_int_equal(all.error_rows_measured, all.rows);
    cb_palette_free(&all);
    cb_sampler_free(s);
    cb_model_free(robot);

    const char *rel = "assets/quaternius-cow/Cow.glb";
    cb_model *m = load_shared(rel);
    s = cb_sampler_create(m, 0, &err);
    o.fps = 60;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &subset, &err), CB_OK);
    assert_true(subset.error_rows_measured > 0 && subset.error_rows_measured < subset.rows);
    o.measure_all = true;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &all, &err), CB_OK);
    assert_int_equal(all.error_rows_measured, all.rows);
    assert_int_equal(all.texel_bytes, subset.texel_bytes);
    assert_memory_equal(all.texels, subset.texels, all.texel_bytes);
    double quant, blend;
    exhaustive(m, &all, &o, &quant, &blend);
    if (!(all.max_error == quant && all.visible_error == fmax(quant, blend)))
        fail_msg("%s: measured %.17g / %.17g at every row, every row skinned %.17g / %.17g", rel, all.max_error,
                 all.visible_error, quant, fmax(quant, blend));
    assert_true(subset.max_error <= quant && subset.visible_error <= all.visible_error);
    /* On rows it skips: the blend's worst. (The worst row's encoding error falls in the subset since Gallop_Jump
     * lost its extra key interval, 1,483 rows: 751 measured.) */
    assert_true(subset.visible_error < all.visible_error);

    /* The command line: the bake line says when a subset was measured. */
    char model[PATH_MAX], model_abs[PATH_MAX], cmd[2 * PATH_MAX], text[PATH_MAX + 128], line[128];
    static char out[65536];
    float encoding, visible;
    shared_path(model, sizeof model, rel);
    assert_non_null(realpath(model, model_abs));
    assert_int_equal(system("rm -rf " TEST_TMP "/measure && mkdir -p " TEST_TMP "/measure"), 0);
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TEST_TMP "/measure/subset.pal --fps 60 --bone-space global", crowdbake_exe(), model_abs);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    snprintf(line, sizeof line, "errors measured at %u of the %u rows", subset.error_rows_measured, subset.rows);
    if (!strstr(out, line) || !strstr(out, "--measure-all")) fail_msg("no '%s' in: %s", line, out);
    header_errors(TEST_TMP "/measure/subset.pal", &encoding, &visible);
    assert_true(encoding == (float)subset.max_error && visible == (float)subset.visible_error);
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TEST_TMP "/measure/all.pal --fps 60 --measure-all --bone-space global", crowdbake_exe(), model_abs);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (strstr(out, "errors measured at")) fail_msg("every row was measured: %s", out);
    header_errors(TEST_TMP "/measure/all.pal", &encoding, &visible);
    assert_true(encoding == (float)quant && visible == (float)fmax(quant, blend));

    /* A catalog: measure_all = true bakes as --measure-all; turning it off re-bakes (the
     * header's errors differ); a value that is not a boolean names its line. */
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out\"\nfps = 60\nmeasure_all = true\nbone_space = \"global\"\n[animal.cow]\nmodel = \"%s\"\n", model_abs);
    write_text(TEST_TMP "/measure/c.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TEST_TMP "/measure/c.toml 2>&1", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    header_errors(TEST_TMP "/measure/out/cow.pal", &encoding, &visible);
    assert_true(encoding == (float)quant && visible == (float)fmax(quant, blend));
    if (strstr(out, "measured at")) fail_msg("every row was measured: %s", out);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "1 up to date")) fail_msg("%s", out);
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out\"\nfps = 60\nmeasure_all = false\nbone_space = \"global\"\n[animal.cow]\nmodel = \"%s\"\n", model_abs);
    write_text(TEST_TMP "/measure/c.toml", text);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    snprintf(line, sizeof line, "measured at %u of %u rows", subset.error_rows_measured, subset.rows);
    if (!strstr(out, "1 baked") || !strstr(out, line)) fail_msg("no '%s' in: %s", line, out);
    header_errors(TEST_TMP "/measure/out/cow.pal", &encoding, &visible);
    assert_true(encoding == (float)subset.max_error);
    snprintf(text, sizeof text, "[animal.cow]\nmodel = \"%s\"\nmeasure_all = 1\n", model_abs);
    write_text(TEST_TMP "/measure/bad.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TEST_TMP "/measure/bad.toml 2>&1", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT);
    if (!strstr(out, "bad.toml:3:") || !strstr(out, "measure_all must be true or false")) fail_msg("%s", out);

    cb_palette_free(&subset), cb_palette_free(&all);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_auto_rates_do_not_depend_on_threads(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/quaternius-cow/Cow.glb");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    uint32_t n = m->animation_count;
    cb_clip_plan plan[2][32];
    cb_rate_goal goals[32];
    cb_rate_choice out[2][32];
    assert_true(n <= 32);
    for (int run = 0; run < 2; ++run) {
        cb_bake_options o = cb_default_bake_options();
        o.threads = run ? 3 : 1;
        for (uint32_t i = 0; i < n; ++i) plan[run][i] = (cb_clip_plan){(int32_t)i, NULL, -1, 0, false, false, 0, NULL}, goals[i] = (cb_rate_goal){1, 60, CB_ROWS_SAMPLED};
        assert_int_equal(cb_choose_rates(s, &o, plan[run], n, goals, out[run], &err), CB_OK);
    }
    bool varied = false;
    for (uint32_t i = 0; i < n; ++i) {
        assert_true(plan[0][i].fps == plan[1][i].fps && out[0][i].error == out[1][i].error);
        varied = varied || plan[0][i].fps != plan[0][0].fps;
    }
    assert_true(varied); /* the clips need different rates: the search decided something */
    cb_sampler_free(s);
    cb_model_free(m);
}

/* The bake after a rate search measures each clip's blends from a floor its probes hand it: the
 * final palette's own error at the blend where the probe of the same rows found its worst
 * (pose_cache_note_worst); and it leaves out the blends whose bound in that probe, moved by what
 * the file's u16 box can change (palette_taken_point_bounds), is within that floor, and the
 * baked rows whose cap is within the clip's blends and every baked row measured. Every
 * maximum stays the bits a bake of the same plan with nothing kept (no floor: every blend
 * measured from 0) finds, as do the texels; and the floor is really taken (a point kept for
 * most clips' rows), else this would test nothing. */
static void expect_floors_keep_the_maxima_of(const char *rel, uint32_t first, uint32_t count, uint32_t min_floored)
{
    cb_model *m = load_shared(rel);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    uint32_t n = count ? count : m->animation_count, floored = 0;
    assert_true(n <= 32 && first + n <= m->animation_count);
    cb_clip_plan plan[32];
    cb_rate_goal goals[32];
    cb_rate_choice out[32];
    search_keep *keep = search_keep_create(n);
    assert_non_null(keep);
    pose_cache **kept = keep->poses;
    cb_bake_options o = cb_default_bake_options();
    o.threads = 2;
    for (uint32_t i = 0; i < n; ++i)
        plan[i] = (cb_clip_plan){(int32_t)(first + i), NULL, -1, 0, false, false, 0, NULL},
        goals[i] = (cb_rate_goal){1, 120, CB_ROWS_BEST};
    assert_int_equal(palette_choose_rates(s, &o, plan, n, goals, out, keep, NULL, &err), CB_OK);
    palette_probe probe = {NULL, NULL, kept, NULL, NULL};
    cb_palette floors, fresh;
    assert_int_equal(palette_bake_with_facts(s, &o, plan, n, NULL, &probe, &floors, &err), CB_OK);
    assert_int_equal(cb_palette_bake(s, &o, plan, n, &fresh, &err), CB_OK);
    for (uint32_t c = 0; c < n; ++c) {
        pose_worst at;
        floored += kept[c] && pose_cache_worst(kept[c], floors.clips[c].frames, floors.clips[c].fitted ? 4 : 2, &at);
        if (floors.clips[c].visible_error != fresh.clips[c].visible_error)
            fail_msg("%s clip %u: %.17g from the probe's floor, %.17g from none", rel, c, floors.clips[c].visible_error,
                     fresh.clips[c].visible_error);
    }
    assert_true(floors.max_error == fresh.max_error && floors.visible_error == fresh.visible_error);
    assert_true(floors.texel_bytes == fresh.texel_bytes && !memcmp(floors.texels, fresh.texels, fresh.texel_bytes));
    if (floored < min_floored) fail_msg("%s: a floor for %u of %u clips, expected %u", rel, floored, n, min_floored);
    search_keep_free(keep);
    cb_palette_free(&floors), cb_palette_free(&fresh);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void expect_floors_keep_the_maxima(const char *rel, uint32_t min_floored)
{
    expect_floors_keep_the_maxima_of(rel, 0, 0, min_floored);
}

static void test_floors_from_the_probes_keep_the_maxima(void **state)
{
    (void)state;
    expect_floors_keep_the_maxima("assets/quaternius-cow/Cow.glb", 10);
    expect_floors_keep_the_maxima("assets/fox-bevy/Fox.glb", 3);
    expect_floors_keep_the_maxima("assets/quaternius-husky/Husky.glb", 10);
    expect_floors_keep_the_maxima("assets/robot-quaternius-raylib/robot.glb", 6);
    /* A clip alone: its baked rows within its blends are left out, and as no other clip's baked
     * rows were measured, those that could still be the palette's max_error are measured after
     * (palette_measure_rest). */
    for (uint32_t c = 0; c < 3; ++c) expect_floors_keep_the_maxima_of("assets/fox-bevy/Fox.glb", c, 1, 1);
    expect_floors_keep_the_maxima_of("assets/quaternius-cow/Cow.glb", 0, 2, 2);
}

/* One clip of `rel` baked as a search's probe (one thread, its pose cache and batches of poses),
 * then the same plan baked with nothing kept: the same errors and texels, bit for bit. */
static void expect_probe_as_fresh(cb_sampler *s, const palette_skin_facts *facts, pose_cache *poses, pose_batch *batch,
                                  const cb_clip_plan *plan, double goal)
{
    cb_bake_options o = cb_default_bake_options();
    o.threads = 1, o.error_goal = goal;
    palette_probe probe = {poses, NULL, NULL, batch, NULL};
    cb_palette kept, fresh;
    cb_error err = {0};
    assert_int_equal(palette_bake_with_facts(s, &o, plan, 1, facts, &probe, &kept, &err), CB_OK);
    assert_int_equal(cb_palette_bake(s, &o, plan, 1, &fresh, &err), CB_OK);
    if (kept.visible_error != fresh.visible_error || kept.max_error != fresh.max_error)
        fail_msg("clip %d at %g fps (%s rows, goal %g): errors %.17g / %.17g as a probe, %.17g / %.17g fresh",
                 plan->animation, plan->fps, plan->fit ? "fitted" : "sampled", goal, kept.visible_error, kept.max_error,
                 fresh.visible_error, fresh.max_error);
    assert_true(kept.texel_bytes == fresh.texel_bytes && !memcmp(kept.texels, fresh.texels, fresh.texel_bytes));
    cb_palette_free(&kept), cb_palette_free(&fresh);
}

/* A probe of a rig of similarities (Fox) keeps the lanes its rows were sampled from, and its
 * baked rows (and a fitted probe's after it at the same rate, whose rows start from those) are
 * measured against them, not sampled again (palette_row_lanes_find): the probes' errors are
 * those of bakes that sample them again, measured exactly and within a goal. */
static void test_probes_measure_rows_against_their_lanes(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/fox-bevy/Fox.glb");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    assert_true(cb_sampler_is_similarity(s)); /* else the lanes are never kept */
    palette_skin_facts facts;
    assert_int_equal(palette_skin_facts_build(s, &facts, &err), CB_OK);
    pose_batch *batch = pose_batch_create(s);
    assert_non_null(batch);
    static const double rates[] = {24, 72, 120};
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        pose_cache *poses = palette_probe_poses(NULL, m->skins[0].joint_count, (size_t)64 << 20);
        assert_non_null(poses);
        for (int r = 0; r < 3; ++r)
            for (int fit = 0; fit < 2; ++fit) {
                cb_clip_plan plan = {(int32_t)a, NULL, -1, rates[r], fit, false, 0, NULL};
                expect_probe_as_fresh(s, &facts, poses, batch, &plan, 0);
                expect_probe_as_fresh(s, &facts, poses, batch, &plan, 1e9); /* met: the baked rows after the blends */
                assert_non_null(*pose_batch_row_lanes(batch));
            }
        pose_cache_free(poses);
    }
    pose_batch_free(batch);
    palette_skin_facts_free(&facts);
    cb_sampler_free(s);
    cb_model_free(m);
}

/* Local rows (the default bake's) keep the same measuring budget: Cow at 60 fps (1,483 rows x 4,970 vertices) is
 * measured composed at an even subset of its rows, which the bake line says; --measure-all measures every row and
 * finds at least as much, the texels the same; under the budget (30 fps, 744 rows; Husky's timed default) every
 * row is measured. */
static void test_local_rows_keep_the_measuring_budget(void **state)
{
    (void)state;
    char model[PATH_MAX], cmd[2 * PATH_MAX];
    static char out[65536];
    shared_path(model, sizeof model, "assets/quaternius-cow/Cow.glb");
    assert_int_equal(system("rm -rf " TEST_TMP "/measure-local && mkdir -p " TEST_TMP "/measure-local"), 0);
    static const char *const runs[3] = {"--fps 60", "--fps 60 --measure-all", "--fps 30"};
    float encoding[3], visible[3];
    cbpal_file f[3];
    for (int i = 0; i < 3; ++i) {
        char path[256], err[256];
        snprintf(path, sizeof path, TEST_TMP "/measure-local/%d.pal", i);
        snprintf(cmd, sizeof cmd, "%s bake %s -o %s %s 2>&1", crowdbake_exe(), model, path, runs[i]);
        assert_int_equal(run_command(cmd, out, sizeof out), 0);
        const char *at = strstr(out, "errors measured at ");
        unsigned measured = 0, rows = 0;
        if (at) assert_int_equal(sscanf(at, "errors measured at %u of the %u rows", &measured, &rows), 2);
        printf("  local rows, %s: %s\n", runs[i], at ? "a subset measured" : "every row measured");
        if (i == 0) assert_true(at && measured > 0 && measured < rows && rows == 1483);
        else assert_null(at);
        header_errors(path, &encoding[i], &visible[i]);
        if (cbpal_open(path, 0, &f[i], err, sizeof err)) fail_msg("%s", err);
        assert_true(f[i].header.flags & CBPAL_FLAG_LOCAL_ROWS);
    }
    assert_true(encoding[0] <= encoding[1] && visible[0] <= visible[1] && visible[1] > 0);
    assert_int_equal(f[0].texels_size, f[1].texels_size);
    assert_memory_equal(f[0].texels, f[1].texels, f[0].texels_size);
    for (int i = 0; i < 3; ++i) cbpal_close(&f[i]);
    /* Husky's default bake (514 rows, three clips timed: their map rows counted as the file holds them) is under
     * the budget: every row measured, nothing said. */
    shared_path(model, sizeof model, "assets/quaternius-husky/Husky.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TEST_TMP "/measure-local/husky.pal 2>&1", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (strstr(out, "errors measured at")) fail_msg("%s", out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_group_bounds_hold),
        cmocka_unit_test(test_maxima_equal_every_row_skinned),
        cmocka_unit_test(test_measure_all_past_the_budget),
        cmocka_unit_test(test_local_rows_keep_the_measuring_budget),
        cmocka_unit_test(test_auto_rates_do_not_depend_on_threads),
        cmocka_unit_test(test_floors_from_the_probes_keep_the_maxima),
        cmocka_unit_test(test_probes_measure_rows_against_their_lanes),
    };
    return cmocka_run_group_tests_name("measure_bound", tests, NULL, NULL);
}
