/* stride_feet.h - cb_stride_measure in two steps, for callers that measure many clips of one
 * model (foot_cache.h): the feet found once from the rest pose, then each clip measured with
 * them; and the measured tracks kept, so the one number that depends on the clip's row count
 * (cb_stride.slide_mean_varying) is worked out again for another count without sampling. */
#ifndef CB_STRIDE_FEET_H
#define CB_STRIDE_FEET_H

#include <stdbool.h>
#include <stdint.h>

#include "crowdbake/stride.h"
#include "foot_sole.h"

/* The model's feet (foot_soles_find on the rest pose), its height, and the joints their soles
 * read, sampled alone (a big rig's soles read a few of its joints). */
typedef struct stride_feet {
    foot_sole soles[CB_MAX_FEET];
    uint32_t count;
    double size;
    struct cb_joint_subset *joints; /* the joints the soles read (cb_sample_joint_subset_batch) */
} stride_feet;

/* False when out of memory. stride_feet_free releases the soles. */
bool stride_feet_find(cb_sampler *sampler, stride_feet *feet);
void stride_feet_free(stride_feet *feet);

/* The sampled feet of one clip: heights, velocities and planted flags, per foot. */
typedef struct stride_tracks {
    uint32_t feet; /* 0 when not sampled */
    double *buf;
    bool *down;
} stride_tracks;
void stride_tracks_free(stride_tracks *tracks);

/* cb_stride_measure with the feet given: the same result, bit for bit. `keep` receives the
 * tracks (stride_tracks_free). With `screen`, a quarter of the samples are taken first, and a
 * clip on which fewer than two feet could be planted for long enough to stride (stride.c's
 * feet_may_stride) is answered from them: no stride, with a why of its own, its feet's stances
 * and speeds left 0, no tracks kept. Whenever cb_stride_measure finds a stride whose feet are
 * each planted in at most five stretches of the cycle, the screen passes the clip on, and the
 * answer is cb_stride_measure's, bit for bit. */
void stride_measure_feet(cb_sampler *sampler, const cb_clip_info *clip, const stride_feet *feet, bool screen,
                         cb_stride *out, stride_tracks *keep);

/* st->slide_mean_varying again for `rows` rows, from the tracks it was measured with. */
void stride_varying_at(cb_stride *st, const stride_tracks *kept, uint32_t rows);

#endif
