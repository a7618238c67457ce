/* runtime.c - see runtime.h: what the shipped shaders compute, on the CPU (the rate search is
 * rate_search.c, the verification verify.c). */
#include "crowdbake/runtime.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"
#include "palette_bake.h" /* palette_local_matrices */

void cb_runtime_frame(const cb_instance *in, double time, uint32_t *row0, uint32_t *row1, double *fr)
{
    bool loops = in->frame_count > 0, held = in->first_row < 0;
    double first = held ? -in->first_row - 1 : in->first_row;
    double frames = fabs(in->frame_count), fpos = time * in->rate + in->phase * frames, f0, f1;
    if (loops) {
        fpos = fmod(fpos, frames);
        if (fpos < 0) fpos += frames;
        f0 = floor(fpos);
        f1 = fmod(f0 + 1, frames);
    } else {
        fpos = fpos < 0 ? 0 : fpos > frames - 1 ? frames - 1 : fpos;
        f0 = floor(fpos);
        f1 = f0 + 1 < frames ? f0 + 1 : frames - 1;
    }
    if (held) f1 = f0, fpos = f0; /* a stepped clip: its row alone, no blend across a step */
    *fr = fpos - f0;
    *row0 = (uint32_t)(first + f0);
    *row1 = (uint32_t)(first + f1);
}

cb_instance cb_instance_of(const cb_palette_clip *clip)
{
    double first = clip->step ? -(double)clip->first_row - 1 : clip->first_row;
    return (cb_instance){first, clip->loops ? clip->frames : -(double)clip->frames, clip->fps, 0};
}

void cb_runtime_matrices(const cb_palette *p, const void *texels, const cb_instance *in, double time, double *out)
{
    palette_frame f;
    cb_runtime_frame(in, time, &f.row0, &f.row1, &f.fr);
    if (p->bone_space == CB_BONE_SPACE_LOCAL && palette_local_matrices(p, texels, &f, NULL, 1, out)) return;
    for (uint32_t j = 0; j < p->bone_count; ++j) cb_palette_blend(p, texels, f.row0, f.row1, f.fr, j, out + (size_t)j * 16);
}

bool cb_runtime_matrices_crossfade(const cb_palette *p, const void *texels, const cb_instance *from,
                                   const cb_instance *to, double fade, double time, double *out)
{
    if (fade >= 1) return cb_runtime_matrices(p, texels, to, time, out), true;
    if (p->bone_space == CB_BONE_SPACE_LOCAL) { /* local rows faded before they are composed */
        palette_frame a, b;
        cb_runtime_frame(from, time, &a.row0, &a.row1, &a.fr);
        cb_runtime_frame(to, time, &b.row0, &b.row1, &b.fr);
        return palette_local_matrices(p, texels, &b, &a, fade, out);
    }
    double *other = malloc((size_t)p->bone_count * 16 * sizeof *other);
    if (!other) return false;
    cb_runtime_matrices(p, texels, from, time, other);
    cb_runtime_matrices(p, texels, to, time, out);
    for (size_t k = 0; k < (size_t)p->bone_count * 16; ++k) out[k] = other[k] + (out[k] - other[k]) * fade;
    free(other);
    return true;
}
