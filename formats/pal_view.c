/* pal_view.c - see pal_view.h. */
#include "crowdbake/pal_view.h"
#include "crowdbake_pal.h"

#include <stdlib.h>
#include <string.h>

cb_status cb_palette_view(const cbpal_file *f, cb_palette *p, cb_error *err)
{
    const cbpal_header *h = &f->header;
    memset(p, 0, sizeof *p);
    p->layout = (cb_layout)h->layout;
    p->precision = (cb_precision)h->precision;
    p->positions_relative = (h->flags & CBPAL_FLAG_POSITIONS_RELATIVE) != 0;
    p->fitted = (h->flags & CBPAL_FLAG_FITTED_ROWS) != 0;
    p->bone_count = h->bone_count;
    p->texels_per_bone = h->texels_per_bone;
    p->row_texels = h->row_texels;
    p->rows = h->rows;
    p->width = h->width;
    p->height = h->height;
    p->blocks = h->blocks;
    p->fps = h->fps;
    p->linear_range = h->linear_range;
    p->max_error = h->max_error;
    p->model_height = h->model_height;
    memcpy(p->bounds_min, h->bounds_min, sizeof p->bounds_min);
    memcpy(p->bounds_max, h->bounds_max, sizeof p->bounds_max);
    p->texel_bytes = f->texels_size;
    p->bind_positions = malloc(sizeof(float) * 3 * h->bone_count);
    p->position_offsets = malloc(sizeof(float) * 3 * h->bone_count);
    p->clips = calloc(h->clip_count ? h->clip_count : 1, sizeof *p->clips);
    p->parents = malloc(sizeof(int32_t) * h->bone_count);
    p->bone_space = h->range_table_offset ? CB_BONE_SPACE_LOCAL : CB_BONE_SPACE_GLOBAL;
    p->bone_ranges = h->range_table_offset ? malloc(sizeof(float) * 8 * h->bone_count) : NULL;
    if (!p->bind_positions || !p->position_offsets || !p->clips || !p->parents || (h->range_table_offset && !p->bone_ranges)) {
        cb_palette_view_free(p);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    for (uint32_t j = 0; j < h->bone_count; ++j) {
        cbpal_bone b;
        cbpal_get_bone(f, j, &b);
        memcpy(p->bind_positions + 3 * j, b.bind_position, sizeof b.bind_position);
        memcpy(p->position_offsets + 3 * j, b.position_offset, sizeof b.position_offset);
        p->parents[j] = b.parent;
        float range[8] = {b.pos_min[0], b.pos_min[1], b.pos_min[2], b.scale_max, b.pos_max[0], b.pos_max[1], b.pos_max[2], 0};
        if (p->bone_ranges) memcpy(p->bone_ranges + 8 * j, range, sizeof range);
    }
    p->clip_count = h->clip_count;
    for (uint32_t i = 0; i < h->clip_count; ++i) {
        cbpal_clip c;
        cbpal_get_clip(f, i, &c);
        cb_palette_clip *d = &p->clips[i];
        d->name = c.name;
        d->first_row = c.first_row;
        d->frames = c.frames;
        d->fps = c.fps;
        d->duration = c.duration;
        d->start = c.start;
        d->loops = (c.flags & CBPAL_CLIP_LOOPS) != 0;
        d->fitted = (c.flags & CBPAL_CLIP_FITTED) != 0;
        d->step = (c.flags & CBPAL_CLIP_STEP) != 0;
        d->timed = (c.flags & CBPAL_CLIP_TIMED) != 0; /* cbpal_open checked its entry and map */
        d->cells = c.cells;
        d->cell_rate = c.cell_rate;
        d->map_rows = c.map_rows;
        memcpy(d->root_velocity, c.root_velocity, sizeof d->root_velocity);
        memcpy(d->bounds_min, c.bounds_min, sizeof d->bounds_min);
        memcpy(d->bounds_max, c.bounds_max, sizeof d->bounds_max);
    }
    return CB_OK;
}

void cb_palette_view_free(cb_palette *p)
{
    free(p->bind_positions);
    free(p->position_offsets);
    free(p->clips);
    free(p->parents);
    free(p->bone_ranges);
    memset(p, 0, sizeof *p);
}
