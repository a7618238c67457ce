/* blend.c - how the runtime blends two adjacent rows of a palette (cb_palette_blend): the
 * shipped shaders do the same arithmetic in float. Every value is mixed by fr; a qpos
 * quaternion the shorter way round, then normalized.
 *
 * Between two rows a bone's vertices move on arcs (a turning parent swings its children on
 * circles), which this blend cuts as chords. Two other blends were built here and measured on
 * Cow.glb (README, "Better interpolation than linear, measured"): Catmull-Rom over four rows
 * overshoots the kinks a linearly keyed source has at every key, and a dual-quaternion (screw)
 * blend, better on key-aligned rates, needed more rows than fitted rows (src/fit.c) with this
 * blend for the same error; neither shipped. */
#include "palette_bake.h"

void palette_blend_values(const cb_palette *p, uint32_t bone, const double a[16], const double b[16], double fr,
                          double out[16])
{
    double v[16], sign = 1;
    if (p->layout == CB_LAYOUT_QPOS && a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0)
        sign = -1; /* the shorter way between the rows */
    /* Two loops, the first texel's and the rest: no per-value choice of sign, so both vectorize. */
    for (uint32_t k = 0; k < 4; ++k) v[k] = a[k] * (1 - fr) + sign * b[k] * fr;
    for (uint32_t k = 4; k < p->texels_per_bone * 4; ++k) v[k] = a[k] * (1 - fr) + b[k] * fr;
    cb_palette_values_to_matrix(p, bone, v, out); /* normalizes q for qpos */
}

void cb_palette_blend(const cb_palette *p, const void *texels, uint32_t row0, uint32_t row1, double fr, uint32_t bone,
                      double out[16])
{
    double a[16], b[16];
    if (p->bone_space == CB_BONE_SPACE_LOCAL) { /* blend the local rows, then compose (local_rows.c) */
        palette_local_composed(p, texels, row0, row1, fr, bone, a);
        cb_palette_values_to_matrix(p, bone, a, out);
        return;
    }
    cb_palette_decode_values(p, texels, row0, bone, a);
    cb_palette_decode_values(p, texels, row1, bone, b);
    palette_blend_values(p, bone, a, b, fr, out);
}
