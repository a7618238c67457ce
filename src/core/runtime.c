/* runtime.c - see runtime.h: what the shipped shaders compute, on the CPU (the rate search is
 * rate_search.c, the verification verify.c). */
#include "crowdbake/runtime.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"
#include "palette_bake.h" /* palette_local_matrices */
#include "timed_rows.h"

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

/* A timed clip (rate < 0): its cell at `time`, and the map's texel there (docs/pal-format.md). */
static void timed_frame(const cb_palette *p, const void *texels, const cb_instance *in, double time, uint32_t *row0,
                        uint32_t *row1, double *fr)
{
    bool held = in->first_row < 0;
    double first = held ? -in->first_row - 1 : in->first_row;
    double cells = fabs(in->frame_count), u = time * -in->rate + in->phase * cells, c;
    if (in->frame_count > 0) {
        u = fmod(u, cells);
        if (u < 0) u += cells; /* may round onto `cells`: the last cell below, as a GPU's mod may */
    } else {
        u = u < 0 ? 0 : u > cells ? cells : u;
    }
    c = fmin(floor(u), cells - 1);
    double m[4];
    timed_map_read(p, texels, (uint32_t)first, (uint32_t)cells, (uint32_t)c, m);
    *row0 = (uint32_t)(first + m[0]);
    *row1 = held ? *row0 : (uint32_t)(first + m[1]);
    *fr = held ? 0 : m[2] + (m[3] - m[2]) * (u - c);
}

void cb_runtime_frame_in(const cb_palette *p, const void *texels, const cb_instance *in, double time, uint32_t *row0,
                         uint32_t *row1, double *fr)
{
    if (in->rate < 0) timed_frame(p, texels, in, time, row0, row1, fr);
    else cb_runtime_frame(in, time, row0, row1, fr);
}

cb_instance cb_instance_of(const cb_palette_clip *clip)
{
    double first = clip->step ? -(double)clip->first_row - 1 : clip->first_row;
    if (clip->timed) return (cb_instance){first, clip->loops ? clip->cells : -(double)clip->cells, -clip->cell_rate, 0};
    return (cb_instance){first, clip->loops ? clip->frames : -(double)clip->frames, clip->fps, 0};
}

uint32_t cb_bind_texels(const cb_palette *p, float *rgba)
{
    bool local = p->bone_space == CB_BONE_SPACE_LOCAL;
    uint32_t n = p->bone_count, rows = local ? 5 : 2;
    if (!rgba) return rows;
    memset(rgba, 0, (size_t)n * rows * 4 * sizeof(float));
    for (uint32_t j = 0; j < n; ++j) {
        memcpy(rgba + j * 4, p->bind_positions + j * 3, 3 * sizeof(float));
        if (p->positions_relative) memcpy(rgba + (n + j) * 4, p->position_offsets + j * 3, 3 * sizeof(float));
        if (!local) continue;
        rgba[(2 * n + j) * 4] = (float)p->parents[j];
        memcpy(rgba + (3 * n + j) * 4, p->bone_ranges + j * 8, 4 * sizeof(float)); /* pos_min, scale_max */
        memcpy(rgba + (4 * n + j) * 4, p->bone_ranges + j * 8 + 4, 4 * sizeof(float)); /* pos_max, 0 */
    }
    return rows;
}

void cb_runtime_matrices(const cb_palette *p, const void *texels, const cb_instance *in, double time, double *out)
{
    palette_frame f;
    cb_runtime_frame_in(p, texels, in, time, &f.row0, &f.row1, &f.fr);
    if (p->bone_space == CB_BONE_SPACE_LOCAL && palette_local_matrices(p, texels, &f, NULL, 1, out)) return;
    for (uint32_t j = 0; j < p->bone_count; ++j) cb_palette_blend(p, texels, f.row0, f.row1, f.fr, j, out + (size_t)j * 16);
}

bool cb_runtime_matrices_crossfade(const cb_palette *p, const void *texels, const cb_instance *from,
                                   const cb_instance *to, double fade, double time, double *out)
{
    if (fade >= 1) return cb_runtime_matrices(p, texels, to, time, out), true;
    if (p->bone_space == CB_BONE_SPACE_LOCAL) { /* local rows faded before they are composed */
        palette_frame a, b;
        cb_runtime_frame_in(p, texels, from, time, &a.row0, &a.row1, &a.fr);
        cb_runtime_frame_in(p, texels, to, time, &b.row0, &b.row1, &b.fr);
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
