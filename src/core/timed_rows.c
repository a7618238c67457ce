/* timed_rows.c - a timed clip's map (docs/pal-format.md "Timed rows"): one texel per cell of its
 * grid naming the two rows blended in the cell and their weights at its ends, written by the bake
 * from the cells its rows lie on and read by the runtime's frame. */
#include "crowdbake/palette.h"
#include "timed_rows.h"

#include <math.h>
#include <string.h>

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
