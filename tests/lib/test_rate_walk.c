/* test_rate_walk.c - the rate search's walk (src/core/rate_search.c: one walk over both families
 * of rates and both kinds of rows from the key rate, the 1/fps^2 law ruling out far misses
 * unbaked) against fresh measurements that share nothing with it but the bake: on Fox, Cow and
 * Husky at the default goal (1 mm/m) and cap (120 fps), every clip's choice, cb_choose_rates on
 * 1 and 2 threads, must be
 * - within the goal, its stated error equal to the clip baked afresh alone at that rate and kind
 *   of rows and measured in full (every row, every blend; no goal to stop at);
 * - the fewest rows: every lower rate of either family (the key rate's multiples and fractions,
 *   the common rates), baked afresh with sampled and with fitted rows, misses the goal, and so do
 *   sampled rows at the chosen rate where fitted rows were chosen (a tie goes to sampled rows).
 * So no rate the law ruled out unbaked would have met the goal, and no probe's remembered error
 * stands in for another rate's or kind's, nor did the walk skip fitted rows that meet it where
 * sampled rows err over twice the goal (speed43e: fitted rows err at best half what sampled rows
 * do; a sampled probe that fitted rows may follow measures to twice the goal, and where it stops
 * above it no fitted rows are baked: Fox's Survey at 20 and 12 fps, Cow's and Husky's misses at
 * 24-48 fps). The robot too, where that skip spares the most probes (6 of 76): its punch misses the goal
 * even at 120 fps (a fast transient the bake searches on past the cap), the rest must meet it; its
 * stated error there is the lower of both kinds' exact errors, baked afresh. */
#include "testutil.h"

#include <math.h>

#include "crowdbake/palette.h"
#include "crowdbake/runtime.h"

/* The steps whose grid holds every key of the clip, from the first key (a key within 1e-3 of a
 * step of it lies on it): the shortest key gap divided by m, the smallest m up to 8 that does, 0
 * when none does (key_grid.c's rule, restated here). */
static double key_grid_step(const cb_animation *a, double gap)
{
    for (int m = 1; gap > 0 && m <= 8; ++m) {
        bool all = true;
        for (uint32_t c = 0; c < a->channel_count && all; ++c)
            for (uint32_t k = 0; k < a->channels[c].key_count && all; ++k) {
                double at = ((double)a->channels[c].times[k] - a->t0) / (gap / m);
                all = fabs(at - round(at)) < 1e-3;
            }
        if (all) return gap / m;
    }
    return 0;
}

/* Every rate either family offers the clip under `below` (see families_of in rate_search.c,
 * restated here): the key rate's 1/4 .. 4 multiples and the common rates; and the 1/4 .. 4
 * multiples of its shortest key gap's rate too where its keys' grid is finer (Fox's Run: keys
 * every 1/24 s, then on a grid 1/120 s off it; rows at 24, 48 or 96 fps must miss as well). */
static size_t rates_under(const cb_animation *a, double below, double *out)
{
    static const double common[] = {2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 24, 30, 40, 48, 60, 90, 120};
    static const double factors[] = {0.25, 0.5, 1, 2, 3, 4};
    double gap = cb_animation_key_interval(a), grid = key_grid_step(a, gap);
    double steps[2] = {gap, grid};
    size_t n = 0;
    for (size_t i = 0; i < sizeof common / sizeof common[0]; ++i)
        if (common[i] < below) out[n++] = common[i];
    for (int g = 0; g < (grid > 0 && grid != gap ? 2 : 1); ++g)
        for (size_t i = 0; steps[g] > 0 && i < 6; ++i) {
            double r = round(factors[i] / steps[g] * 1000) / 1000;
            if (r < below) out[n++] = r;
        }
    return n;
}

static void expect_fewest_rows_within(const char *asset, uint32_t out_of_reach)
{
    cb_model *m = load_shared(asset);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    double lo[3], hi[3], height = cb_skin_rest_bounds(s, lo, hi), goal = 1.0 / 1000 * height;
    uint32_t n = m->animation_count, fitted = 0, lower = 0, unmet = 0;
    assert_true(n <= 64);
    cb_clip_plan plan[2][64];
    cb_rate_choice choices[2][64];
    for (uint32_t threads = 1; threads <= 2; ++threads) {
        cb_rate_goal goals[64];
        for (uint32_t c = 0; c < n; ++c)
            plan[threads - 1][c] = (cb_clip_plan){(int32_t)c, NULL, -1, 0, false, false, 0, NULL},
            goals[c] = (cb_rate_goal){1, CB_AUTO_MAX_FPS, CB_ROWS_BEST};
        cb_bake_options o = cb_default_bake_options();
        o.threads = threads;
        assert_int_equal(cb_choose_rates(s, &o, plan[threads - 1], n, goals, choices[threads - 1], &err), CB_OK);
    }
    for (uint32_t c = 0; c < n; ++c) {
        const cb_clip_plan *p = &plan[0][c];
        const cb_rate_choice *ch = &choices[0][c];
        assert_true(plan[1][c].fps == p->fps && plan[1][c].fit == p->fit && choices[1][c].error == ch->error);
        assert_true(ch->fitted == p->fit);
        if (!ch->met) { /* over the goal even at max_fps: the kind with the lower error there */
            assert_true(p->fps == CB_AUTO_MAX_FPS && !(ch->error <= goal));
            /* Both exact: the sampled rows' too, which the search measures with the goal first and
             * in full only once fitted rows miss as well (defer_exact). */
            double sampled = clip_visible_error(s, (int32_t)c, p->fps, false, 0);
            double fit = clip_visible_error(s, (int32_t)c, p->fps, true, 0);
            if (ch->error != fmin(sampled, fit) || p->fit != !(sampled < fit))
                fail_msg("%s clip %u: over the goal at %g fps, stated %.17g with %s rows; baked afresh, sampled %.17g, "
                         "fitted %.17g", asset, c, p->fps, ch->error, p->fit ? "fitted" : "sampled", sampled, fit);
            ++unmet;
            continue;
        }
        double full = clip_visible_error(s, (int32_t)c, p->fps, p->fit, 0);
        if (!(full <= goal) || full != ch->error)
            fail_msg("%s clip %u: chose %g fps %s rows, stated error %.17g; baked afresh and measured in full %.17g "
                     "(goal %.17g)", asset, c, p->fps, p->fit ? "fitted" : "sampled", ch->error, full, goal);
        if (p->fit && !(clip_visible_error(s, (int32_t)c, p->fps, false, goal) > goal))
            fail_msg("%s clip %u: fitted rows chosen at %g fps, where sampled rows meet the goal", asset, c, p->fps);
        double under[48];
        size_t k = rates_under(&m->animations[c], p->fps, under);
        for (size_t i = 0; i < k; ++i)
            for (int fit = 0; fit <= 1; ++fit, ++lower)
                if (!(clip_visible_error(s, (int32_t)c, under[i], fit, goal) > goal))
                    fail_msg("%s clip %u: chose %g fps, but %g fps with %s rows meets the goal", asset, c, p->fps, under[i],
                             fit ? "fitted" : "sampled");
        fitted += p->fit;
    }
    assert_int_equal(unmet, out_of_reach);
    assert_true(fitted > 0 && fitted < n); /* both kinds chosen: the walk's both branches are checked */
    assert_true(lower > 2 * n);            /* and rates under every answer */
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_fox_fewest_rows_within_the_goal(void **state)
{
    (void)state;
    expect_fewest_rows_within("assets/fox-bevy/Fox.glb", 0);
}

static void test_cow_fewest_rows_within_the_goal(void **state)
{
    (void)state;
    expect_fewest_rows_within("assets/quaternius-cow/Cow.glb", 0);
}

static void test_husky_fewest_rows_within_the_goal(void **state)
{
    (void)state;
    expect_fewest_rows_within("assets/quaternius-husky/Husky.glb", 0);
}

static void test_robot_fewest_rows_within_the_goal(void **state)
{
    (void)state;
    expect_fewest_rows_within("assets/robot-quaternius-raylib/robot.glb", 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fox_fewest_rows_within_the_goal),
        cmocka_unit_test(test_cow_fewest_rows_within_the_goal),
        cmocka_unit_test(test_husky_fewest_rows_within_the_goal),
        cmocka_unit_test(test_robot_fewest_rows_within_the_goal),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
