/* test_auto_rates.c - fps = "auto" bakes each candidate rate once per clip and kind of rows
 * (src/runtime.c keeps its probes): its choices must be those of the plain rule applied to
 * errors measured here independently, each rate baked exactly (no error goal) - for one kind of
 * rows, the lowest rate within the goal by binary search over the common rates, then over the
 * key rate's multiples and fractions below that, else max_fps with its exact error; for a clip,
 * fitted rows first, then sampled rows up to that rate, the lower rate taken and sampled rows on
 * a tie. A remembered probe answered for the wrong rate or kind of rows, or a goal-shortened
 * value taken for an exact one, changes a rate, a kind of rows or an error here.
 * cb_choose_rates (what a bake without --fps runs) must choose the same for every clip at once,
 * on 1 and 2 threads; and on Cow the choice must mix fitted and sampled clips (one palette of
 * both), and every clip's error, measured by cb_verify_clip in the palette baked with the
 * choices, must be within 1 mm/m. */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"
#include "crowdbake/runtime.h"

/* The clip baked alone at fps (its rows fitted or sampled), its visible error measured in full. */
static double exact_error(cb_sampler *s, int32_t animation, double fps, bool fit)
{
    cb_bake_options o = cb_default_bake_options();
    o.fps = fps;
    cb_clip_plan plan = {animation, NULL, -1, fps, fit};
    cb_palette p;
    cb_error err = {0};
    assert_int_equal(cb_palette_bake(s, &o, &plan, 1, &p, &err), CB_OK);
    double e = p.visible_error;
    cb_palette_free(&p);
    return e;
}

static double lowest(cb_sampler *s, int32_t animation, const double *rates, size_t n, double max_fps, double goal,
                     double *error, bool fit)
{
    while (n > 0 && rates[n - 1] > max_fps) --n;
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        double e = exact_error(s, animation, rates[mid], fit);
        if (e <= goal) hi = mid, *error = e;
        else lo = mid + 1;
    }
    return hi < n ? rates[hi] : 0;
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
        double key = cb_animation_key_interval(&m->animations[c]), aligned[6];
        size_t na = 0;
        for (size_t i = 0; key > 0 && i < 6; ++i) aligned[na++] = round(factors[i] / key * 1000) / 1000;
        double rate[2] = {0, 0}, err_at[2] = {INFINITY, INFINITY}; /* [fit]: the lowest rate within the goal */
        for (int fit = 1; fit >= 0; --fit) {
            double cap = fit ? max_fps : rate[1] > 0 ? rate[1] : max_fps, ea = INFINITY, eb = INFINITY;
            double a = lowest(s, (int32_t)c, common, 17, cap, goal, &ea, fit);
            double b = lowest(s, (int32_t)c, aligned, na, a > 0 ? fmin(a, cap) : cap, goal, &eb, fit);
            bool take_b = b > 0 && (a == 0 || b < a);
            rate[fit] = take_b ? b : a, err_at[fit] = take_b ? eb : a > 0 ? ea : INFINITY;
        }
        bool want_fit;
        double want, want_error;
        if (rate[0] > 0 || rate[1] > 0) {
            want_fit = !(rate[0] > 0 && (rate[1] == 0 || rate[0] <= rate[1])); /* sampled on a tie */
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
            plan[c] = (cb_clip_plan){(int32_t)c, NULL, -1, 0, false}, goals[c] = (cb_rate_goal){max_error_mm, max_fps, CB_ROWS_BEST};
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fox_choices_follow_the_rule),
        cmocka_unit_test(test_cow_choices_follow_the_rule),
        cmocka_unit_test(test_cow_meets_1mm_under_the_default_cap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
