/* timed_rows.h - a timed clip's map (docs/pal-format.md "Timed rows"). Internal. */
#ifndef CB_TIMED_ROWS_H
#define CB_TIMED_ROWS_H

#include "crowdbake/palette.h"

/* Writes clip c's map rows (cb_timed_map_rows of them, just before c->first_row, in p's
 * precision) from the cells its rows lie on: row_cells[k] for k < c->frames, increasing from 0
 * (a one-shot's last at c->cells). */
void timed_map_fill(cb_palette *p, const cb_palette_clip *c, const uint32_t *row_cells);
/* Cell `cell`'s texel of the map of the timed clip starting at first_row: (r0, r1, f0, f1),
 * rows relative to first_row, weights decoded. */
void timed_map_read(const cb_palette *p, const void *texels, uint32_t first_row, uint32_t cells, uint32_t cell,
                    double v[4]);

/* The cells a timed clip's rows lie on, read back from its map (each row's interval starts at the
 * cell whose start weight is 0; a one-shot's last row at cell `cells`): c->frames of them into out. */
void timed_map_row_cells(const cb_palette *p, const void *texels, const cb_palette_clip *c, uint32_t *out);

#endif
