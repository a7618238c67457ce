/* timed_subset.h - timed rows (.pal version 7) made without the bake choosing them: a uniform bake's
 * rows kept at a non-uniform subset of its cells (intervals of 1, 2 and 3 rows), each timed clip's
 * map written before its first row (timed_map_fill), and the palette written with the library's
 * writer. The conformance cases (runtimes/conformance.h) and the reader's tests use it.
 *
 * A uniform clip's row k lies at cell k of a grid at its own rate (loops: `frames` cells, wrapping
 * to row 0; one-shots: frames - 1 cells, the last row at the end), so the kept rows are exact
 * samples of the clip at their cells. Header-only, like testutil.h. */
#ifndef CROWDBAKE_TEST_TIMED_SUBSET_H
#define CROWDBAKE_TEST_TIMED_SUBSET_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/budget.h"
#include "crowdbake/pal_write.h"
#include "crowdbake/palette.h"
#include "crowdbake_pal.h"
#include "core/timed_rows.h"

#define TIMED_KEEP_ALL UINT32_MAX

/* The cells a clip of `cells` cells keeps, intervals 1, 2, 1, 1, 3 over and over: a loop's before
 * `cells` (its last interval wraps to row 0), a one-shot's ending on `cells`. Returns how many. */
static inline uint32_t timed_subset_cells(uint32_t cells, bool loops, uint32_t *out)
{
    static const uint32_t steps[5] = {1, 2, 1, 1, 3};
    uint32_t n = 0, c = 0;
    out[n++] = 0;
    for (uint32_t i = 0; c + steps[i % 5] < cells; ++i) out[n++] = c += steps[i % 5];
    if (!loops && cells > 0) out[n++] = cells;
    return n;
}

/* Row r's texels from one palette's addressing to another's (the same bones, layout and precision). */
static inline void timed_subset_copy_row(const cb_palette *from, const void *from_texels, uint32_t from_row, cb_palette *to,
                                         uint32_t to_row)
{
    uint32_t fx, fy, tx, ty;
    size_t tb = cb_precision_texel_bytes(from->precision);
    cb_palette_texel_xy(from, from_row, 0, &fx, &fy);
    cb_palette_texel_xy(to, to_row, 0, &tx, &ty);
    memcpy((unsigned char *)to->texels + ((size_t)ty * to->width + tx) * tb,
           (const unsigned char *)from_texels + ((size_t)fy * from->width + fx) * tb, (size_t)from->row_texels * tb);
}

/* `out` = `src` (the file f as cb_palette_view reads it) with every clip but `untimed` timed: its
 * map rows, then its kept rows; texture re-planned under max_texture (0: one block). f's travel
 * offsets follow their rows (map rows 0). Free with timed_subset_free; the rest (bones, names,
 * ranges) is src's. False when it does not fit. */
static inline bool timed_subset_make(const cbpal_file *f, const cb_palette *src, uint32_t untimed, uint32_t max_texture,
                                     cb_palette *out)
{
    const void *src_texels = f->texels;
    *out = *src;
    out->clips = calloc(src->clip_count, sizeof *out->clips);
    uint32_t **cells = calloc(src->clip_count, sizeof *cells), rows = 0;
    for (uint32_t c = 0; c < src->clip_count; ++c) {
        const cb_palette_clip *s = &src->clips[c];
        cb_palette_clip *d = &out->clips[c];
        *d = *s;
        cbpal_clip fc;
        cbpal_get_clip(f, c, &fc);
        d->travel.applied = f->header.travel_table_offset && (fc.travel_heading[0] || fc.travel_heading[2]);
        memcpy(d->travel.heading, fc.travel_heading, sizeof fc.travel_heading);
        cells[c] = malloc(sizeof(uint32_t) * (s->frames + 1));
        if (c == untimed) { /* every row, uniform */
            for (uint32_t k = 0; k < s->frames; ++k) cells[c][k] = k;
            d->first_row = rows, rows += s->frames;
            continue;
        }
        uint32_t n = s->loops ? s->frames : s->frames - 1;
        d->timed = true, d->cells = n, d->cell_rate = s->fps, d->map_rows = cb_timed_map_rows(n, src->row_texels);
        d->frames = timed_subset_cells(n, s->loops, cells[c]);
        d->fps = d->frames / s->duration; /* informative */
        d->first_row = rows + d->map_rows, rows += d->map_rows + d->frames;
    }
    out->rows = rows;
    cb_texture_geometry g;
    bool fits = cb_wrap_rows(out->row_texels, rows, max_texture ? max_texture : UINT32_MAX / 2, &g);
    out->width = g.width, out->height = g.height, out->blocks = g.blocks;
    out->texel_bytes = (size_t)g.width * g.height * cb_precision_texel_bytes(src->precision);
    out->texels = fits ? calloc(out->texel_bytes, 1) : NULL;
    out->texels_borrowed = false;
    out->row_travel = f->header.travel_table_offset ? calloc(rows, sizeof(float)) : NULL;
    for (uint32_t c = 0; fits && c < src->clip_count; ++c) {
        const cb_palette_clip *s = &src->clips[c], *d = &out->clips[c];
        for (uint32_t k = 0; k < d->frames; ++k) {
            timed_subset_copy_row(src, src_texels, s->first_row + cells[c][k], out, d->first_row + k);
            if (out->row_travel) out->row_travel[d->first_row + k] = cbpal_row_travel(f, s->first_row + cells[c][k]);
        }
        if (d->timed) timed_map_fill(out, d, cells[c]);
    }
    for (uint32_t c = 0; c < src->clip_count; ++c) free(cells[c]);
    free(cells);
    return fits;
}

static inline void timed_subset_free(cb_palette *p)
{
    free(p->clips), free(p->texels), free(p->row_travel);
    memset(p, 0, sizeof *p);
}

/* Writes `p` (made from the file `f`) with the library's writer, f's header settings kept. */
static inline cb_status timed_subset_write(const char *path, const cb_palette *p, const cbpal_file *f, const cb_model *m,
                                           cb_error *err)
{
    cb_pal_write_options o = {0};
    o.input_hash = f->header.input_hash;
    o.speed_reference = f->header.speed_reference;
    o.in_place = (f->header.flags & CBPAL_FLAG_IN_PLACE) != 0;
    return cb_pal_write(path, p, m, 0, &o, err);
}

#endif
