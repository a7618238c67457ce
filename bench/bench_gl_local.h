/* bench_gl_local.h - local rows for a bone pass that composes them (issue 43 item 1's lever, weighed before the
 * format has it): a qpos row of joint j holding L_j = M_p^-1 M_j, p its nearest ancestor joint (the .pal bone
 * table's `parent`), instead of M_j. bench_gl --local-rows (with bench/bones_local.glsl) draws from them, so its
 * image is checked against the global palette's, not only timed. */
#ifndef CROWDBAKE_BENCH_GL_LOCAL_H
#define CROWDBAKE_BENCH_GL_LOCAL_H

#include <stdint.h>

#include "crowdbake/crowdbake.h"

/* Each joint's nearest ancestor that is a joint of skin `skin` (-1: none), as pal_write.c's bone table writes it,
 * into parents and into meta's w (8 floats a joint: cb_bind_positions rows 2 and 3); the chains' depths on stderr. */
void bench_joint_parents(const cb_model *m, uint32_t skin, int32_t *parents, float *meta);

/* A qpos/u16 palette `global` rewritten with local rows (q_L = conj(q_p) q_j, s_L = s_j / s_p,
 * p_L = b_p + rotate(conj(q_p), p_j - p_p) / s_p, from the decoded rows; absolute positions, no offsets), quantized
 * per bone: one box and scale range for every bone would quantize a child's local position (~bone length / the
 * root's scale) in the root's box (the animated range), and its scale (~1) in the root's range (100 on Cow), then
 * multiply both by the ancestors' scales. The local palette's box is the unit box and its range 1; meta (8 floats a
 * bone, the pass's cb_bind_positions rows 2 and 3) gets each bone's min xyz (row 2, w untouched: the parent) and
 * extent xyz and scale range (row 3). *local shares the rest of global's fields: free local->texels alone. */
void bench_local_palette(const cb_palette *global, const int32_t *parents, cb_palette *local, float *meta);

#endif
