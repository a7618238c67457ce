/* measure_lanes.h - one bone's differences (exact less decoded) and their bound terms for a
 * batch of measured rows, the rows as lanes (palette_error.c's measurement). Internal. */
#ifndef CB_MEASURE_LANES_H
#define CB_MEASURE_LANES_H

#include <stdbool.h>
#include <stdint.h>

#include "error_bound.h"
#include "palette_bake.h"

/* Bone j of the batch's rows, measured against similarities: lane i's exact matrix from the
 * sampler's lanes `sim` (sim[0 .. 3] the quaternion, [4 .. 6] the translation, [7] the scale:
 * cb_similarity_matrix's operations), or from the joint matrices mats[i] where sim is NULL (a
 * rig that is not made of similarities); its decoded one from rows a[i] (blended towards b[i]
 * by fr when b: palette_blend_values's operations; CB_SAMPLE_BATCH of each, those past count
 * repeating the last) as cb_palette_values_to_matrix builds a qpos bone, and their difference
 * into row i's diff (diff + i * bones * 16: every lane, those past count repeat the last); the
 * difference's bound terms (cb_joint_errors's) into row i's joints, for the first `count` rows,
 * and whether they are finite into finite[i] (and-ed). The same operations in the same order as
 * one matrix at a time, so the same bits. */
void palette_bone_differences(const cb_palette *p, uint32_t j, const double (*sim)[CB_SAMPLE_BATCH],
                              const double *const *mats, const double *const *a, const double *const *b, uint32_t count,
                              double fr, double *diff, cb_joint_error *joints, bool *finite);

#endif
