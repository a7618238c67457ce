/* sampler.h - the sampler's state and what sample.c (one time, 4x4 matrices) and
 * sample_lanes.c (similarities, CB_SAMPLE_BATCH times at once) share. Internal. */
#ifndef CB_SAMPLER_H
#define CB_SAMPLER_H

#include "crowdbake/core.h"

#include <stdbool.h>
#include <stdint.h>

struct cb_sampler {
    const cb_model *model;
    int32_t skin;
    uint32_t *order;     /* node indices, parents before children */
    double *local_trs;   /* 10 per node: t[3], r[4], s[3] */
    bool *animated;      /* per node, set while evaluating one clip */
    double *globals;     /* 16 per node */
    bool affine_ibm;     /* every inverse bind matrix ends in 0 0 0 1: cheaper products */
    uint32_t *cursor;    /* per channel of every clip: the key interval of the last sample */
    uint32_t *cursor_base; /* per clip: its channels' first cursor */
    cb_wrap *wraps;      /* per clip: where a loop without a closing key comes round (cb_sampler_set_period) */
    cb_animation **closed; /* per clip: its channels closed onto their first pose (loop_close.c), or NULL */
    double *closed_with;   /* per clip, 5: the travel and the wrap its closed copy was made with (cb_sampler_set_loop) */
    double rest_extent;  /* the rest pose's joint box diagonal (clip.c), 0 until worked out */
    /* The similarity path (cb_sampler_is_similarity) visits only the joints and their ancestors. */
    bool similar;
    bool *relevant;              /* per node: a joint or an ancestor of one */
    uint32_t relevant_count;
    uint32_t *relevant_order;    /* the relevant nodes, parents first */
    uint32_t *slot;              /* per node: its place in relevant_order */
    int32_t *parent_slot;        /* per place in relevant_order: its parent's place, or -1 for a root (a
                                  * batch reads this, not the nodes' structs: a cache line a node) */
    cb_similarity *sim_rest;     /* per node: its rest transform */
    cb_similarity *sim_ibm;      /* per joint: its inverse bind matrix */
    /* Per relevant node, its transform at each time of a batch, as 8 lanes of CB_SAMPLE_BATCH
     * (structure of arrays: a loop over the times vectorizes and has no dependency chain). */
    double *lanes;
    /* Channels of a clip that share their key times (one input accessor for many channels, as
     * exporters write them) share one key search per batch: a span group per distinct times
     * array of LINEAR channels with two keys or more. */
    int32_t *span_group;         /* per channel of every clip (as cursor): its group, -1 for none */
    uint32_t span_group_count;
    uint32_t *group_base;        /* per clip and one more: its groups are group_base[a] .. group_base[a + 1] - 1 */
    const float **group_times;   /* per group: the key times it stands for */
    uint32_t *group_keys;        /* per group: their count */
    uint32_t *group_cursor;      /* per group: the key interval of the last search */
    struct cb_key_spans *spans;  /* per group of the clip sampled (g - group_base[a]): the batch's spans */
    /* Per clip and relevant node (a * relevant_count + slot): bit 1 << path for each path one of
     * the clip's channels sets. Those components need no rest pose: every channel writes all of
     * a batch's lanes. */
    uint8_t *clip_paths;
};

/* Where each time of a batch falls among a channel's keys: key[i] and key[i] + 1 around it at
 * fraction s[i], or edge[i] when it is at or outside the first or last key (those lanes are
 * evaluated one by one: clamped, or wrapped round, see cb_wrap). */
typedef struct cb_key_spans {
    uint32_t key[CB_SAMPLE_BATCH];
    double s[CB_SAMPLE_BATCH];
    double edge[CB_SAMPLE_BATCH]; /* 1 or 0; a double, so the loops that read it vectorize */
    bool any_edge;
} cb_key_spans;

/* Asks the memory for the keys the lanes of `sp` read of channel `ch` (whose key times the spans
 * were found among): key[0] to key[last] + 1, 3 or 4 floats a key. A clip's keys outgrow the L2
 * cache on a big rig, so a channel's keys are asked for while the channels before it are
 * interpolated. A hint: it changes no value. */
static inline void cb_prefetch_keys(const cb_channel *ch, const cb_key_spans *sp)
{
#if defined(__GNUC__)
    uint32_t first = sp->key[0], last = sp->key[CB_SAMPLE_BATCH - 1] > first ? sp->key[CB_SAMPLE_BATCH - 1] : first;
    size_t bytes = (ch->path == CB_PATH_ROTATION ? 4 : 3) * sizeof(float);
    size_t from = first * bytes, to = (size_t)(last + 2 < ch->key_count ? last + 2 : ch->key_count) * bytes;
    for (size_t at = from & ~(size_t)63; at < to; at += 64) __builtin_prefetch((const char *)ch->values + at);
#else
    (void)ch, (void)sp;
#endif
}

/* Index of the last key with times[k] <= t (0 when t is before the first key). `hint` holds the
 * previous answer: frames are sampled in order, so the answer is usually it or the next key.
 * The answer does not depend on the hint (times increase strictly). */
static inline uint32_t cb_find_key(const float *times, uint32_t key_count, double t, uint32_t *hint)
{
    uint32_t last = key_count - 1, h = *hint;
    for (uint32_t k = h; k <= h + 1 && k <= last; ++k)
        if (times[k] <= t && (k == last || t < times[k + 1])) return *hint = k;
    uint32_t lo = 0, hi = last;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo + 1) / 2;
        if (times[mid] <= t)
            lo = mid;
        else
            hi = mid - 1;
    }
    return *hint = lo;
}

/* Some of a skin's joints, sampled alone (sample_subset.c): the nodes they hang from (parents
 * first) and the joints (indices into the skin's), with room for a batch's lanes. What reads a
 * few joints of a big rig (the soles of a foot analysis) samples only their chains. */
typedef struct cb_joint_subset {
    bool *relevant;          /* per node: a wanted joint or an ancestor of one */
    uint32_t *order, count;  /* those nodes, parents first */
    uint32_t *slot;          /* per node: its place in order */
    uint32_t *joints, joint_count;
    uint32_t *joint_slot;    /* per skin joint: its place in joints, or UINT32_MAX */
    bool *animated;          /* per node, while sampling a batch: a channel sets it */
    uint8_t *paths;          /* per node of order, while sampling a batch: the TRS components channels set */
    bool filled;             /* the rest lanes hold filled_clip's (channels of animation filled_animation) */
    int32_t filled_animation;
    const struct cb_animation *filled_clip;
    double *channel_lanes;   /* per channel of a clip: 4 x CB_SAMPLE_BATCH values */
    double *node_lanes;      /* per node of order: TRS and global matrix, 26 x CB_SAMPLE_BATCH */
} cb_joint_subset;
/* wanted: per skin joint. NULL when out of memory. */
cb_joint_subset *cb_joint_subset_create(const cb_sampler *s, const bool *wanted);
void cb_joint_subset_free(cb_joint_subset *sub);
/* cb_sample_joint_matrices for the subset's joints only, at 1..CB_SAMPLE_BATCH times at once, the
 * same bits, as lanes: component c of the k-th wanted joint's matrix (sub->joints[k]) at times[i]
 * is out[(k * 16 + c) * CB_SAMPLE_BATCH + i] (lanes past `count` repeat the last time). Each
 * channel is evaluated over the times together (cb_channel_lanes_at), then the hierarchy over
 * them side by side. */
void cb_sample_joint_subset_batch(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                  cb_joint_subset *sub, double *out);
/* The same matrices written straight into one pose a time: joint sub->joints[k]'s at times[i]
 * into pose[i] + sub->joints[k] * 16 (pose[i] NULL: not wanted). lanes: scratch as `out` above
 * and room for one pose (the skin's joints x 16 doubles: what lanes not wanted are stored into). */
void cb_sample_joint_subset_poses(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                  cb_joint_subset *sub, double *lanes, double *const *pose);
/* The channels a clip is sampled with: its own, or their loop-closed copy (loop_close.c). */
static inline const cb_animation *cb_sampler_clip(const cb_sampler *s, int32_t animation)
{
    return s->closed[animation] ? s->closed[animation] : &s->model->animations[animation];
}
/* loop_close.c: plays `animation` with every channel's mismatch between its last and first key
 * spread over the key span (travel, scene space: the root's travel kept); false when out of
 * memory (the clip then plays as it is). open: plays it as it is again. */
bool cb_sampler_close_clip(cb_sampler *s, int32_t animation, const double travel[3]);
void cb_sampler_open_clip(cb_sampler *s, int32_t animation);
/* loop_close.c: cb_sampler_set_baked_loop for `judged`'s animation without judging it again:
 * judged is cb_clip_analyze's analysis of it (any rate and loop override) on a sampler of the
 * same model and skin. A clip analyzed as a loop (judged->loops) is judged alike by any analysis
 * as a loop (its loop_reason comes from its poses alone; the override keeps
 * CB_LOOP_CLOSED_CORRECTED for a loop, and so does the loop's decision), and closed with the same
 * travel, which the analysis measured from the same poses; a one-shot's analysis is no judgement
 * of it as a loop: then judged again. */
bool sampler_set_baked_loop_judged(cb_sampler *s, const cb_clip_info *judged, bool loops, double start, double duration);
/* loop_close.c: a closed clip's loop_correction_mm_per_m, sampled at its ends and between; 1
 * when out of memory. */
int cb_loop_correction_measure(cb_sampler *s, cb_clip_info *clip);

/* One channel at time t (sample.c): the reference every lane must equal bit for bit. */
void cb_channel_eval_at(const cb_channel *ch, double t, double out[4], uint32_t *hint, const cb_wrap *wrap);

/* sample_lanes.c: the span groups of a similarity sampler's clips (false when out of memory),
 * and for tests, one LINEAR channel (two keys or more) at CB_SAMPLE_BATCH times the way a
 * batch samples it: out[c][i] is component c (3 or 4) at times[i]. */
bool cb_sampler_prepare_spans(cb_sampler *s);
/* cb_sample_joint_similarities_batch's similarities for 1..CB_SAMPLE_BATCH times (the same
 * bits) as lanes: component c (rotation x y z w, translation x y z, scale) of joint j at
 * times[i] is out[(j * 8 + c) * CB_SAMPLE_BATCH + i]; lanes past `count` repeat the last time. */
void cb_sample_joint_lanes(cb_sampler *s, int32_t animation, const double *times, uint32_t count, double *out);
/* The same joints' lanes handed over one joint at a time, in joint order, as each is made:
 * sink(ctx, j, lanes) with joint j's 8 x CB_SAMPLE_BATCH values, valid until it returns. A bake
 * that turns each joint into rows at once keeps one joint's lanes in cache, not every joint's. */
typedef void (*cb_joint_lanes_sink)(void *ctx, uint32_t joint, double (*lanes)[CB_SAMPLE_BATCH]);
void cb_sample_joint_lanes_each(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                cb_joint_lanes_sink sink, void *ctx);
/* clip.c: the same for 1..CB_SAMPLE_BATCH increasing frames of a clip, as
 * cb_clip_frame_similarities frames them (the root's travel taken off in place). */
void cb_clip_frame_lanes(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                         cb_root_motion root_motion, double *out);
/* cb_clip_frame_lanes's joints handed to `sink` one at a time (cb_sample_joint_lanes_each), the
 * root's travel taken off each: the same bits. */
void cb_clip_frame_lanes_each(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                              cb_root_motion root_motion, cb_joint_lanes_sink sink, void *ctx);
/* clip.c: cb_clip_frame_matrices at 1..CB_SAMPLE_BATCH frames of a clip at once, through `all`
 * (a subset of every joint of the skin; lanes: its joints x 16 x CB_SAMPLE_BATCH doubles of
 * scratch): the same bits, into out[i] for frames[i] (out[i] NULL: not wanted). */
void cb_clip_frame_matrices_batch(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                                  cb_root_motion root_motion, cb_joint_subset *all, double *lanes, double *const *out);
void cb_channel_eval_lanes(const cb_channel *ch, const double *times, double (*out)[CB_SAMPLE_BATCH]);
/* Any channel at CB_SAMPLE_BATCH times, with its cursor and its clip's wrap as the sampler
 * samples it: out[c][i] is component c (3 or 4; a 4th of 3 undefined) at times[i], the bits of
 * cb_channel_eval_at (the lanes where they can, time by time where they cannot). spans: where
 * the times fall among the channel's keys when the caller found them for another channel of the
 * same key times (cb_find_spans; only for a cb_channel_in_lanes channel), else NULL. */
void cb_channel_lanes_at(const cb_channel *ch, const double *times, uint32_t *hint, const cb_wrap *wrap,
                         const cb_key_spans *spans, double (*out)[CB_SAMPLE_BATCH]);
/* Whether cb_channel_lanes_at evaluates a channel in lanes (LINEAR, two keys or more). */
bool cb_channel_in_lanes(const cb_channel *ch);
/* Where CB_SAMPLE_BATCH times fall among key times (channel_eval's key and fraction; the answer
 * does not depend on the hint). */
void cb_find_spans(const float *key_times, uint32_t key_count, const double *times, uint32_t *hint, cb_key_spans *out);

#endif
