/* clip_memo.h - one bake run's clip analyses, each made once (internal). A bake asks about the
 * same clips four times over: the speed reference, the palette's framing, the per-row travel
 * and the loop notes each analyzed every clip again (cb_clip_analyze: two whole poses and the
 * loop's judgement each time, 40 M instructions on a 200-joint, 30-clip rig, most of it on one
 * thread). An analysis depends on its sampler's model and skin, the clip, the loop override and
 * max_frames; on its rate only through its framing (cb_clip_frame_at) and whether the feet were
 * weighed as a loop at both rates (clip_feet_weighed_alike), as the rate search's kept analyses
 * already rely on (palette_plan.c). So an analysis made once stands in for every later one with
 * those equal: framed at the asked rate and its loop set on the asker's sampler, it is what
 * analyzing gives, bit for bit. One thread's; the memo belongs to its creator (a bake run). */
#ifndef CB_CLIP_MEMO_H
#define CB_CLIP_MEMO_H

#include <stdbool.h>
#include <stdint.h>

#include "crowdbake/core.h"

typedef struct clip_memo clip_memo;

/* NULL when out of memory (every call below then analyzes, as without a memo). */
clip_memo *clip_memo_create(void);
void clip_memo_free(clip_memo *memo);

/* cb_clip_analyze(sampler, animation, fps, loop, limits, out, err), bit for bit, the sampler
 * left as it leaves it; analyzed only where no analysis in the memo stands in (memo NULL: always). */
cb_status clip_memo_analyze(clip_memo *memo, cb_sampler *sampler, int32_t animation, double fps, int loop,
                            const cb_limits *limits, cb_clip_info *out, cb_error *err);

/* Only a stand-in: true with *out and the sampler as clip_memo_analyze leaves them, false (both
 * untouched) where the memo holds none or framing it at fps fails. */
bool clip_memo_take(clip_memo *memo, cb_sampler *sampler, int32_t animation, double fps, int loop,
                    const cb_limits *limits, cb_clip_info *out);

/* Keeps an analysis made elsewhere (cb_clip_analyze with these arguments, on a sampler of the
 * same model and skin as `sampler`, which is not touched), unless one is kept already. */
void clip_memo_keep(clip_memo *memo, const cb_sampler *sampler, const cb_clip_info *info, double fps, int loop,
                    const cb_limits *limits);

/* One analysis asked for (clip_memo_prefetch). */
typedef struct clip_ask {
    int32_t animation;
    double fps;
    int loop; /* the loop override */
} clip_ask;

/* The asks the memo has no stand-in for, analyzed side by side on `threads` threads (each on a
 * sampler of its own, of `sampler`'s model and skin, which is not touched) and kept, so that
 * clip_memo_analyze takes each after. With one thread, or one clip to analyze, nothing is done
 * here (clip_memo_analyze analyzes them when asked); one that fails is left to it too. */
void clip_memo_prefetch(clip_memo *memo, const cb_sampler *sampler, const clip_ask *asks, uint32_t count,
                        const cb_limits *limits, uint32_t threads);

/* How many analyses the memo holds (for tests). */
uint32_t clip_memo_count(const clip_memo *memo);

/* Whether weigh_feet (loop_decide.c) framed the clip as a loop at both rates or at neither (its
 * cb_clip_frame_at fails past max_frames, and then the feet weigh nothing): the one way a clip's
 * analysis depends on the rate it is analyzed at, but for the framing at its end. */
bool clip_feet_weighed_alike(const cb_clip_info *clip, double a, double b, const cb_limits *limits);

#endif
