/* test_pose_batch.c - a bake that keeps its exact poses (the rate search's probes and the bake
 * after them) samples those it lacks a batch of times at once (src/core/pose_batch.c) through
 * cb_clip_frame_matrices_batch: every skin joint's matrix the same bits as cb_clip_frame_matrices
 * gives one time at a time. On every shared model with a skin, Cow and Husky (whose joints are
 * not similarities: they are sampled this way) and the samples, every clip as a bake analyzes
 * it (its loop closed where the analysis closes it), its root kept and taken off in place, at
 * batches of 1 to CB_SAMPLE_BATCH frames, consecutive and spread out, the lanes not wanted left
 * unwritten. */
#include "testutil.h"

#include <string.h>

#include "../../src/core/sampler.h"

static const char *const more_models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb"};

/* Frames first, first + step, ... of the framing (at most `count` of them, within its frames)
 * sampled as a batch and one at a time: the same bits; a NULL out stays untouched. */
static uint32_t compare_batch(cb_sampler *s, const cb_clip_info *info, uint32_t first, uint32_t step, uint32_t count,
                              cb_root_motion rm, cb_joint_subset *all, double *lanes, double *batch, double *single,
                              uint32_t bones)
{
    uint32_t frames[CB_SAMPLE_BATCH], n = 0;
    for (uint32_t f = first; n < count && f < info->frames; f += step) frames[n++] = f;
    if (n == 0) return 0;
    double *out[CB_SAMPLE_BATCH];
    size_t pose = (size_t)bones * 16;
    for (uint32_t i = 0; i < n; ++i) out[i] = i == 1 ? NULL : batch + i * pose; /* lane 1 not wanted */
    for (size_t k = 0; k < n * pose; ++k) batch[k] = -12345.0;
    cb_clip_frame_matrices_batch(s, info, frames, n, rm, all, lanes, out);
    for (uint32_t i = 0; i < n; ++i) {
        if (i == 1) {
            for (size_t k = 0; k < pose; ++k) assert_true(batch[pose + k] == -12345.0);
            continue;
        }
        cb_clip_frame_matrices(s, info, frames[i], rm, single);
        if (memcmp(single, out[i], pose * sizeof(double)))
            fail_msg("animation %d frame %u of %u (root motion %d): the batch's matrices differ", info->animation,
                     frames[i], info->frames, (int)rm);
    }
    return n - (n > 1);
}

/* Every clip of m (freed here), as above; how many poses were compared. */
static uint32_t compare_model(cb_model *m)
{
    uint32_t compared = 0;
    if (m->skin_count == 0) return cb_model_free(m), 0;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    uint32_t bones = m->skins[0].joint_count;
    bool *every = malloc(bones * sizeof *every);
    for (uint32_t j = 0; j < bones; ++j) every[j] = true;
    cb_joint_subset *all = cb_joint_subset_create(s, every);
    double *lanes = malloc(((size_t)bones * 16 + 1) * CB_SAMPLE_BATCH * sizeof(double));
    double *batch = malloc((size_t)CB_SAMPLE_BATCH * bones * 16 * sizeof(double));
    double *single = malloc((size_t)bones * 16 * sizeof(double));
    assert_true(all && lanes && batch && single);
    static const cb_root_motion motions[] = {CB_ROOT_MOTION_KEEP, CB_ROOT_MOTION_IN_PLACE};
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_clip_info info;
        if (cb_clip_analyze(s, (int32_t)a, 48, -1, NULL, &info, &err)) {
            err = (cb_error){0};
            continue;
        }
        for (int r = 0; r < 2; ++r)
            for (uint32_t count = 1; count <= CB_SAMPLE_BATCH; count += 5) {
                compared += compare_batch(s, &info, 0, 1, count, motions[r], all, lanes, batch, single, bones);
                compared += compare_batch(s, &info, count, 3, count, motions[r], all, lanes, batch, single, bones);
            }
        compared += compare_batch(s, &info, info.frames > 16 ? info.frames - 16 : 0, 1, CB_SAMPLE_BATCH,
                                  CB_ROOT_MOTION_IN_PLACE, all, lanes, batch, single, bones); /* the clip's end */
    }
    free(every), free(lanes), free(batch), free(single);
    cb_joint_subset_free(all);
    cb_sampler_free(s);
    cb_model_free(m);
    return compared;
}

static void test_batches_are_the_single_poses_bit_for_bit(void **state)
{
    (void)state;
    uint32_t compared = 0, models = 0;
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i, ++models) compared += compare_model(load_shared(shared_models[i]));
    for (size_t i = 0; i < COUNT_OF(more_models); ++i, ++models) compared += compare_model(load_shared(more_models[i]));
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i, ++models) {
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        compared += compare_model(load_or_fail(path));
    }
    printf("  %u poses of %u models compared\n", compared, models);
    assert_true(compared > 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_batches_are_the_single_poses_bit_for_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
