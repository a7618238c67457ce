/* bake_travel.h - the bake job's per-row travel offsets (row_travel.h): measured per clip of a
 * baked palette, kept where they help, unless the settings turn them off. */
#ifndef CB_BAKE_TRAVEL_H
#define CB_BAKE_TRAVEL_H

#include "crowdbake/bake.h"

struct foot_cache;
struct clip_memo;

/* Fills each clip's cb_palette_clip.travel and, where any clip's offsets are applied,
 * p->row_travel (rows floats), with the run's foot analyses (`feet`, foot_cache.h; NULL: measured
 * here) and clip analyses (`memo`, clip_memo.h; NULL: analyzed here). Fails only when out of memory. */
cb_status bake_row_travel(const cb_bake_job *job, struct foot_cache *feet, struct clip_memo *memo, cb_sampler *s,
                          cb_palette *p, cb_error *err);

/* A note per striding loop: its per-row travel applied or not, and why (the numbers). */
void bake_travel_notes(const cb_palette *p, cb_warnings *w);

/* A note per loop closed over its key span with its mismatch spread (CB_LOOP_CLOSED_CORRECTED):
 * how far that moves the poses off the source, and the override (bake_loop_notes.c). memo: the
 * run's clip analyses, or NULL. */
void bake_loop_notes(const cb_bake_job *job, struct clip_memo *memo, cb_sampler *s, const cb_palette *p, cb_warnings *w);

#endif
