/* leg_ik.h - analytic two-bone IK: a leg chain hip (a), knee (b), ankle (c) turned so that the
 * ankle reaches a target, the bones keeping their lengths and the knee bending in its own plane.
 * Internal (plant_feet.c). */
#ifndef CB_LEG_IK_H
#define CB_LEG_IK_H

#include "cb_math.h"

/* The turns that bring the ankle to `target`: the hip's bone turns by *hip (a world rotation
 * about a), then the knee's bone by *knee (a world rotation about the knee's new place, applied
 * after *hip). The knee keeps its plane: a target in the plane of a, b, c leaves the plane where
 * it is, and one off it turns the plane by the angle the hip-target line leaves it, no more (the
 * plane through that line nearest the old one), the knee on the side it was. A target out of
 * reach (past the straight leg, or inside the folded one) is met as nearly as the chain allows:
 * the ankle's new place is returned. A chain already straight (no plane to bend in) bends in the
 * plane that holds `pole` (a direction the knee points, e.g. the body's forward). */
cb_vec3 leg_ik_solve(cb_vec3 a, cb_vec3 b, cb_vec3 c, cb_vec3 target, cb_vec3 pole, cb_quat *hip, cb_quat *knee);

/* The shortest rotation taking direction u to direction v (neither zero). */
cb_quat leg_ik_turn(cb_vec3 u, cb_vec3 v);

#endif
