/* timed_rows.c - a timed clip's map (docs/pal-format.md "Timed rows"): one texel per cell of its
 * grid naming the two rows blended in the cell and their weights at its ends, written by the bake
 * from the cells its rows lie on and read by the runtime's frame; and a bake's timed clips laid out
 * (their rows kept from a uniform bake at their cell rate, their maps made room for). */
#include "crowdbake/palette.h"
#include "timed_rows.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "palette_bake.h" /* palette_plan_texture */

uint32_t cb_timed_map_rows(uint32_t cells, uint32_t row_texels)
{
    return row_texels ? (uint32_t)(((uint64_t)cells + row_texels - 1) / row_texels) : 0;
}

const cb_palette_clip *cb_palette_timed_clip(const cb_palette *p)
{
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].timed) return &p->clips[c];
    return NULL;
}

static unsigned char *map_texel(const cb_palette *p, const void *texels, uint32_t first_row, uint32_t cells,
                                uint32_t cell)
{
    uint32_t row = first_row - cb_timed_map_rows(cells, p->row_texels) + cell / p->row_texels, x, y;
    uint32_t k = cell % p->row_texels;
    cb_palette_texel_xy(p, row, k / p->texels_per_bone, &x, &y);
    size_t tb = cb_precision_texel_bytes(p->precision);
    return (unsigned char *)texels + ((size_t)y * p->width + x + k % p->texels_per_bone) * tb;
}

static void put_texel(const cb_palette *p, unsigned char *t, const double v[4])
{
    for (int i = 0; i < 4; ++i) {
        if (p->precision == CB_PRECISION_FLOAT) {
            float f = (float)v[i];
            memcpy(t + 4 * i, &f, 4);
        } else {
            uint16_t h = p->precision == CB_PRECISION_HALF ? cb_float_to_half((float)v[i])
                         : i < 2                          ? (uint16_t)v[i]
                                                          : (uint16_t)lround(v[i] * 65535);
            t[2 * i] = (unsigned char)(h & 0xff), t[2 * i + 1] = (unsigned char)(h >> 8);
        }
    }
}

void timed_map_fill(cb_palette *p, const cb_palette_clip *c, const uint32_t *row_cells)
{
    uint32_t map_rows = cb_timed_map_rows(c->cells, p->row_texels);
    for (uint32_t r = 0; r < map_rows; ++r) { /* unused texels 0 */
        uint32_t x, y;
        cb_palette_texel_xy(p, c->first_row - map_rows + r, 0, &x, &y);
        memset((unsigned char *)p->texels + ((size_t)y * p->width + x) * cb_precision_texel_bytes(p->precision), 0,
               (size_t)p->row_texels * cb_precision_texel_bytes(p->precision));
    }
    uint32_t k = 0;
    for (uint32_t cell = 0; cell < c->cells; ++cell) {
        while (k + 1 < c->frames && row_cells[k + 1] <= cell) ++k;
        bool wraps = k + 1 >= c->frames; /* a loop's last interval, into row 0 at cell `cells` */
        double start = row_cells[k], end = wraps ? c->cells : row_cells[k + 1];
        double v[4] = {k, wraps ? 0 : k + 1, (cell - start) / (end - start), (cell + 1 - start) / (end - start)};
        put_texel(p, map_texel(p, p->texels, c->first_row, c->cells, cell), v);
    }
}

void timed_map_row_cells(const cb_palette *p, const void *texels, const cb_palette_clip *c, uint32_t *out)
{
    for (uint32_t k = 0; k < c->frames; ++k) out[k] = c->cells;
    for (uint32_t cell = 0; cell < c->cells; ++cell) {
        double v[4];
        timed_map_read(p, texels, c->first_row, c->cells, cell, v);
        if (v[2] == 0 && v[0] < c->frames) out[(uint32_t)v[0]] = cell;
    }
}

void timed_map_read(const cb_palette *p, const void *texels, uint32_t first_row, uint32_t cells, uint32_t cell,
                    double v[4])
{
    const unsigned char *t = map_texel(p, texels, first_row, cells, cell);
    for (int i = 0; i < 4; ++i) {
        if (p->precision == CB_PRECISION_FLOAT) {
            float f;
            memcpy(&f, t + 4 * i, 4);
            v[i] = f;
        } else {
            uint16_t h = (uint16_t)(t[2 * i] | t[2 * i + 1] << 8);
            v[i] = p->precision == CB_PRECISION_HALF ? cb_half_to_float(h) : i < 2 ? h : h / 65535.0;
        }
    }
}

/* ---- timed clips: the rows on their cells kept, their maps made room for ---- */

bool timed_any(const cb_clip_plan *plan, uint32_t count)
{
    for (uint32_t i = 0; plan && i < count; ++i)
        if (plan[i].timed_rows) return true;
    return false;
}

cb_status timed_keep_rows(cb_palette *g, const cb_clip_plan *plan, uint32_t max_texture_size, const char *source,
                                 cb_error *err)
{
    cb_palette old = *g; /* the uniform rows' geometry, to read them */
    uint32_t rows = 0, *old_first = malloc((g->clip_count ? g->clip_count : 1) * sizeof *old_first);
    if (!old_first) return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for timed rows", source);
    for (uint32_t c = 0; c < g->clip_count; ++c) {
        cb_palette_clip *clip = &g->clips[c];
        old_first[c] = clip->first_row;
        const cb_clip_plan *pl = &plan[c];
        if (pl->timed_rows) {
            uint32_t cells = cb_clip_step_count(clip->duration, pl->fps);
            if (clip->frames != cells + (clip->loops ? 0 : 1) || pl->row_cells[pl->timed_rows - 1] > cells)
                return free(old_first), cb_fail(err, CB_ERR_INTERNAL, "%s: clip '%s' framed at %u rows, not on its %u cells", source,
                               clip->name, clip->frames, cells);
            clip->timed = true, clip->cells = cells, clip->cell_rate = pl->fps;
            clip->map_rows = cb_timed_map_rows(cells, g->row_texels);
            clip->frames = pl->timed_rows;
            clip->fps = clip->duration > 0 ? clip->frames / clip->duration : clip->fps;
            rows += clip->map_rows;
        }
        clip->first_row = rows;
        rows += clip->frames;
    }
    g->rows = rows;
    if (palette_plan_texture(g, max_texture_size, source, err)) return free(old_first), err->status;
    size_t tb = cb_precision_texel_bytes(g->precision);
    g->texel_bytes = (size_t)g->width * g->height * tb;
    g->texels = calloc(g->texel_bytes ? g->texel_bytes : 1, 1);
    if (!g->texels) return free(old_first), g->texels = old.texels, cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for timed rows", source);
    for (uint32_t c = 0; c < g->clip_count; ++c) {
        const cb_palette_clip *clip = &g->clips[c];
        for (uint32_t k = 0; k < clip->frames; ++k) { /* a row's texels lie side by side in its block */
            uint32_t from = old_first[c] + (clip->timed ? plan[c].row_cells[k] : k), x0, y0, x1, y1;
            cb_palette_texel_xy(&old, from, 0, &x0, &y0);
            cb_palette_texel_xy(g, clip->first_row + k, 0, &x1, &y1);
            memcpy((unsigned char *)g->texels + ((size_t)y1 * g->width + x1) * tb,
                   (const unsigned char *)old.texels + ((size_t)y0 * old.width + x0) * tb, (size_t)g->row_texels * tb);
        }
    }
    if (!old.texels_borrowed) free(old.texels);
    g->texels_borrowed = false;
    free(old_first);
    return CB_OK;
}

void timed_fill_maps(cb_palette *p, const cb_clip_plan *plan)
{
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].timed) timed_map_fill(p, &p->clips[c], plan[c].row_cells);
}
