/* local_lanes.h - local rows measured four points at a time (local_rate.c's rate choice and its
 * measurement of a finished palette). Internal to libcrowdbake. */
#ifndef CB_LOCAL_LANES_H
#define CB_LOCAL_LANES_H

#include <stdbool.h>
#include <stdint.h>

#include "error_bound.h"
#include "local_pose.h"
#include "local_rate.h" /* local_skeleton */

/* Four points of a clip's local rows against its exact poses, lane l (0..3) each: the local
 * rows a[l] and b[l] (one a bone) blended by f[l] and composed down the skeleton as the runtime
 * plays them (local_qpos_blend, then local_qpos_compose about the parent's bind position in
 * compose_bind, every quaternion normalised after composing), each bone's matrix about its bind
 * position in `bind` (v -> p + s R (v - b)) taken from the exact one: mats[l] (16 doubles a
 * bone, column-major), or where mats is NULL the exact global rows exact[l] made matrices alike.
 * Into diff + l x bones x 16 (exact less composed, a bone's 16 doubles; zero for a bone whose
 * reach is negative: it moves no vertex) and joints + l x bones (cb_joint_errors's terms of
 * them, each pointing at its difference); finite[l]: cb_joint_errors's answer. Each lane runs
 * the scalar operations in their order (local_pose.h, cb_math.h, error_bound.h), so its values
 * are the bits one point at a time gives. composed: room for bones x 32 doubles, 32-byte
 * aligned. */
void local_points4(const local_skeleton *k, const float *compose_bind, const float *bind, const double *reach,
                   const local_qpos *const a[4], const local_qpos *const b[4], const double f[4],
                   const double *const *mats, const local_qpos *const exact[4], double *composed, double *diff,
                   cb_joint_error *joints, bool finite[4]);

#endif
