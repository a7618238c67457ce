/* test_auto_rates.c - fps = "auto" bakes each candidate rate once per clip (src/runtime.c keeps
 * its probes): its choices must be those of the plain rule applied to errors measured here
 * independently, each rate baked exactly (no error goal) - the lowest rate within the goal by
 * binary search over the common rates, then over the key rate's multiples and fractions below
 * that, else max_fps with its exact error. A remembered probe answered for the wrong rate, or a
 * goal-shortened value taken for an exact one, changes a rate or an error here. */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"
#include "crowdbake/runtime.h"

/* The clip baked alone at fps, its visible error measured in full. */
static double exact_error(cb_sampler *s, int32_t animation, double fps)
{
    cb_bake_options o = cb_default_bake_options();
    o.fps = fps;
    cb_clip_plan plan = {animation, NULL, -1, fps};
    cb_palette p;
    cb_error err = {0};
    assert_int_equal(cb_palette_bake(s, &o, &plan, 1, &p, &err), CB_OK);
    double e = p.visible_error;
    cb_palette_free(&p);
    return e;
}

static double lowest(cb_sampler *s, int32_t animation, const double *rates, size_t n, double max_fps, double goal,
                     double *error)
{
    while (n > 0 && rates[n - 1] > max_fps) --n;
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        double e = exact_error(s, animation, rates[mid]);
        if (e <= goal) hi = mid, *error = e;
        else lo = mid + 1;
    }
    return hi < n ? rates[hi] : 0;
}

static void expect_reference_choices(const char *asset, double max_error_mm, double max_fps)
{
    cb_model *m = load_shared(asset);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    double lo3[3], hi3[3], height = cb_skin_rest_bounds(s, lo3, hi3), goal = max_error_mm / 1000 * height;
    static const double common[] = {2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 24, 30, 40, 48, 60, 90, 120};
    static const double factors[] = {0.25, 0.5, 1, 2, 3, 4};
    uint32_t met = 0, unmet = 0;
    for (uint32_t c = 0; c < m->animation_count; ++c) {
        double key = cb_animation_key_interval(&m->animations[c]), aligned[6];
        size_t na = 0;
        for (size_t i = 0; key > 0 && i < 6; ++i) aligned[na++] = round(factors[i] / key * 1000) / 1000;
        double ea = INFINITY, eb = INFINITY, want_error;
        double a = lowest(s, (int32_t)c, common, 17, max_fps, goal, &ea);
        double b = lowest(s, (int32_t)c, aligned, na, a > 0 ? fmin(a, max_fps) : max_fps, goal, &eb);
        double want = b > 0 && (a == 0 || b < a) ? b : a > 0 ? a : max_fps;
        want_error = want == b && b > 0 && (a == 0 || b < a) ? eb : a > 0 ? ea : exact_error(s, (int32_t)c, max_fps);

        cb_clip_plan plan = {(int32_t)c, NULL, -1, 0};
        bool got_met;
        double got_error;
        cb_bake_options o = cb_default_bake_options();
        double got = cb_choose_clip_fps(s, &o, &plan, goal, max_fps, &got_met, &got_error, &err);
        assert_int_equal(err.status, CB_OK);
        if (got != want || got_error != want_error)
            fail_msg("%s clip %u: chose %g fps (error %.17g), the rule %g fps (error %.17g)", asset, c, got, got_error, want,
                     want_error);
        assert_true(got_met == (want_error <= goal));
        met += got_met, unmet += !got_met;
    }
    assert_true(met > 0 && unmet > 0); /* both endings of the search are checked */
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_fox_choices_follow_the_rule(void **state)
{
    (void)state;
    expect_reference_choices("assets/fox-bevy/Fox.glb", 1, 60);
}

static void test_cow_choices_follow_the_rule(void **state)
{
    (void)state;
    expect_reference_choices("assets/quaternius-cow/Cow.glb", 1, 60);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fox_choices_follow_the_rule),
        cmocka_unit_test(test_cow_choices_follow_the_rule),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
