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

/* ---- a bake's timed clips ---- */

/* Whether some clip of the plan is timed (its timed_rows and row_cells). */
bool timed_any(const cb_clip_plan *plan, uint32_t count);
/* The palette g, baked uniform at each timed clip's cell rate (plan[c].fps), laid out again: a
 * timed clip keeps only the rows on its row_cells, after its map's rows (left 0, filled once its
 * rows are encoded: timed_fill_maps); other clips' rows as they were. Its row travel, where it has
 * some, is the bake job's to lay out (it reads the plan). */
cb_status timed_keep_rows(cb_palette *g, const cb_clip_plan *plan, uint32_t max_texture_size, const char *source,
                          cb_error *err);
/* Each timed clip's map, from the cells its rows lie on, in the palette's precision. */
void timed_fill_maps(cb_palette *p, const cb_clip_plan *plan);

#endif
