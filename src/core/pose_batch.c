/* pose_batch.c - a bake's exact poses sampled a batch of times at once into its pose cache
 * (palette_bake.h: palette_prefetch_poses). A bake of a rig whose joints are not similarities
 * samples each pose as 4x4 matrices, one time at a time (cb_clip_frame_matrices); where it keeps
 * its poses (a rate search's probes, the bake after them) the times it is about to read are known
 * a batch ahead - a measurement's rows, a clip's next rows, a fit's mid-rows - so those not kept
 * yet are sampled together through the sampler's lanes (cb_clip_frame_matrices_batch: the same
 * bits, tests/lib/test_pose_batch.c) and kept, and each is then found where it was. */
#include <stdlib.h>

#include <string.h>

#include "lanes.h"
#include "palette_bake.h"
#include "pose_cache.h"
#include "sampler.h"

struct pose_batch {
    cb_joint_subset *joints; /* every joint of the skin */
    double *lanes;           /* joints x 16 x CB_SAMPLE_BATCH */
};

pose_batch *pose_batch_create(const cb_sampler *s)
{
    uint32_t bones = cb_sampler_model(s)->skins[cb_sampler_skin(s)].joint_count;
    bool *every = malloc((bones ? bones : 1) * sizeof *every);
    pose_batch *b = calloc(1, sizeof *b);
    for (uint32_t j = 0; every && j < bones; ++j) every[j] = true;
    if (b && every) b->joints = cb_joint_subset_create(s, every);
    if (b) b->lanes = malloc(((size_t)bones * 16 + 1) * CB_SAMPLE_BATCH * sizeof(double));
    free(every);
    if (!b || !b->joints || !b->lanes) return pose_batch_free(b), NULL;
    return b;
}

void pose_batch_free(pose_batch *b)
{
    if (!b) return;
    cb_joint_subset_free(b->joints);
    free(b->lanes), free(b);
}

/* Fewer poses missing than this are left to palette_frame_matrices, one at a time: a batch
 * samples all its lanes whatever it fills. */
enum { BATCH_AT_LEAST = 4 };

void palette_prefetch_poses(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, const uint32_t *frames,
                            uint32_t count)
{
    pose_cache *poses = st->poses ? st->poses : st->clip_poses ? st->clip_poses[c] : NULL;
    if (!poses || count > CB_SAMPLE_BATCH) return;
    uint32_t missing[CB_SAMPLE_BATCH], n = 0;
    for (uint32_t i = 0; i < count; ++i)
        if (!pose_cache_find(poses, cb_clip_frame_time(framing, frames[i]))) missing[n++] = frames[i];
    if (n < BATCH_AT_LEAST) return;
    pose_batch *b = st->batch ? st->batch : w->batch ? w->batch : (w->batch = pose_batch_create(w->sampler));
    if (!b) return; /* out of memory: sampled one at a time */
    double *out[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < n; ++i) out[i] = pose_cache_add(poses, cb_clip_frame_time(framing, missing[i])); /* NULL: full */
    cb_clip_frame_matrices_batch(w->sampler, framing, missing, n, st->opt->root_motion, b->joints, b->lanes, out);
}

/* ---- a rig of similarities: each pose's lanes kept by time ---- */

/* What a clip's kept lanes may take, and the poses that must fit for a rig to keep them. A pose
 * kept costs its stores on the way and its loads back, and a batch is spared only when every
 * one of its times is kept. Fox's search (24 joints, 1.5 KB a pose) keeps 1,111 poses, about
 * 370 a clip, and takes 109 of its 202 batches from them (61.5 -> 59.6 M instructions). The
 * 200-joint rig's (12.8 KB a pose) took only a quarter of its batches whole: keeping its poses
 * cost it as much time as it saved, and up to 200 MB more memory. So a rig keeps its lanes only
 * where a clip's 2 MB holds 512 poses (64 joints or fewer); past the 2 MB, poses are sampled as
 * before. */
#define KEPT_LANES_BYTES ((size_t)2 << 20)
#define KEPT_LANES_POSES 512

/* The sink that keeps each new lane's values on their way to the caller's sink. */
typedef struct lanes_tee {
    cb_joint_lanes_sink sink;
    void *ctx;
    double *keep[CB_SAMPLE_BATCH]; /* per lane: its pose (8 doubles a joint), or the dump */
    uint32_t count;
} lanes_tee;

#if defined(__GNUC__)
/* Joint j's 8 values at lanes i .. i + 3 (lanes[k][i + l]) into the poses pose[l] + 8 j: two
 * 4x4 transposes (a pose's 8 values are two rows of four). */
static CB_CLONE_INLINE void lanes_to_poses(const double (*lanes)[CB_SAMPLE_BATCH], uint32_t i, uint32_t j, double *const *pose)
{
    for (int half = 0; half < 2; ++half) {
        v4df v[4], r[4];
        for (int k = 0; k < 4; ++k) memcpy(&v[k], &lanes[half * 4 + k][i], sizeof v[k]);
        cb_transpose4(v, r);
        for (int l = 0; l < 4; ++l) memcpy(pose[l] + (size_t)j * 8 + half * 4, &r[l], sizeof r[l]);
    }
}

/* The other way: poses pose[l] (joint j's 8 values) as lanes i .. i + 3. */
static CB_CLONE_INLINE void poses_to_lanes(const double *const *pose, uint32_t i, uint32_t j, double (*lanes)[CB_SAMPLE_BATCH])
{
    for (int half = 0; half < 2; ++half) {
        v4df r[4];
        for (int l = 0; l < 4; ++l) memcpy(&r[l], pose[l] + (size_t)j * 8 + half * 4, sizeof r[l]);
        cb_rows_to_lanes4(r, lanes + half * 4, (int)i);
    }
}
#else
static CB_CLONE_INLINE void lanes_to_poses(const double (*lanes)[CB_SAMPLE_BATCH], uint32_t i, uint32_t j, double *const *pose)
{
    for (int l = 0; l < 4; ++l)
        for (int k = 0; k < 8; ++k) pose[l][(size_t)j * 8 + k] = lanes[k][i + l];
}
static CB_CLONE_INLINE void poses_to_lanes(const double *const *pose, uint32_t i, uint32_t j, double (*lanes)[CB_SAMPLE_BATCH])
{
    for (int l = 0; l < 4; ++l)
        for (int k = 0; k < 8; ++k) lanes[k][i + l] = pose[l][(size_t)j * 8 + k];
}
#endif

/* keep[l]: where lane l's values go (its pose, or `dump`: a lane not kept, or past count). The
 * moves compiled for AVX2 too (CB_TARGET_CLONES): 32-byte vectors without it are pairs. */
CB_TARGET_CLONES
static void keep_lanes(void *ctx, uint32_t j, double (*lanes)[CB_SAMPLE_BATCH])
{
    lanes_tee *t = ctx;
    for (uint32_t i = 0; i < t->count; i += 4) lanes_to_poses((const double(*)[CB_SAMPLE_BATCH])lanes, i, j, t->keep + i);
    t->sink(t->ctx, j, lanes);
}

/* Kept poses (from[i] for lane i) to the sink as lanes, joint by joint. */
CB_TARGET_CLONES
static void kept_to_sink(const double *const *from, uint32_t joints, cb_joint_lanes_sink sink, void *ctx)
{
    double lanes[8][CB_SAMPLE_BATCH];
    for (uint32_t j = 0; j < joints; ++j) {
        for (uint32_t i = 0; i < CB_SAMPLE_BATCH; i += 4) poses_to_lanes(from + i, i, j, lanes);
        sink(ctx, j, lanes);
    }
}

void palette_frame_lanes_each(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, const uint32_t *frames,
                              uint32_t count, cb_joint_lanes_sink sink, void *ctx)
{
    pose_cache *poses = st->poses ? st->poses : st->clip_poses ? st->clip_poses[c] : NULL;
    uint32_t joints = cb_sampler_model(w->sampler)->skins[cb_sampler_skin(w->sampler)].joint_count;
    bool small = (size_t)joints * 8 * sizeof(double) * KEPT_LANES_POSES <= KEPT_LANES_BYTES;
    pose_cache *kept = poses && small ? pose_cache_companion(poses, 8 * joints, KEPT_LANES_BYTES) : NULL;
    const double *have[CB_SAMPLE_BATCH];
    bool all = kept != NULL;
    for (uint32_t i = 0; kept && i < count; ++i)
        all &= (have[i] = pose_cache_find(kept, cb_clip_frame_time(framing, frames[i]))) != NULL;
    if (!kept) {
        cb_clip_frame_lanes_each(w->sampler, framing, frames, count, st->opt->root_motion, sink, ctx);
        return;
    }
    if (!all) { /* sampled, the new poses kept on the way (a full cache keeps none) */
        lanes_tee t = {.sink = sink, .ctx = ctx, .count = count};
        double *dump = w->mats; /* the worker's scratch (bones x 16 doubles), unused on this path */
        bool any = false;
        for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) {
            double *pose = i < count && !have[i] ? pose_cache_add(kept, cb_clip_frame_time(framing, frames[i])) : NULL;
            t.keep[i] = pose ? pose : dump, any |= pose != NULL;
        }
        cb_clip_frame_lanes_each(w->sampler, framing, frames, count, st->opt->root_motion, any ? keep_lanes : sink,
                                 any ? (void *)&t : ctx); /* full: nothing to keep */
        return;
    }
    /* Every pose kept: each joint's lanes as the sampler hands them (lanes past count repeat
     * the last time, whose values they are: a lane's values depend on its time alone). */
    const double *from[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) from[i] = have[i < count ? i : count - 1];
    kept_to_sink(from, joints, sink, ctx);
}
