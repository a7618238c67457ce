/* test_motion.c - how baked clips move in a game: loops without a closing key, one-shots that
 * are not speed-synced, the speed reference, ground speed from root travel and planted feet.
 * On a real FBX2glTF export (../shared/assets/quaternius-cow/Cow.glb) and the samples. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>

#include "catalog/catalog_toml.h"
#include "crowdbake_pal.h"
#include "crowdbake/pal_view.h"
#include "roster/roster.h"
#include "catalog/catalog.h"
#include "crowdbake/runtime.h"
#include "internal/plumbing.h"

#define TMP TEST_TMP "/motion"
#define COW "assets/quaternius-cow/Cow.glb"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

static cb_model *load_sample(const char *name)
{
    char path[600];
    sample_path(path, sizeof path, name);
    return load_or_fail(path);
}

static void analyze(cb_sampler *s, const char *clip, int loop, cb_clip_info *info)
{
    cb_error err = {0};
    int32_t a = cb_model_find_animation(cb_sampler_model(s), clip);
    assert_true(a >= 0);
    assert_int_equal(cb_clip_analyze(s, a, 30, loop, NULL, info, &err), CB_OK);
}

/* Skinned positions of every vertex of the skin at row `frame` of a framed clip. */
static void skin_row(cb_sampler *s, const cb_clip_info *info, uint32_t frame, double *mats, double *out)
{
    const cb_model *m = cb_sampler_model(s);
    cb_clip_frame_matrices(s, info, frame, CB_ROOT_MOTION_IN_PLACE, mats);
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        if (m->primitives[p].skin != cb_sampler_skin(s)) continue;
        cb_skin_positions(&m->primitives[p], mats, out);
        out += (size_t)m->primitives[p].vertex_count * 3;
    }
}

static double largest_move(const double *a, const double *b, uint64_t verts)
{
    double worst = 0;
    for (uint64_t v = 0; v < verts * 3; v += 3)
        worst = fmax(worst, sqrt((a[v] - b[v]) * (a[v] - b[v]) + (a[v + 1] - b[v + 1]) * (a[v + 1] - b[v + 1]) +
                                 (a[v + 2] - b[v + 2]) * (a[v + 2] - b[v + 2])));
    return worst;
}

/* FBX2glTF leaves out the closing key: Cow's Gallop has keys every 1/24 s on [0, 0.5833] and its
 * first pose comes round at 0.625 s. It must loop over that period, and the wrap from its last
 * baked row to row 0 must be no bigger a step than any other. */
static void test_gallop_without_closing_key_loops_smoothly(void **state)
{
    (void)state;
    cb_model *m = load_shared(COW);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    cb_clip_info info;
    analyze(s, "AnimalArmature|Gallop", -1, &info);
    assert_true(info.loops);
    assert_int_equal(info.loop_reason, CB_LOOP_OPEN);
    assert_float_equal(info.key_interval, 1.0 / 24, 1e-6);
    assert_float_equal(info.t1 - info.t0, 14.0 / 24, 1e-6);
    assert_float_equal(info.duration, 15.0 / 24, 1e-6); /* the true period */
    assert_int_equal(info.frames, 19);                   /* round(0.625 * 30) rows, no duplicate of row 0 */

    uint64_t verts = cb_model_skin_vertex_count(m, 0);
    double *mats = malloc((size_t)m->skins[0].joint_count * 16 * sizeof(double));
    double *first = malloc(verts * 3 * sizeof(double)), *prev = malloc(verts * 3 * sizeof(double));
    double *cur = malloc(verts * 3 * sizeof(double));
    skin_row(s, &info, 0, mats, first);
    memcpy(prev, first, verts * 3 * sizeof(double));
    double largest = 0, smallest = INFINITY;
    for (uint32_t f = 1; f < info.frames; ++f) {
        skin_row(s, &info, f, mats, cur);
        double step = largest_move(prev, cur, verts);
        largest = fmax(largest, step), smallest = fmin(smallest, step);
        memcpy(prev, cur, verts * 3 * sizeof(double));
    }
    double wrap = largest_move(prev, first, verts);
    double lo[3], hi[3], height = cb_skin_rest_bounds(s, lo, hi);
    printf("  Gallop: wrap step %.4f, other steps %.4f..%.4f units (height %.3f)\n", wrap, smallest, largest, height);
    assert_true(wrap <= largest);
    assert_true(wrap > 0.1 * smallest); /* a real step, not a held pose */
    /* The last row (t = 18/19 of 0.625 s = 0.592 s) lies past the last key (0.583 s), 1/5 of the
     * way to the first pose coming round: nearer to row 0 than the last key's pose is, not
     * clamped to it. */
    cb_clip_info at_last_key = info;
    at_last_key.duration = info.t1 - info.t0, at_last_key.steps = 1;
    skin_row(s, &at_last_key, 1, mats, cur);
    double from_last_key = largest_move(cur, first, verts);
    printf("  last key to row 0: %.4f units\n", from_last_key);
    assert_true(wrap < 0.9 * from_last_key);

    /* A catalog's loop = false still makes it a one-shot, over its keys. */
    analyze(s, "AnimalArmature|Gallop", 0, &info);
    assert_false(info.loops);
    assert_int_equal(info.loop_reason, CB_LOOP_SET);
    assert_int_equal(info.frames, info.steps + 1);
    free(mats), free(first), free(prev), free(cur);
    cb_sampler_free(s);
    cb_model_free(m);
}

/* Loops with their closing key stay loops over their keys; clips that end elsewhere play once. */
static void test_loop_judgements(void **state)
{
    (void)state;
    cb_model *m = load_shared(COW);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info;
    analyze(s, "AnimalArmature|Walk", -1, &info);
    assert_true(info.loops);
    assert_int_equal(info.loop_reason, CB_LOOP_CLOSED);
    assert_float_equal(info.duration, info.t1 - info.t0, 0);
    analyze(s, "AnimalArmature|Death", -1, &info);
    assert_false(info.loops);
    assert_int_equal(info.loop_reason, CB_LOOP_ENDS_ELSEWHERE);
    assert_true(info.wrap_jump > 5 * info.largest_step); /* lying down is far from standing */
    char why[160];
    cb_loop_reason_text(&info, why, sizeof why);
    assert_non_null(strstr(why, "ends elsewhere"));
    cb_sampler_free(s);
    cb_model_free(m);

    m = load_sample("quadruped");
    s = cb_sampler_create(m, 0, &err);
    analyze(s, "walk", -1, &info);
    assert_int_equal(info.loop_reason, CB_LOOP_CLOSED);
    analyze(s, "death", -1, &info);
    assert_false(info.loops);
    cb_sampler_free(s);
    cb_model_free(m);
}

/* `info` says why, and the palette and verify agree that Gallop loops over 0.625 s. */
static void test_info_says_why_and_the_bake_loops(void **state)
{
    (void)state;
    static char out[65536];
    char cow[1024], cmd[4096];
    shared_path(cow, sizeof cow, COW);
    snprintf(cmd, sizeof cmd, "%s info %s", crowdbake_exe(), cow);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "no closing key: wrap") || !strstr(out, "plays once (-") || !strstr(out, "ends elsewhere") ||
        !strstr(out, "loops (+") || !strstr(out, "last pose = first pose"))
        fail_msg("info does not say why:\n%s", out);
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/cow.pal -q && %s verify %s " TMP "/cow.pal --json", crowdbake_exe(),
             cow, crowdbake_exe(), cow);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/cow.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    bool found = false;
    for (uint32_t c = 0; c < f.header.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&f, c, &clip);
        if (strcmp(clip.name, "AnimalArmature|Gallop") != 0) continue;
        found = true;
        assert_true(clip.flags & CBPAL_CLIP_LOOPS);
        assert_int_equal(clip.frames, 19);
        assert_float_equal(clip.duration, 0.625, 1e-6);
    }
    assert_true(found);
    cbpal_close(&f);
}

/* The pack's animal as a game uses it: idle by default, wander -> walk, flee -> gallop,
 * die -> death. */
static void test_catalog_states_move_right(void **state)
{
    (void)state;
    char cow[1024], text[8192];
    shared_path(cow, sizeof cow, COW);
    char cow_abs[PATH_MAX];
    assert_non_null(realpath(cow, cow_abs));
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"out-cow\"\nfps = 30\n\n[animal.cow]\nmodel = \"%s\"\n"
             "states = { idle = [\"Idle\"], wander = [\"Walk\"], flee = [\"Gallop\"], die = [\"Death\"] }\n"
             "default_state = \"idle\"\n",
             cow_abs);
    write_text(TMP "/cow.toml", text);
    cb_catalog cat;
    cb_error err = {0};
    assert_int_equal(cb_catalog_load(TMP "/cow.toml", &cat, &err), CB_OK);
    cb_roster r;
    cb_roster_options opt = {0};
    opt.jobs = 1;
    if (cb_roster_bake(&cat, &opt, &r, &err)) fail_msg("%s", err.message);
    const cb_roster_type *t = &r.types[0];
    const cb_roster_clip *walk = NULL, *gallop = NULL, *death = NULL;
    for (uint32_t s = 0; s < cat.animals[0].state_count; ++s) {
        const char *name = cat.animals[0].states[s].name;
        const cb_roster_clip *c = &t->clips[t->state_clip[s]];
        if (!strcmp(name, "wander")) walk = c;
        if (!strcmp(name, "flee")) gallop = c;
        if (!strcmp(name, "die")) death = c;
    }
    assert_true(walk && gallop && death);
    assert_true(walk->loops && gallop->loops);
    assert_false(death->loops);
    /* The speed reference: idle does not move, so the slowest locomotion loop, the walk. */
    assert_float_equal(t->speed_reference, walk->speed.speed, 0);
    assert_non_null(strstr(t->speed_reference_from, "slowest locomotion state 'wander'"));
    /* Both walk in place: their ground speed is what the planted feet show, not the root's drift. */
    for (const cb_roster_clip *c = walk; c; c = c == walk ? gallop : NULL) {
        printf("  %s: ground %.3f (%s), root %.4f, feet %.3f units/s\n", c->name, c->speed.speed, c->speed.method,
               c->speed.root, c->speed.feet);
        assert_true(fabs(c->speed.speed - c->speed.feet) <= 0.15 * c->speed.feet);
        assert_true(c->speed.root < 0.01 * c->speed.speed);
    }
    assert_true(gallop->speed.speed > 2 * walk->speed.speed);

    /* The manifest's per-instance numbers, as a game reads them. */
    static char out[65536];
    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "python3 -c \"import json; t = json.load(open('%s/out-cow/roster.json'))['types']['cow']; s = t['states']; "
             "c = {x['name']: x for x in t['clips']}; "
             "print(t['speed_reference'], *[' '.join(str(v) for v in (s[k]['instance']['rate'], "
             "s[k]['instance']['rate_per_speed'], s[k]['instance']['frame_count'], c[s[k]['clip']]['ground_speed'], "
             "c[s[k]['clip']]['fps'])) for k in ('wander', 'flee', 'die')])\"",
             TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    double ref, v[3][5];
    assert_int_equal(sscanf(out, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &ref, &v[0][0], &v[0][1],
                            &v[0][2], &v[0][3], &v[0][4], &v[1][0], &v[1][1], &v[1][2], &v[1][3], &v[1][4], &v[2][0],
                            &v[2][1], &v[2][2], &v[2][3], &v[2][4]),
                     16);
    assert_float_equal(ref, walk->speed.speed, 1e-6 * ref);
    for (int k = 0; k < 2; ++k) { /* locomotion at its own ground speed plays at its natural rate */
        assert_true(v[k][2] > 0);   /* loops */
        assert_float_equal(v[k][1] * v[k][3], v[k][4], 1e-6 * v[k][4]);
    }
    /* Dying at speed 0 still plays the clip: at its own rate, not per unit of speed, once. */
    assert_float_equal(v[2][1], 0, 0);
    assert_float_equal(v[2][0], v[2][4], 1e-9);
    assert_true(v[2][2] < 0);
    /* The .pal header has the same speed reference. */
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/out-cow/cow.pal", 0, &f, msg, sizeof msg), 0);
    assert_float_equal(f.header.speed_reference, (float)ref, 0);
    cbpal_close(&f);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

/* The ground speed from the evidence: Cow's Walk keeps its root still while its feet stride, so
 * the feet give it; its Jump_toIdle is a one-shot, which has no cycle to stride in (its feet
 * step, but a one-shot never follows the speed), so its root's drift is all there is. Where the
 * root does travel (the sample quadruped's walk is generated with root motion and no stance),
 * root travel is the ground speed. */
static void test_ground_speed_from_evidence(void **state)
{
    (void)state;
    cb_model *m = load_shared(COW);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info;
    cb_ground_speed gs;
    analyze(s, "AnimalArmature|Walk", -1, &info);
    cb_measure_ground_speed(s, &info, &gs);
    assert_float_equal(gs.root, 0, 0);
    assert_true(gs.stride.stride && gs.feet > 0);
    assert_float_equal(gs.speed, gs.feet, 0);
    assert_string_equal(gs.method, "planted feet");
    analyze(s, "AnimalArmature|Jump_toIdle", -1, &info);
    cb_measure_ground_speed(s, &info, &gs);
    assert_false(gs.stride.stride);
    assert_non_null(strstr(gs.stride.why, "plays once"));
    assert_true(gs.root > 0.1);
    assert_float_equal(gs.speed, gs.root, 0);
    assert_string_equal(gs.method, "root motion");
    cb_sampler_free(s);
    cb_model_free(m);

    m = load_sample("quadruped");
    s = cb_sampler_create(m, 0, &err);
    analyze(s, "walk", -1, &info);
    cb_measure_ground_speed(s, &info, &gs);
    assert_float_equal(gs.speed, 1.2, 1e-6);
    assert_string_equal(gs.method, "root motion");
    cb_sampler_free(s);
    cb_model_free(m);
}

/* Two error figures, everywhere an error is reported: the encoding's at the baked rows, and the
 * visible one (the runtime blends two rows). The visible figure of a bake equals what verify
 * measures at the same times (every baked row and every mid-point between rows), computed
 * independently: verify skins the exact and the blended matrices separately. */
static void test_both_error_figures(void **state)
{
    (void)state;
    char fox[1024], cmd[4096];
    static char out[65536];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    cb_model *m = load_or_fail(fox);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    cb_palette p;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &p, &err), CB_OK);
    double worst = 0;
    for (uint32_t c = 0; c < p.clip_count; ++c) {
        cb_clip_error e;
        assert_int_equal(cb_verify_clip(s, &p, p.texels, c, (int32_t)c, 0, &e, &err), CB_OK);
        worst = fmax(worst, fmax(e.quant_max, e.interp_max));
    }
    printf("  Fox: encoding %.4f mm/m, visible %.3f mm/m (verify: %.3f)\n", p.max_error / p.model_height * 1000,
           p.visible_error / p.model_height * 1000, worst / p.model_height * 1000);
    assert_float_equal(p.visible_error, worst, 1e-6 * worst);
    assert_true(p.visible_error > 100 * p.max_error); /* blending 30 fps rows is the bigger error by far */
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);

    /* The bake line and --json name both. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/fox.pal", crowdbake_exe(), fox);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "encoding error") || !strstr(out, "(at the baked rows), visible error") ||
        !strstr(out, "(blending rows at runtime)"))
        fail_msg("%s", out);
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/fox.pal --json", crowdbake_exe(), fox);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"max_error_mm_per_m\""));
    assert_non_null(strstr(out, "\"visible_error_mm_per_m\""));
    /* The .pal header records both; the roster log, manifest and report show both. */
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/fox.pal", 0, &f, msg, sizeof msg), 0);
    assert_true(f.header.visible_error > 100 * f.header.max_error);
    cbpal_close(&f);
    char fox_abs[PATH_MAX], text[8192];
    assert_non_null(realpath(fox, fox_abs));
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out-fox\"\nfps = 30\n[animal.fox]\nmodel = \"%s\"\n", fox_abs);
    write_text(TMP "/fox.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/fox.toml 2>&1 && %s report " TMP "/fox.toml --markdown", crowdbake_exe(),
             crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "encoding error") || !strstr(out, "visible") || !strstr(out, "palette encoding error mm/m") ||
        !strstr(out, "palette visible error mm/m"))
        fail_msg("%s", out);
    snprintf(cmd, sizeof cmd, "grep -c '_error_mm_per_m' " TMP "/out-fox/roster.json");
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_int_equal(atoi(out), 2 + 3); /* the type's two, and each of Fox's three clips' visible error */
}

/* fps = "auto" and max_error in a catalog: [bake] sets it for every clip, a clip can keep a fixed
 * rate or its own goal. verify (random times as well as mid-frames) confirms the goals. */
static void test_catalog_fps_auto(void **state)
{
    (void)state;
    char cow[1024], cow_abs[PATH_MAX], text[8192], cmd[4096];
    static char out[65536];
    shared_path(cow, sizeof cow, COW);
    assert_non_null(realpath(cow, cow_abs));
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"out-auto\"\nfps = \"auto\"\nmax_error = 1.0\nmax_fps = 120\nbone_space = \"global\"\n\n[animal.cow]\nmodel = \"%s\"\n"
             "clips = [\"AnimalArmature|Idle\", \"AnimalArmature|Walk\", { source = \"AnimalArmature|Death\", fps = 30 },\n"
             "         { source = \"AnimalArmature|Eating\", max_error = 5 }]\n",
             cow_abs);
    write_text(TMP "/auto.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/auto.toml -q", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/out-auto/cow.pal", 0, &f, msg, sizeof msg), 0);
    double fps[4];
    for (uint32_t c = 0; c < 4; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&f, c, &clip);
        fps[c] = clip.fps;
        printf("  %s: %.1f fps, %u rows\n", clip.name, clip.fps, clip.frames);
    }
    cbpal_close(&f);
    assert_float_equal(fps[0], 24, 1e-4);  /* Idle: its key rate is enough */
    assert_true(fps[1] > 30);              /* Walk needs more than 30 fps for 1 mm/m */
    assert_float_equal(fps[2], 30, 1e-4);  /* Death: fixed */
    assert_true(fps[3] < fps[1]);          /* Eating: a looser goal, fewer rows */
    /* verify agrees for the clips with a 1 mm/m goal (it adds random times). */
    snprintf(cmd, sizeof cmd, "%s verify %s " TMP "/out-auto/cow.pal", crowdbake_exe(), cow);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    double q, b;
    const char *walk = strstr(out, "AnimalArmature|Walk");
    assert_non_null(walk);
    assert_int_equal(sscanf(walk + strlen("AnimalArmature|Walk"), "%*f %*f %*f %*f %lf %lf", &q, &b), 2);
    /* Walk's rows are fitted (fewer rows): the fit moves them, within the budget. It evens the error
     * out between the rows and the blends, so either may carry the worst (0.563 and 0.506 mm/m). */
    assert_true(q <= 1.0 && b <= 1.0 && q > 0.1);
    /* A bad value names the file, the line and the fix. */
    snprintf(text, sizeof text, "[animal.cow]\nmodel = \"%s\"\nfps = \"fast\"\n", cow_abs);
    write_text(TMP "/bad-auto.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/bad-auto.toml 2>&1", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT);
    if (!strstr(out, "bad-auto.toml:3:") || !strstr(out, "fps must be a rate in frames per second or \"auto\""))
        fail_msg("%s", out);
}

/* An in-place loop without a closing key ends where it starts: over its last interval the
 * sampler returns to the first pose, and so does the travel taken off. (Taking v * t off to
 * the end left a jump of v * period at the wrap: 0.011 units on Cow's Gallop, which blending
 * towards row 0 showed as 1.2 mm/m however many rows were baked.) */
static void test_in_place_open_loop_ends_where_it_starts(void **state)
{
    (void)state;
    cb_model *m = load_shared(COW);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info;
    analyze(s, "AnimalArmature|Gallop", -1, &info);
    assert_true(info.ground_speed > 0.01); /* the root drifts: there is travel to take off */
    size_t n = (size_t)m->skins[0].joint_count * 16;
    double *a = malloc(n * sizeof(double)), *b = malloc(n * sizeof(double));
    cb_clip_frame_matrices(s, &info, 0, CB_ROOT_MOTION_IN_PLACE, a);
    cb_clip_frame_matrices(s, &info, info.steps, CB_ROOT_MOTION_IN_PLACE, b); /* t = t0 + period */
    double worst = 0;
    for (size_t k = 0; k < n; ++k) worst = fmax(worst, fabs(a[k] - b[k]));
    printf("  Gallop in place: pose at the period less pose at 0: %.3g (travel per period %.4f units)\n", worst,
           info.ground_speed * info.duration);
    assert_true(worst < 0.01 * info.ground_speed * info.duration); /* float32 key times: not exactly 0 */
    /* Over the keys the average travel is still taken off: the last key's root is where row 0's is. */
    assert_float_equal(cb_root_travel_time(info.t1 - info.t0, info.t1 - info.t0, info.duration, true), info.t1 - info.t0, 0);
    assert_float_equal(cb_root_travel_time(info.duration, info.t1 - info.t0, info.duration, true), 0, 1e-12);
    free(a), free(b);
    cb_sampler_free(s);
    cb_model_free(m);
}

/* Rows fitted to the runtime's linear blend (--fit-rows, fit_rows = true): the goal on
 * the pack's Cow, in place, qpos/u16 - every clip's worst visible error within 1 mm per metre of
 * height at no more than 1.5x the bytes of the 30 fps bake - measured by verify, independently
 * of the bake's own figures (random times as well as mid-rows). Sampled rows at the same rates
 * miss it, and at a fixed rate fitting cuts the visible error by a third or more. */
static void test_fitted_rows_meet_the_goal(void **state)
{
    (void)state;
    cb_model *m = load_shared(COW);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.root_motion = CB_ROOT_MOTION_IN_PLACE;
    o.fit = true;
    uint32_t n = m->animation_count;
    cb_clip_plan *plan = calloc(n, sizeof *plan);
    cb_rate_goal *goals = calloc(n, sizeof *goals);
    for (uint32_t i = 0; i < n; ++i) plan[i] = (cb_clip_plan){(int32_t)i, NULL, -1, 0, false, false, 0, NULL}, goals[i] = (cb_rate_goal){1.0, 120, CB_ROWS_FITTED};
    assert_int_equal(cb_choose_rates(s, &o, plan, n, goals, NULL, &err), CB_OK);
    cb_palette fitted, sampled, at30;
    assert_int_equal(cb_palette_bake(s, &o, plan, n, &fitted, &err), CB_OK);
    cb_bake_options plain = o;
    plain.fit = false;
    for (uint32_t i = 0; i < n; ++i) plan[i].fit = false; /* the same rates, sampled */
    assert_int_equal(cb_palette_bake(s, &plain, plan, n, &sampled, &err), CB_OK);
    assert_int_equal(cb_palette_bake(s, &plain, NULL, 0, &at30, &err), CB_OK);
    assert_true(fitted.fitted && !sampled.fitted);
    double worst_fit = 0, worst_sampled = 0;
    for (uint32_t c = 0; c < n; ++c) {
        cb_clip_error e, f;
        assert_int_equal(cb_verify_clip(s, &fitted, fitted.texels, c, plan[c].animation, 256, &e, &err), CB_OK);
        assert_int_equal(cb_verify_clip(s, &sampled, sampled.texels, c, plan[c].animation, 256, &f, &err), CB_OK);
        worst_fit = fmax(worst_fit, fmax(e.quant_max, e.interp_max));
        worst_sampled = fmax(worst_sampled, fmax(f.quant_max, f.interp_max));
    }
    double h = fitted.model_height;
    printf("  Cow in place, fps auto up to 120: %u rows, %zu bytes (30 fps: %u rows, %zu bytes, x%.2f); worst visible "
           "%.3f mm/m fitted, %.3f sampled at the same rates\n",
           fitted.rows, fitted.texel_bytes, at30.rows, at30.texel_bytes, (double)fitted.texel_bytes / at30.texel_bytes,
           cb_mm_per_m(worst_fit, h), cb_mm_per_m(worst_sampled, h));
    /* 745 while Gallop_Jump got one more key interval (45 rows; 44 over its key span, its closing key corrected) */
    assert_int_equal(at30.rows, 744);
    assert_true(fitted.texel_bytes <= 1.5 * at30.texel_bytes);
    assert_true(cb_mm_per_m(worst_fit, h) <= 1.0);
    assert_true(cb_mm_per_m(worst_sampled, h) > 1.0);
    cb_palette_free(&fitted), cb_palette_free(&sampled), cb_palette_free(&at30);

    /* A fixed 48 fps: fitted rows against sampled ones, every clip, as verify sees them. */
    o.fps = plain.fps = 48;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &fitted, &err), CB_OK);
    assert_int_equal(cb_palette_bake(s, &plain, NULL, 0, &sampled, &err), CB_OK);
    worst_fit = worst_sampled = 0;
    for (uint32_t c = 0; c < n; ++c) {
        cb_clip_error e, f;
        assert_int_equal(cb_verify_clip(s, &fitted, fitted.texels, c, (int32_t)c, 64, &e, &err), CB_OK);
        assert_int_equal(cb_verify_clip(s, &sampled, sampled.texels, c, (int32_t)c, 64, &f, &err), CB_OK);
        worst_fit = fmax(worst_fit, fmax(e.quant_max, e.interp_max));
        worst_sampled = fmax(worst_sampled, fmax(f.quant_max, f.interp_max));
    }
    printf("  48 fps: visible %.3f mm/m fitted, %.3f sampled; encoding %.3f against %.3f mm/m\n", cb_mm_per_m(worst_fit, h),
           cb_mm_per_m(worst_sampled, h), cb_mm_per_m(fitted.max_error, h), cb_mm_per_m(sampled.max_error, h));
    assert_true(worst_fit < 0.7 * worst_sampled);
    /* The rows give up some error, no more than the blend then errs (the fit evens the two out). */
    assert_true(fitted.max_error > 10 * sampled.max_error && fitted.max_error <= fitted.visible_error);
    cb_palette_free(&fitted), cb_palette_free(&sampled);
    free(plan), free(goals);
    cb_sampler_free(s);
    cb_model_free(m);

    /* In a catalog: fit_rows = true, flagged in the .pal header; a wrong value names its line. */
    char cow[1024], cow_abs[PATH_MAX], text[PATH_MAX + 256], cmd[4096];
    static char out[65536];
    shared_path(cow, sizeof cow, COW);
    assert_non_null(realpath(cow, cow_abs));
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out-fit\"\nfps = 30\nfit_rows = true\n[animal.cow]\nmodel = \"%s\"\n"
             "clips = [\"AnimalArmature|Walk\"]\n", cow_abs);
    write_text(TMP "/fit.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/fit.toml -q", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    cbpal_file pf;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/out-fit/cow.pal", 0, &pf, msg, sizeof msg), 0);
    assert_true(pf.header.flags & CBPAL_FLAG_FITTED_ROWS);
    cbpal_close(&pf);
    snprintf(text, sizeof text, "[animal.cow]\nmodel = \"%s\"\nfit_rows = 1\n", cow_abs);
    write_text(TMP "/bad-fit.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/bad-fit.toml 2>&1", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT);
    if (!strstr(out, "bad-fit.toml:3:") || !strstr(out, "fit_rows must be true or false")) fail_msg("%s", out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gallop_without_closing_key_loops_smoothly),
        cmocka_unit_test(test_loop_judgements),
        cmocka_unit_test(test_info_says_why_and_the_bake_loops),
        cmocka_unit_test(test_catalog_states_move_right),
        cmocka_unit_test(test_ground_speed_from_evidence),
        cmocka_unit_test(test_both_error_figures),
        cmocka_unit_test(test_catalog_fps_auto),
        cmocka_unit_test(test_in_place_open_loop_ends_where_it_starts),
        cmocka_unit_test(test_fitted_rows_meet_the_goal),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
