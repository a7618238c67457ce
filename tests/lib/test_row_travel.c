/* test_row_travel.c - the per-row travel offset (.pal version 5) against an independent measure:
 * the reference joint matrices (../shared/reference, another implementation's sampling at 30 fps)
 * skin the mesh's sole vertices (reference_soles.h), and the feet's slide is measured in the
 * world of a game that moves the instance at the clip's ground speed, without the offsets and
 * with the ones the .pal carries (read by the C reader, blended between rows as the runtimes
 * blend them). On Cow and Husky, the gallops' mean slide falls by a third or more; the walks,
 * whose front and hind feet step back at different speeds, carry no offsets, and even the best
 * per-frame body speed the reference allows (the mean of the planted feet's) would cut their
 * slide by less than a third. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include "crowdbake_pal.h"
#include "reference_soles.h"

#define TMP TEST_TMP "/row_travel"

/* One clip as `info --json` gives it. */
typedef struct clip_facts {
    char name[128];
    double period, ground_speed;
} clip_facts;

static uint32_t info_clips(const char *model, clip_facts *out, uint32_t cap)
{
    char cmd[4096], log[4096];
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && %s info %s --json > %s/info.json && python3 -c \"import json\n"
             "for c in json.load(open('%s/info.json'))['clips']: print(c['name'], c['period'], c['ground_speed'])\" > %s/clips.txt",
             TMP, crowdbake_exe(), model, TMP, TMP, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    FILE *f = fopen(TMP "/clips.txt", "r");
    assert_non_null(f);
    uint32_t n = 0;
    while (n < cap && fscanf(f, " %127s %lf %lf", out[n].name, &out[n].period, &out[n].ground_speed) == 3) ++n;
    fclose(f);
    return n;
}

/* The four feet over one cycle: ground positions per frame (the frame at the period is the first
 * again) and whether each interval is planted (both ends within 2% of the height of the foot's lowest). */
typedef struct cycle {
    uint32_t frames;
    double t[REF_MAX_FRAMES + 1], x[4][REF_MAX_FRAMES + 1][2];
    bool down[4][REF_MAX_FRAMES];
} cycle;

static void track_cycle(const cb_model *m, const ref_sole feet[4], const ref_clip *ref, double period, double height,
                        cycle *c)
{
    uint32_t n = ref->frames;
    if (n > 1 && fabs(ref->t[n - 1] - period) < 1e-4) --n; /* a closing key: its last frame is its first */
    double h[4][REF_MAX_FRAMES + 1], p[3];
    for (int k = 0; k < 4; ++k) {
        double lo = INFINITY;
        for (uint32_t i = 0; i < n; ++i) {
            ref_sole_at(m, &feet[k], (const double (*)[16])ref->m[i], p);
            c->t[i] = ref->t[i], h[k][i] = p[1], c->x[k][i][0] = p[0], c->x[k][i][1] = p[2], lo = fmin(lo, p[1]);
        }
        h[k][n] = h[k][0], c->x[k][n][0] = c->x[k][0][0], c->x[k][n][1] = c->x[k][0][1];
        for (uint32_t i = 0; i < n; ++i) c->down[k][i] = fmax(h[k][i], h[k][i + 1]) <= lo + 0.02 * height;
    }
    c->t[n] = period, c->frames = n;
}

/* A foot's velocity over interval i. */
static void velocity(const cycle *c, int k, uint32_t i, double u[2])
{
    double dt = c->t[i + 1] - c->t[i];
    u[0] = (c->x[k][i + 1][0] - c->x[k][i][0]) / dt, u[1] = (c->x[k][i + 1][1] - c->x[k][i][1]) / dt;
}

/* The direction of travel: against the planted feet's mean motion. */
static void heading_of(const cycle *c, double d[2])
{
    double u[2], sx = 0, sz = 0;
    for (int k = 0; k < 4; ++k)
        for (uint32_t i = 0; i < c->frames; ++i)
            if (c->down[k][i]) velocity(c, k, i, u), sx -= u[0], sz -= u[1];
    double len = hypot(sx, sz);
    assert_true(len > 0);
    d[0] = sx / len, d[1] = sz / len;
}

/* The three measures of mean slide (fractions of the ground speed v): the body at v alone; at v
 * plus the .pal's offsets; at the best speed per frame (the planted feet's mean backward speed). */
typedef struct slides {
    double at_v, with_pal, best;
} slides;

static slides measure(const cycle *c, const cbpal_file *pal, uint32_t clip, double v, const double d[2])
{
    double sum[3] = {0}, u[2];
    uint32_t count = 0;
    for (uint32_t i = 0; i < c->frames; ++i) {
        double dt = c->t[i + 1] - c->t[i], best = 0;
        float a[3], b[3];
        uint32_t planted = 0;
        for (int k = 0; k < 4; ++k)
            if (c->down[k][i]) velocity(c, k, i, u), best -= u[0] * d[0] + u[1] * d[1], ++planted;
        best = planted ? best / planted : v;
        assert_int_equal(cbpal_travel_offset(pal, clip, c->t[i], a), 0);
        assert_int_equal(cbpal_travel_offset(pal, clip, c->t[i + 1], b), 0);
        for (int k = 0; k < 4; ++k) {
            if (!c->down[k][i]) continue;
            velocity(c, k, i, u);
            sum[0] += hypot(u[0] + v * d[0], u[1] + v * d[1]);
            sum[1] += hypot(u[0] + v * d[0] + (b[0] - a[0]) / dt, u[1] + v * d[1] + (b[2] - a[2]) / dt);
            sum[2] += hypot(u[0] + best * d[0], u[1] + best * d[1]);
            ++count;
        }
    }
    assert_true(count > 0);
    return (slides){sum[0] / count / v, sum[1] / count / v, sum[2] / count / v};
}

static uint32_t clip_index(const cbpal_file *pal, const char *name, cbpal_clip *out)
{
    for (uint32_t i = 0; i < pal->header.clip_count; ++i)
        if (cbpal_get_clip(pal, i, out) == 0 && strcmp(out->name, name) == 0) return i;
    fail_msg("the palette has no clip '%s'", name);
    return 0;
}

static void check_model(const char *asset, const char *reference, const char *stem)
{
    char model[1024], csv[1024], cmd[4096], log[8192], pal_path[256];
    shared_path(model, sizeof model, asset);
    shared_path(csv, sizeof csv, reference);
    snprintf(pal_path, sizeof pal_path, "%s/%s.pal", TMP, stem);
    snprintf(cmd, sizeof cmd, "mkdir -p %s && %s bake %s -o %s 2>&1", TMP, crowdbake_exe(), model, pal_path);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    assert_non_null(strstr(log, "per-row travel applied")); /* the log says what it decided, and why */
    cbpal_file pal;
    char err[256];
    if (cbpal_open(pal_path, CBPAL_VERIFY_CHECKSUM, &pal, err, sizeof err)) fail_msg("%s: %s", pal_path, err);
    assert_true(pal.header.version >= 5); /* 5; 6 and 7: local rows, the default, timed where fewer */
    assert_true(pal.header.flags & CBPAL_FLAG_ROW_TRAVEL);

    cb_model *m = load_or_fail(model);
    ref_clip ref = {.m = calloc(REF_MAX_FRAMES, sizeof *ref.m)};
    assert_non_null(ref.m);
    ref_read_clip(csv, "AnimalArmature|Idle", &ref);
    ref_sole feet[4] = {{0}};
    double height = ref_find_soles(m, (const double (*)[16])ref.m[0], feet);
    static clip_facts facts[64];
    uint32_t n = info_clips(model, facts, 64);
    static const char *const clips[] = {"AnimalArmature|Gallop", "AnimalArmature|Gallop_Jump", "AnimalArmature|Walk"};
    for (int i = 0; i < 3; ++i) {
        const clip_facts *f = NULL;
        for (uint32_t k = 0; k < n; ++k)
            if (strcmp(facts[k].name, clips[i]) == 0) f = &facts[k];
        assert_non_null(f);
        cbpal_clip pc;
        uint32_t index = clip_index(&pal, clips[i], &pc);
        ref_read_clip(csv, clips[i], &ref);
        static cycle c;
        track_cycle(m, feet, &ref, f->period, height, &c);
        double d[2];
        heading_of(&c, d);
        slides s = measure(&c, &pal, index, f->ground_speed, d);
        bool applied = pc.travel_heading[0] != 0 || pc.travel_heading[2] != 0;
        printf("  %-6s %-28s ground speed %.3f: slide %.0f%% at that speed, %.0f%% with the .pal's offsets (%s), "
               "%.0f%% at the best per-frame speed\n", stem, clips[i], f->ground_speed, 100 * s.at_v, 100 * s.with_pal,
               applied ? "applied" : "none", 100 * s.best);
        if (strstr(clips[i], "Gallop")) {
            assert_true(applied);
            assert_true(pc.travel_heading[0] * d[0] + pc.travel_heading[2] * d[1] > 0.99); /* the heading the feet give */
            assert_true(s.with_pal <= (2.0 / 3.0) * s.at_v);                                  /* cut by a third or more */
        } else {
            assert_false(applied);
            assert_true(fabs(s.with_pal - s.at_v) < 1e-9);  /* no offsets: the rows read 0 */
            assert_true(s.best > (2.0 / 3.0) * s.at_v);      /* no body speed would have cut it by a third */
        }
    }
    free(ref.m);
    cb_model_free(m);
    cbpal_close(&pal);
}

static void test_cow(void **state)
{
    (void)state;
    check_model("assets/quaternius-cow/Cow.glb", "reference/Cow.fps30.csv", "cow");
}

static void test_husky(void **state)
{
    (void)state;
    check_model("assets/quaternius-husky/Husky.glb", "reference/Husky.fps30.csv", "husky");
}

/* --row-travel off overrides the bake's decision: no travel table (no version 5), every offset 0. */
static void test_row_travel_off(void **state)
{
    (void)state;
    char model[1024], cmd[4096], log[8192];
    shared_path(model, sizeof model, "assets/quaternius-husky/Husky.glb");
    snprintf(cmd, sizeof cmd, "mkdir -p %s && %s bake %s -o %s/off.pal --row-travel off 2>&1", TMP, crowdbake_exe(), model, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    cbpal_file pal;
    char err[256];
    if (cbpal_open(TMP "/off.pal", CBPAL_VERIFY_CHECKSUM, &pal, err, sizeof err)) fail_msg("%s", err);
    assert_true(pal.header.version != 5); /* 1-4, or 6-7 for local rows: no table */
    assert_false(pal.header.flags & CBPAL_FLAG_ROW_TRAVEL);
    float o[3] = {1, 1, 1};
    assert_int_equal(cbpal_travel_offset(&pal, 0, 0.1, o), 0);
    assert_true(o[0] == 0 && o[1] == 0 && o[2] == 0);
    assert_true(cbpal_row_travel(&pal, 0) == 0);
    cbpal_close(&pal);
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/bad.pal --row-travel sometimes 2>&1", crowdbake_exe(), model, TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), EXIT_USAGE);
    assert_non_null(strstr(log, "--row-travel is auto or off"));
}

/* A catalog warns of the slide a herd shows: with the per-row travel, what it leaves (Husky's
 * Gallop, 32% without, under the 25% warning with); the walk, which gets none, still warns. */
static void test_slide_warning_counts_the_travel(void **state)
{
    (void)state;
    char model[1024], model_abs[4096], text[8192], cmd[8192];
    static char log[65536];
    shared_path(model, sizeof model, "assets/quaternius-husky/Husky.glb");
    assert_non_null(realpath(model, model_abs));
    snprintf(text, sizeof text, "[bake]\nout_dir = \"herd\"\n[animal.husky]\nmodel = \"%s\"\n"
             "states = { idle = [\"Idle\"], walk = [\"Walk\"], gallop = [\"Gallop\"] }\n", model_abs);
    assert_int_equal(system("mkdir -p " TMP), 0);
    write_text(TMP "/herd.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/herd.toml --force 2>&1", crowdbake_exe());
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s", log);
    if (!strstr(log, "clip 'AnimalArmature|Walk': its planted feet slide") ||
        strstr(log, "clip 'AnimalArmature|Gallop': its planted feet slide"))
        fail_msg("%s", log);
    /* The report's foot-sync table says the same. */
    snprintf(cmd, sizeof cmd, "%s report " TMP "/herd.toml 2>/dev/null | grep 'AnimalArmature|Gallop '", crowdbake_exe());
    if (run_command(cmd, log, sizeof log) != 0 || !strstr(log, "% with its per-row travel (") || strstr(log, "FEET SLIDE"))
        fail_msg("%s", log);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/herd.toml --force --row-travel off 2>&1", crowdbake_exe());
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s", log);
    if (!strstr(log, "clip 'AnimalArmature|Gallop': its planted feet slide")) fail_msg("%s", log);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cow),
        cmocka_unit_test(test_husky),
        cmocka_unit_test(test_row_travel_off),
        cmocka_unit_test(test_slide_warning_counts_the_travel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
