/* pose_batch.c - a bake's exact poses sampled a batch of times at once into its pose cache
 * (palette_bake.h: palette_prefetch_poses). A bake of a rig whose joints are not similarities
 * samples each pose as 4x4 matrices, one time at a time (cb_clip_frame_matrices); where it keeps
 * its poses (a rate search's probes, the bake after them) the times it is about to read are known
 * a batch ahead - a measurement's rows, a clip's next rows, a fit's mid-rows - so those not kept
 * yet are sampled together through the sampler's lanes (cb_clip_frame_matrices_batch: the same
 * bits, tests/lib/test_pose_batch.c) and kept, and each is then found where it was. */
#include <stdlib.h>

#include "palette_bake.h"
#include "sampler.h"

struct pose_batch {
    cb_joint_subset *joints; /* every joint of the skin */
    double *lanes;           /* joints x 16 x CB_SAMPLE_BATCH */
    struct measure_scratch *measure; /* the thread's measurement scratch, kept across its probes (or NULL) */
    struct row_lanes *row_lanes;     /* the lanes its last probes' rows were sampled from (or NULL) */
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
    palette_measure_scratch_free(b->measure);
    palette_row_lanes_free(b->row_lanes);
    free(b->lanes), free(b);
}

struct measure_scratch **pose_batch_measure(pose_batch *b) { return &b->measure; }

struct row_lanes **pose_batch_row_lanes(pose_batch *b) { return &b->row_lanes; }

/* Fewer poses missing than this are left to palette_frame_matrices, one at a time: a batch
 * samples all its lanes whatever it fills. */
enum { BATCH_AT_LEAST = 4 };

/* The pose cache palette_frame_matrices keeps clip c's poses in, or NULL. */
static pose_cache *clip_cache(const bake_state *st, uint32_t c)
{
    return st->poses ? st->poses : st->clip_poses ? st->clip_poses[c] : NULL;
}

/* The batch to sample n missing poses with, or NULL: too few to batch, or out of memory (one at a time). */
static pose_batch *probe_batch(bake_state *st, worker *w, uint32_t n)
{
    if (n < BATCH_AT_LEAST) return NULL;
    return st->batch ? st->batch : w->batch ? w->batch : (w->batch = pose_batch_create(w->sampler));
}

void palette_prefetch_poses(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, const uint32_t *frames,
                            uint32_t count)
{
    pose_cache *poses = clip_cache(st, c);
    if (!poses || count > CB_SAMPLE_BATCH) return;
    uint32_t missing[CB_SAMPLE_BATCH], n = 0;
    for (uint32_t i = 0; i < count; ++i)
        if (!pose_cache_find(poses, cb_clip_frame_time(framing, frames[i]))) missing[n++] = frames[i];
    pose_batch *b = probe_batch(st, w, n);
    if (!b) return; /* sampled one at a time */
    double *out[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < n; ++i) out[i] = pose_cache_add(poses, cb_clip_frame_time(framing, missing[i])); /* NULL: full */
    cb_clip_frame_matrices_batch(w->sampler, framing, missing, n, st->opt->root_motion, b->joints, b->lanes, out);
}

void palette_unkept_poses(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, const uint32_t *frames,
                          uint32_t count, double *room, const double **mats)
{
    pose_cache *poses = clip_cache(st, c);
    size_t stride = (size_t)st->p->bone_count * 16;
    uint32_t missing[CB_SAMPLE_BATCH], n = 0;
    double *out[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < count; ++i) {
        mats[i] = poses ? pose_cache_find(poses, cb_clip_frame_time(framing, frames[i])) : NULL;
        if (!mats[i]) mats[i] = out[n] = room + i * stride, missing[n++] = frames[i];
    }
    pose_batch *b = probe_batch(st, w, n);
    if (b) {
        cb_clip_frame_matrices_batch(w->sampler, framing, missing, n, st->opt->root_motion, b->joints, b->lanes, out);
        return;
    }
    for (uint32_t i = 0; i < n; ++i) /* few, or out of memory: one at a time */
        cb_clip_frame_matrices(w->sampler, framing, missing[i], st->opt->root_motion, out[i]);
}
