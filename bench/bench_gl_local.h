/* bench_gl_local.h - local rows for a bone pass that composes them (issue 43 item 1's lever, weighed before the
 * format has it): a qpos row of joint j holding L_j = M_p^-1 M_j, p its nearest ancestor joint (the .pal bone
 * table's `parent`), instead of M_j. bench_gl --local-rows (with bench/bones_local.glsl) draws from them, so its
 * image is checked against the VAT's, not only timed. */
#ifndef CROWDBAKE_BENCH_GL_LOCAL_H
#define CROWDBAKE_BENCH_GL_LOCAL_H

#include <stdint.h>

#include "crowdbake/crowdbake.h"

/* Each joint's nearest ancestor that is a joint of skin `skin` (-1: none), as pal_write.c's bone table writes it,
 * into parents and into meta's row 2 x (12 floats a joint: cb_bind_positions rows 2..4 of local rows, as
 * docs/pal-format.md's version 6 defines them); the chains' depths on stderr. */
void bench_joint_parents(const cb_model *m, uint32_t skin, int32_t *parents, float *meta);

/* A qpos/u16 palette `global` rewritten with local rows as .pal version 6 holds them (q_L = conj(q_p) q_j,
 * s_L = s_j / s_p, p_L = b_p + rotate(conj(q_p), p_j - p_p) / s_p, from the decoded rows; absolute positions, no
 * offsets), quantized with each bone's ranges: meta's rows 3 and 4 get the bone range table (pos_min xyz, scale_max;
 * pos_max xyz, 0). *local shares the rest of global's fields: free local->texels alone. Before the bake writes local
 * rows itself this is bench_gl's way to draw them (the shipped GLSL with CB_LOCAL_ROWS). */
void bench_local_palette(const cb_palette *global, const int32_t *parents, cb_palette *local, float *meta);

#endif
