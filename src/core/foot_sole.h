/* foot_sole.h - the feet of a rig, found from its skinned mesh: each foot is the sole of one
 * paw or hoof (the skinned vertices at the bottom of the rest pose, grouped by where they stand),
 * tracked by skinning those vertices as the renderer will, and named after the leg's deform
 * bone, never an IK control or a pole target (rig helpers that move the leg without being it). */
#ifndef CB_FOOT_SOLE_H
#define CB_FOOT_SOLE_H

#include <stdbool.h>
#include <stdint.h>

#include "crowdbake/core.h"

/* One vertex of a sole: its bind position and the joints that move it. */
typedef struct sole_vertex {
    double p[3];
    uint32_t joint[4];
    double weight[4];
} sole_vertex;

typedef struct foot_sole {
    uint32_t joint;     /* the deform bone the foot is named after (index into the skin's joints) */
    uint32_t count;     /* its vertices */
    sole_vertex *v;     /* owned: foot_soles_free */
} foot_sole;

/* Whether a joint's name says it is a rig control (IK target, pole target, controller) rather
 * than part of the body: "IKBackLeg.L", "PoleTarget.L", "foot_ctrl". */
bool rig_name_is_control(const char *name);

/* Per skin joint: whether any of the skin's vertices has weight on it. out: joint_count bools. */
void rig_deforming_joints(const cb_model *m, int32_t skin, bool *out);

/* The rest pose's feet (at most `cap`, the ones with the most sole vertices, in joint order) and
 * the model's height in *size; without a skinned mesh, the lowest leaf joints. rest: the rest
 * pose's joint matrices. */
uint32_t foot_soles_find(cb_sampler *s, const double *rest, foot_sole *out, uint32_t cap, double *size);
void foot_soles_free(foot_sole *f, uint32_t n);

/* Where a foot is under joint matrices `mats`: the mean position of its sole vertices (height,
 * and x, z). The mean, not the lowest vertex: a paw whose toes curl as it lifts (vertices weighted
 * partly to IK bones) drops its toe tips as low as the planted sole, so only the whole sole rises
 * with the step. */
void foot_sole_at(const foot_sole *f, const double *mats, double *height, double xz[2]);

/* foot_sole_at at CB_SAMPLE_BATCH times at once, the same operations per time in their order
 * (the same bits): `lanes` the wanted joints' matrices as cb_sample_joint_subset_batch gives them
 * (every joint the sole reads among `sub`'s). height, x, z: CB_SAMPLE_BATCH each. */
struct cb_joint_subset;
void foot_sole_at_lanes(const foot_sole *f, const struct cb_joint_subset *sub, const double *lanes, double *height,
                        double *x, double *z);

#endif
