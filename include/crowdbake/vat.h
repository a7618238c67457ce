/* vat.h - vertex animation textures: every vertex of every baked frame, skinned exactly and
 * stored as RGBA16F positions and normals, to compare with a palette side by side. Frames are
 * framed exactly as the palette's rows (same clips, fps, loops, root motion). */
#ifndef CB_VAT_H
#define CB_VAT_H

#include "export.h"

#include "budget.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_vat {
    uint64_t vertices;
    uint32_t frames;
    uint32_t frame_width;      /* texels of one frame's texture row: min(vertices, max) */
    uint32_t rows_per_frame;   /* ceil(vertices / frame_width) */
    cb_texture_geometry geometry;
    uint16_t *positions;       /* width * height RGBA halves (a = 1); NULL when only measured */
    uint16_t *normals;         /* same, unit normals (a = 0) */
    double max_error;          /* half-float positions against exact skinning, model units */
    double model_height;
} cb_vat;

/* Texel of vertex v in frame f. */
CROWDBAKE_API void cb_vat_texel_xy(const cb_vat *vat, uint32_t frame, uint64_t vertex, uint32_t *x, uint32_t *y);

/* Bakes (store = true) or only measures the error of a VAT of the planned clips (every clip
 * when plan is NULL). Fails when the texture exceeds options->max_texture_size. */
CROWDBAKE_API cb_status cb_vat_bake(cb_sampler *sampler, const cb_bake_options *options, const cb_clip_plan *plan,
                                    uint32_t plan_count, bool store, cb_vat *out, cb_error *err);
CROWDBAKE_API void cb_vat_free(cb_vat *vat);

#ifdef __cplusplus
}
#endif

#endif
