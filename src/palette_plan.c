/* palette_plan.c - what a bake settles before sampling: every clip's frames and rows, the
 * texture's geometry (rows wrapped into column blocks), the bind positions and the padding. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/budget.h"
#include "palette_bake.h"

/* ---- geometry of the texture ---- */

cb_status palette_plan_texture(cb_palette *p, uint32_t max_size, const char *source, cb_error *err)
{
    if (max_size < 1) return cb_fail(err, CB_ERR_SETTINGS, "--max-texture-size must be at least 1");
    if (p->row_texels > max_size)
        return cb_fail(err, CB_ERR_INPUT,
                       "%s: %u bones x %u texels = %u texels per row, wider than --max-texture-size %u; use a layout "
                       "with fewer texels per bone (qpos: 2) or a larger limit",
                       source, p->bone_count, p->texels_per_bone, p->row_texels, max_size);
    cb_texture_geometry g;
    if (!cb_wrap_rows(p->row_texels, p->rows, max_size, &g))
        return cb_fail(err, CB_ERR_INPUT,
                       "%s: %u baked rows do not fit a %ux%u texture even wrapped into %u columns of %u rows; lower "
                       "--fps, bake fewer clips, or raise --max-texture-size",
                       source, p->rows, max_size, max_size, max_size / p->row_texels, max_size);
    p->blocks = g.blocks, p->height = g.height, p->width = g.width;
    return CB_OK;
}

cb_status palette_frame_clips(bake_state *st, cb_sampler *sampler, const cb_clip_plan *plan, uint32_t count,
                             cb_clip_info **infos_out, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_model *m = st->model;
    if (!plan) count = m->animation_count;
    cb_clip_info *infos = calloc(count ? count : 1, sizeof *infos);
    p->clips = calloc(count ? count : 1, sizeof *p->clips);
    *infos_out = infos;
    if (!infos || !p->clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint64_t rows = 0;
    for (uint32_t i = 0; i < count; ++i) {
        cb_clip_plan one = plan ? plan[i] : (cb_clip_plan){(int32_t)i, NULL, -1, 0};
        double fps = cb_clip_plan_fps(&one, st->opt->fps);
        if (cb_clip_analyze(sampler, one.animation, fps, one.loop, &st->opt->limits, &infos[i], err)) return err->status;
        cb_palette_clip *c = &p->clips[i];
        c->name = one.name ? one.name : m->animations[one.animation].name;
        c->first_row = (uint32_t)rows;
        c->frames = infos[i].frames;
        c->fps = infos[i].effective_fps;
        c->duration = infos[i].duration;
        c->start = infos[i].t0;
        c->loops = infos[i].loops;
        c->ground_speed = infos[i].ground_speed;
        for (int k = 0; k < 3; ++k)
            c->root_velocity[k] = (float)(st->opt->root_motion == CB_ROOT_MOTION_IN_PLACE ? infos[i].root_velocity[k] : 0);
        rows += infos[i].frames;
        if (rows > st->opt->limits.max_frames)
            return cb_fail(err, CB_ERR_INPUT, "%s: %llu baked rows over all clips, over the limit of %u (--max-frames)",
                           m->source, (unsigned long long)rows, st->opt->limits.max_frames);
    }
    p->clip_count = count;
    p->rows = (uint32_t)rows;
    return CB_OK;
}

void palette_bind_positions(cb_palette *p, const cb_skin *skin)
{
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        /* The joint's bind-pose position is the translation of inverse(IBM). */
        const double *ibm = skin->inverse_bind + (size_t)j * 16;
        double det = cb_mat4_determinant3(ibm);
        cb_vec3 b = {0, 0, 0};
        if (fabs(det) > 1e-300) {
            /* Solve A b = -t with Cramer's rule. */
            double t[3] = {-ibm[12], -ibm[13], -ibm[14]}, col[16];
            double *res[3] = {&b.x, &b.y, &b.z};
            for (int k = 0; k < 3; ++k) {
                memcpy(col, ibm, sizeof col);
                col[k * 4 + 0] = t[0], col[k * 4 + 1] = t[1], col[k * 4 + 2] = t[2];
                *res[k] = cb_mat4_determinant3(col) / det;
            }
        }
        p->bind_positions[j * 3] = (float)b.x, p->bind_positions[j * 3 + 1] = (float)b.y;
        p->bind_positions[j * 3 + 2] = (float)b.z;
    }
}

/* The texels no row covers, which stay zero: in the last block the rows past the last baked
 * one. (Every row's texels are written by the encoder.) */
void palette_zero_padding(cb_palette *p)
{
    size_t tb = cb_precision_texel_bytes(p->precision);
    unsigned char *texels = p->texels;
    for (uint32_t y = 0; y < p->height; ++y) {
        uint32_t blocks_here = p->rows / p->height + (y < p->rows % p->height);
        size_t x0 = (size_t)blocks_here * p->row_texels;
        if (x0 < p->width) memset(texels + ((size_t)y * p->width + x0) * tb, 0, (p->width - x0) * tb);
    }
}
