/* loop_decide.h - loop or one-shot from the clip's name, poses and feet (loop_decide.c). */
#ifndef CB_LOOP_DECIDE_H
#define CB_LOOP_DECIDE_H

#include <stddef.h>

#include "crowdbake/core.h"

/* Whether a clip's name says an action done once (attack, hit, death...; a leap with no gait
 * beside it): the word, lower-cased, into `word`. A loop under such a name still plays once in a
 * game's eyes (an attack repeated), so it gets no per-row travel either (row_travel.c). */
bool cb_name_says_once(const char *name, char *word, size_t size);

/* Weighs a clip judged by its poses (loop_reason, wrap_jump, largest_step set): fills
 * loop_name, loop_word, loop_pose, loop_feet and loop_striding_feet and sets loops (the sum
 * above 0). Leaves the sampler's period and the framing for the caller to set again. */
void cb_loop_decide(cb_sampler *sampler, double fps, const cb_limits *limits, cb_clip_info *out);

#endif
