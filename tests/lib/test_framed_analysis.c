/* test_framed_analysis.c - the bake after a rate search frames each clip's analysis from the
 * search (made at 2 fps) at the clip's own rate instead of analyzing the clip again
 * (src/core/palette_plan.c, take_analysis), as the search's probes already frame it at theirs.
 * That stands in only if a clip's analysis depends on its rate through its framing alone: on
 * every shared model with a skin, Cow, Husky and the samples, every clip, with its loop decided
 * by the analysis, forced on and forced off, analyzed at 2 fps and framed at 24, 30, 48, 90 and
 * 120 fps equals the clip analyzed at that rate, field for field (the analysis clears the
 * whole struct first, so bytes compare), and the other way (the search takes the analysis the
 * root motion's decision made at the bake's fps, framed at 2). */
#include "testutil.h"

#include <string.h>

#include "crowdbake/core.h"

static const char *const more_models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb"};

static uint32_t compare_model(cb_model *m)
{
    uint32_t compared = 0;
    if (m->skin_count == 0) return cb_model_free(m), 0;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    static const double rates[] = {24, 30, 48, 90, 120};
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (int loop = -1; loop <= 1; ++loop) {
            cb_clip_info searched;
            if (cb_clip_analyze(s, (int32_t)a, 2, loop, NULL, &searched, &err)) {
                err = (cb_error){0};
                continue;
            }
            for (size_t r = 0; r < COUNT_OF(rates); ++r) {
                cb_clip_info framed = searched, analyzed;
                cb_error e1 = {0}, e2 = {0};
                cb_status framed_rc = cb_clip_frame_at(m, rates[r], NULL, &framed, &e1);
                cb_status analyzed_rc = cb_clip_analyze(s, (int32_t)a, rates[r], loop, NULL, &analyzed, &e2);
                assert_int_equal(framed_rc, analyzed_rc);
                if (framed_rc) continue;
                if (memcmp(&framed, &analyzed, sizeof framed))
                    fail_msg("%s: clip '%s' (loop %d) framed at %g fps differs from its analysis there", m->source,
                             m->animations[a].name, loop, rates[r]);
                /* and back: the root motion's analysis (at the bake's fps) framed for the search */
                cb_clip_info back = analyzed;
                assert_int_equal(cb_clip_frame_at(m, 2, NULL, &back, &e1), CB_OK);
                if (memcmp(&back, &searched, sizeof back))
                    fail_msg("%s: clip '%s' (loop %d) analyzed at %g fps and framed at 2 differs from its analysis at 2",
                             m->source, m->animations[a].name, loop, rates[r]);
                compared += 2;
            }
        }
    cb_sampler_free(s);
    cb_model_free(m);
    return compared;
}

static void test_a_search_analysis_framed_is_the_analysis(void **state)
{
    (void)state;
    uint32_t compared = 0;
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i) compared += compare_model(load_shared(shared_models[i]));
    for (size_t i = 0; i < COUNT_OF(more_models); ++i) compared += compare_model(load_shared(more_models[i]));
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) {
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        compared += compare_model(load_or_fail(path));
    }
    printf("  %u framings compared\n", compared);
    assert_true(compared > 500);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_search_analysis_framed_is_the_analysis),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
