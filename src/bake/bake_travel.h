/* bake_travel.h - the bake job's per-row travel offsets (row_travel.h): measured per clip of a
 * baked palette, kept where they help, unless the settings turn them off. */
#ifndef CB_BAKE_TRAVEL_H
#define CB_BAKE_TRAVEL_H

#include "crowdbake/bake.h"

struct foot_cache;
struct clip_memo;

/* One clip's per-row travel measured at `fps` (bake_clip_travel): an offset per row of the clip
 * framed at that rate (`cells` of them; a clip on timed rows keeps those at its rows' cells) and
 * what was measured. made false: nothing measured (travel.why says why, where it was tried). */
typedef struct measured_travel {
    bool made;
    double fps;
    uint32_t cells;
    float *offsets; /* the measurer's (free) */
    cb_row_travel travel;
} measured_travel;

/* Planned clip c's per-row travel at the rate the job bakes it at now (cb_bake_job_clip_fps),
 * with the run's foot and clip analyses (`feet`, `memo`; NULL: measured here). False only when
 * out of memory. Reads of the job only what its search wrote for clip c, so it may run beside the
 * search once clip c's search is over (bake_beside.c). */
bool bake_clip_travel(const cb_bake_job *job, uint32_t c, struct foot_cache *feet, struct clip_memo *memo, cb_sampler *s,
                      measured_travel *out);

/* Fills each clip's cb_palette_clip.travel and, where any clip's offsets are applied,
 * p->row_travel (rows floats), with the run's foot analyses (`feet`, foot_cache.h; NULL: measured
 * here) and clip analyses (`memo`, clip_memo.h; NULL: analyzed here); a clip's measured ahead at
 * the rate it was baked at (ahead[c], per planned clip; NULL: none) is taken, the same numbers.
 * Fails only when out of memory. */
cb_status bake_row_travel(const cb_bake_job *job, struct foot_cache *feet, struct clip_memo *memo, cb_sampler *s,
                          const measured_travel *ahead, cb_palette *p, cb_error *err);

/* A note per striding loop: its per-row travel applied or not, and why (the numbers). */
void bake_travel_notes(const cb_palette *p, cb_warnings *w);

/* A note per loop closed over its key span with its mismatch spread (CB_LOOP_CLOSED_CORRECTED):
 * how far that moves the poses off the source, and the override (bake_loop_notes.c). memo: the
 * run's clip analyses, or NULL. */
void bake_loop_notes(const cb_bake_job *job, struct clip_memo *memo, cb_sampler *s, const cb_palette *p, cb_warnings *w);

#endif
