/* foot_cache.h - one bake's foot analyses, each measured once: a model's feet (its soles) and
 * each clip's stride (cb_stride_measure), shared by everything in the bake that asks about the
 * same clip framed the same way (the speed reference, the per-row travel). A stride depends on
 * the clip's framing (its animation, span, period, whether it loops and its root travel), not
 * on its rate: only slide_mean_varying reads the row count, and it is worked out again from the
 * kept tracks for another. The cache belongs to its creator (a bake run creates one and frees it
 * when done) and serves one model and skin: a sampler of another is measured uncached. */
#ifndef CB_FOOT_CACHE_H
#define CB_FOOT_CACHE_H

#include <stdbool.h>
#include <stdint.h>

#include "crowdbake/locomotion.h"
#include "crowdbake/row_travel.h"
#include "crowdbake/stride.h"
#include "foot_sole.h"

typedef struct foot_cache foot_cache;

/* NULL when out of memory (every call below then measures uncached). */
foot_cache *foot_cache_create(void);
void foot_cache_free(foot_cache *cache);

/* From now on, each stride the cache measures is screened first (stride_measure_feet's
 * `screen`): a clip whose feet rule a stride out on a quarter of the samples is answered "no
 * stride" from them, its feet's stances and speeds not measured. For a bake, which reads of a
 * clip that does not stride only that it does not (the speed reference then takes the root's
 * speed, the per-row travel is not applied); `crowdbake info` and the roster, which report
 * every foot, measure in full. */
void foot_cache_screen_strides(foot_cache *cache);

/* cb_stride_measure(sampler, clip, out), bit for bit, measured at most once per framing
 * (screened: the same wherever the clip strides, stride_feet.h). */
void foot_cache_stride(foot_cache *cache, cb_sampler *sampler, const cb_clip_info *clip, cb_stride *out);

/* The strides of `clips` not cached yet, measured on `threads` threads at once (each on a
 * sampler of its own, the clip's loop set on it as cb_clip_analyze sets it) and cached: each
 * as foot_cache_stride would measure it, bit for bit. With one thread, or one clip to measure,
 * nothing is done here (foot_cache_stride measures them when asked). */
void foot_cache_measure_clips(foot_cache *cache, cb_sampler *sampler, const cb_clip_info *clips, uint32_t count,
                              uint32_t threads);

/* cb_skin_rest_bounds's height for the sampler's model and skin, worked out once (cache NULL:
 * every time). */
double foot_cache_rest_height(foot_cache *cache, cb_sampler *sampler);

/* The model's feet as cb_stride_measure finds them (the rest pose's soles), found once; NULL
 * when the sampler is not the cache's model (or out of memory): the caller finds its own. */
struct stride_feet;
const struct stride_feet *foot_cache_feet(foot_cache *cache, cb_sampler *sampler);

/* How many strides were measured and how many answered from the cache (for tests). */
void foot_cache_counts(const foot_cache *cache, uint32_t *measured, uint32_t *reused);
/* How many of those measured the screen answered (for tests). */
uint32_t foot_cache_screened(const foot_cache *cache);

/* The analyses that share it, each as its public function (which measures with a cache of its
 * own) with the cache given (NULL: uncached). */
void row_travel_measure_cached(foot_cache *cache, cb_sampler *sampler, const cb_clip_info *clip, bool in_place,
                               uint32_t rows, float *offsets, cb_row_travel *out); /* row_travel.c */
void ground_speed_cached(foot_cache *cache, cb_sampler *sampler, const cb_clip_info *clip,
                         cb_ground_speed *out); /* locomotion.c */
/* threads: the clips' strides measured on so many at once (foot_cache_measure_clips); memo: the run's
 * clip analyses (clip_memo.h), or NULL. */
struct clip_memo;
double speed_reference_cached(foot_cache *cache, struct clip_memo *memo, const cb_model *model, int32_t skin,
                              const cb_clip_plan *plan, uint32_t count, uint32_t threads, char *why,
                              size_t size); /* locomotion.c */
/* Whether speed_reference_cached analyzes and may measure the model's animation: its name does not
 * say an action done in place (a clip it cannot analyze at all answers true). */
bool speed_reference_may_measure(const cb_model *model, int32_t animation); /* locomotion.c */

#endif
