/* locomotion.h - which clips follow an instance's speed (locomotion) and the speed reference a
 * bake records: decided in the library, so that a program linking it and the crowdbake command
 * record the same speed reference for the same model (a catalog's states add their own words
 * on top: the command's cb_decide_sync). */
#ifndef CB_LOCOMOTION_H
#define CB_LOCOMOTION_H

#include "export.h"

#include "core.h"
#include "palette.h"
#include "stride.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Ground speed of a clip in model units per second, from two pieces of evidence: the root's
 * horizontal travel and the clip's stride (stride.h: the speed at which its planted feet slide
 * least). The stride's speed where the feet stride (it holds the root's travel too, since the
 * feet are measured in the frame that travel is taken off); else the root's travel where it
 * moves more than 1% of the model's height per second; else 0. */
typedef struct cb_ground_speed {
    double speed;       /* the ground speed: what foot-sync uses */
    double root, feet;  /* both measurements; feet 0 without a stride */
    const char *method; /* "planted feet", "root motion" or "none" (static strings) */
    cb_stride stride;   /* the feet: the stride, its ground speed and the feet's slide */
} cb_ground_speed;
CROWDBAKE_API void cb_measure_ground_speed(cb_sampler *sampler, const cb_clip_info *clip, cb_ground_speed *out);

/* What a name's words say about locomotion: 1 for a gait (walk, run, gallop, swim, fly...), -1
 * for an action done in place (idle, eat, attack, hit, death...), 0 when no word says; the first
 * such word, lower-cased, into `word`. */
CROWDBAKE_API int cb_name_says_locomotion(const char *name, char *word, size_t size);

/* Whether a clip follows the instance's speed, from what words say (`kind` as above, `words`
 * the sentence naming them), whether it loops, its ground speed and whether a speed reference
 * is given; why in `reason`. A one-shot never follows speed; where no word decides, its stride
 * (or its root's travel) does. */
CROWDBAKE_API bool cb_decide_locomotion(int kind, const char *words, bool loops, const cb_ground_speed *speed,
                                        bool speed_given, char *reason, size_t size);

/* The speed reference of a single model's bake (no catalog): the ground speed of its slowest
 * clip that follows the speed, decided from the clip's name as above; 0 when none does. `plan`
 * the clips baked (NULL: every clip); why, with "--speed-reference overrides", in `why`. */
CROWDBAKE_API double cb_speed_reference(const cb_model *model, int32_t skin, const cb_clip_plan *plan, uint32_t count,
                                        char *why, size_t size);

#ifdef __cplusplus
}
#endif

#endif
