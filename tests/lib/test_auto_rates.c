/* test_auto_rates.c - a bake without --fps chooses each clip's rate and rows by error, baking
 * each candidate rate once per clip and kind of rows (src/core/rate_search.c keeps its probes):
 * its choices must be those of the plain rule applied here to the clip baked afresh at each rate
 * - exactly at max_fps, elsewhere measured only as far as the goal needs, as the search measures
 * it. The rule is the search as it was before its walk (issue 43: one walk over both families
 * and kinds of rows from the key rate, stopping at the fewest rows, the law taken from the
 * nearest probe; tests/lib/test_rate_walk.c checks its answers against every lower rate): on
 * these models the walk bakes fewer probes and must still choose exactly what the rule does,
 * error for error. The rule: sampled rows first, then fitted rows under that rate (a tie goes to the exact
 * poses); for each, the key rate's family walked from the key rate (down while rates meet the
 * goal, else up), then the common rates under its answer (from the highest under it; with no
 * answer, walked from 30 fps); a rate whose error the probes so far predict (error x fps^2, per
 * kind and family; fitted rows at half the sampled ones') over 1.5x the goal is a miss unbaked;
 * neither kind meeting it: max_fps, the kind with the lower exact error. A remembered probe
 * answered for the wrong rate or kind of rows, or a goal-shortened value taken for an exact one,
 * changes a rate, a kind of rows or an error here. cb_choose_rates (what a bake without --fps
 * runs) must choose the same for every clip at once, on 1 and 2 threads; and on Cow the choice
 * must mix fitted and sampled clips (one palette of both), and every clip's error, measured by
 * cb_verify_clip in the palette baked with the choices, must be within 1 mm/m. */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"
#include "crowdbake/runtime.h"

/* The clip baked alone at fps, its visible error measured in full. */
static double exact_error(cb_sampler *s, int32_t animation, double fps, bool fit)
{
    return clip_visible_error(s, animation, fps, fit, 0);
}

/* The rule's search of one clip (see the top of the file). */
typedef struct rule {
    cb_sampler *s;
    int32_t animation;
    double goal, max_fps;
    double law[2][2]; /* [fit][family: 0 key rates, 1 common]: the largest error x fps^2 baked */
} rule;

static double rule_law(const rule *r, bool fit, int family)
{
    double law = r->law[fit][family] > 0 ? r->law[fit][family] : r->law[fit][0];
    return fit ? fmax(law, 0.5 * rule_law(r, false, family)) : law;
}

static double rule_error(rule *r, double fps, bool fit, int family)
{
    if (fps < r->max_fps && rule_law(r, fit, family) / (fps * fps) > 1.5 * r->goal) return INFINITY;
    double e = clip_visible_error(r->s, r->animation, fps, fit, fps == r->max_fps ? 0 : r->goal);
    if (isfinite(e) && e * fps * fps > r->law[fit][family]) r->law[fit][family] = e * fps * fps;
    return e;
}

static double rule_lowest(rule *r, const double *rates, size_t n, size_t first, double below, bool fit, int family,
                          double *error)
{
    while (n > 0 && (rates[n - 1] > r->max_fps || (below > 0 && rates[n - 1] >= below))) --n;
    if (n == 0) return 0;
    size_t at = below > 0 || first >= n ? n - 1 : first;
    double e = rule_error(r, rates[at], fit, family);
    if (e <= r->goal) {
        for (*error = e; at > 0 && (e = rule_error(r, rates[at - 1], fit, family)) <= r->goal; --at) *error = e;
        return rates[at];
    }
    while (++at < n)
        if ((e = rule_error(r, rates[at], fit, family)) <= r->goal) return *error = e, rates[at];
    return 0;
}

/* The palette of the chosen rates and rows, each clip verified against exact skinning (its rows,
 * mid-rows and 64 random times): within max_error_mm. */
static void expect_palette_within(cb_sampler *s, const cb_clip_plan *plan, uint32_t n, double max_error_mm)
{
    cb_bake_options o = cb_default_bake_options();
    cb_palette p;
    cb_error err = {0};
    assert_int_equal(cb_palette_bake(s, &o, plan, n, &p, &err), CB_OK);
    for (uint32_t c = 0; c < n; ++c) {
        cb_clip_error e;
        assert_int_equal(cb_verify_clip(s, &p, p.texels, c, plan[c].animation, 64, &e, &err), CB_OK);
        double worst = cb_mm_per_m(fmax(e.quant_max, e.interp_max), p.model_height);
        assert_true(p.clips[c].fitted == plan[c].fit);
        if (!(worst <= max_error_mm)) fail_msg("clip %u: verified %.4f mm/m, over %g", c, worst, max_error_mm);
    }
    cb_palette_free(&p);
}

static void expect_reference_choices(const char *asset, double max_error_mm, double max_fps, bool expect_unmet)
{
    cb_model *m = load_shared(asset);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    double lo3[3], hi3[3], height = cb_skin_rest_bounds(s, lo3, hi3), goal = max_error_mm / 1000 * height;
    static const double common[] = {2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 24, 30, 40, 48, 60, 90, 120};
    static const double factors[] = {0.25, 0.5, 1, 2, 3, 4};
    uint32_t met = 0, unmet = 0, n = m->animation_count;
    double *want_fps = calloc(n, sizeof(double)), *want_err = calloc(n, sizeof(double));
    bool *want_fitted = calloc(n, sizeof(bool));
    assert_true(want_fps && want_err && want_fitted);
    uint32_t fitted = 0;
    for (uint32_t c = 0; c < m->animation_count; ++c) {
        double key = cb_animation_key_interval(&m->animations[c]), aligned[16];
        size_t na = 0;
        for (size_t i = 0; key > 0 && i < 6; ++i) aligned[na++] = round(factors[i] / key * 1000) / 1000;
        /* Past the 4th multiple only above the common rates (a cap over 120: fast transients). */
        for (double k = 5; key > 0 && na < 16 && k / key <= max_fps; ++k)
            if (k / key > 120) aligned[na++] = round(k / key * 1000) / 1000;
        size_t key_at = 2; /* the key rate, factor 1 */
        rule r = {s, (int32_t)c, goal, max_fps, {{0, 0}, {0, 0}}};
        double rate[2] = {0, 0}, err_at[2] = {INFINITY, INFINITY}; /* [fit]: the lowest rate within the goal */
        for (int fit = 0; fit <= 1; ++fit) {
            double below = fit ? rate[0] : 0, ea = INFINITY, eb = INFINITY;
            double a = rule_lowest(&r, aligned, na, key_at, below, fit, 0, &ea);
            double b = rule_lowest(&r, common, 17, 11, a > 0 ? a : below, fit, 1, &eb);
            rate[fit] = b > 0 ? b : a, err_at[fit] = b > 0 ? eb : a > 0 ? ea : INFINITY;
        }
        bool want_fit;
        double want, want_error;
        if (rate[0] > 0 || rate[1] > 0) {
            want_fit = rate[1] > 0; /* fitted rows were searched under the sampled ones' rate only */
            want = rate[want_fit], want_error = err_at[want_fit];
        } else { /* neither: the lower exact error at max_fps */
            double ef = exact_error(s, (int32_t)c, max_fps, true), es = exact_error(s, (int32_t)c, max_fps, false);
            want_fit = !(es < ef), want = max_fps, want_error = fmin(ef, es);
        }
        want_fps[c] = want, want_err[c] = want_error, want_fitted[c] = want_fit;
        met += want_error <= goal, unmet += !(want_error <= goal), fitted += want_fit;
    }
    if (expect_unmet) assert_true(met > 0 && unmet > 0); /* both endings of the search are checked */
    else assert_true(unmet == 0);
    assert_true(fitted > 0 && fitted < n); /* both kinds of rows chosen: one palette mixes them */
    for (uint32_t threads = 1; threads <= 2; ++threads) {
        cb_clip_plan plan[64];
        cb_rate_goal goals[64];
        cb_rate_choice choices[64];
        assert_true(n <= 64);
        for (uint32_t c = 0; c < n; ++c)
            plan[c] = (cb_clip_plan){(int32_t)c, NULL, -1, 0, false, false, 0, NULL}, goals[c] = (cb_rate_goal){max_error_mm, max_fps, CB_ROWS_BEST};
        cb_bake_options o = cb_default_bake_options();
        o.threads = threads;
        assert_int_equal(cb_choose_rates(s, &o, plan, n, goals, choices, &err), CB_OK);
        for (uint32_t c = 0; c < n; ++c)
            if (plan[c].fps != want_fps[c] || choices[c].error != want_err[c] || plan[c].fit != want_fitted[c])
                fail_msg("%s clip %u on %u threads: cb_choose_rates chose %g fps, %s rows (error %.17g), the rule %g fps, "
                         "%s rows (error %.17g)", asset, c, threads, plan[c].fps, plan[c].fit ? "fitted" : "sampled",
                         choices[c].error, want_fps[c], want_fitted[c] ? "fitted" : "sampled", want_err[c]);
        if (threads == 2 && !expect_unmet) expect_palette_within(s, plan, n, max_error_mm);
    }
    free(want_fps), free(want_err), free(want_fitted);
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_fox_choices_follow_the_rule(void **state)
{
    (void)state;
    expect_reference_choices("assets/fox-bevy/Fox.glb", 1, 60, true);
}

static void test_cow_choices_follow_the_rule(void **state)
{
    (void)state;
    expect_reference_choices("assets/quaternius-cow/Cow.glb", 1, 60, true);
}

/* The default cap: every clip of Cow meets 1 mm/m, fitted and sampled clips mixed, verified. */
static void test_cow_meets_1mm_under_the_default_cap(void **state)
{
    (void)state;
    expect_reference_choices("assets/quaternius-cow/Cow.glb", 1, CB_AUTO_MAX_FPS, false);
}

/* Past the default cap: the robot's punch, 2.84 mm/m at 120 fps, meets 1 mm/m on its 24 fps key
 * grid above 120 (the fast transients' search, CB_TRANSIENT_MAX_FPS); every clip follows the rule. */
static void test_robot_meets_1mm_up_to_the_transient_cap(void **state)
{
    (void)state;
    expect_reference_choices("assets/robot-quaternius-raylib/robot.glb", 1, CB_TRANSIENT_MAX_FPS, false);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fox_choices_follow_the_rule),
        cmocka_unit_test(test_cow_choices_follow_the_rule),
        cmocka_unit_test(test_cow_meets_1mm_under_the_default_cap),
        cmocka_unit_test(test_robot_meets_1mm_up_to_the_transient_cap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
