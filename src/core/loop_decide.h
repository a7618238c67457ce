/* loop_decide.h - loop or one-shot from the clip's name, poses and feet (loop_decide.c). */
#ifndef CB_LOOP_DECIDE_H
#define CB_LOOP_DECIDE_H

#include <stddef.h>

#include "crowdbake/core.h"

/* A wrap at most this part of the clip's largest key step is its closing key slightly off, not
 * a missing one: a missing closing key makes the wrap about one key step; a closing key
 * slightly off, a small part of one. Over every clip of the shared skinned models whose wrap is
 * no bigger than its neighbour steps, wrap / largest key step is 0.025 to 0.136 for the closing
 * keys slightly off (Cow's and Husky's Gallop_Jump, and two attacks) and 0.261 to 0.590 for the
 * missing ones (the gallops, Husky's Walk): 0.19 sits about x1.4 from both (docs/sampling.md). */
#define CB_LOOP_CORRECTABLE 0.19

/* Whether a clip's name says an action done once (attack, hit, death...; a leap with no gait
 * beside it): the word, lower-cased, into `word`. A loop under such a name still plays once in a
 * game's eyes (an attack repeated), so it gets no per-row travel either (row_travel.c). */
bool cb_name_says_once(const char *name, char *word, size_t size);

/* Weighs a clip judged by its poses (loop_reason, wrap_jump, largest_step set): fills
 * loop_name, loop_word, loop_pose, loop_feet and loop_striding_feet and sets loops (the sum
 * above 0). Leaves the sampler's period and the framing for the caller to set again. */
void cb_loop_decide(cb_sampler *sampler, double fps, const cb_limits *limits, cb_clip_info *out);

#endif
