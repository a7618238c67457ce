/* global_timed.h - timed rows (docs/pal-format.md "Timed rows") for global rows, asked for with
 * timed rows on: a clip's rows on its key times, each key interval split into the fewest equal
 * parts (1 to 4) within its budget, weighed after its uniform rate (rate_search.c) and taken where
 * they cost fewer bytes; laid out by the bake (palette.c). Internal to libcrowdbake. */
#ifndef CB_GLOBAL_TIMED_H
#define CB_GLOBAL_TIMED_H

#include "crowdbake/runtime.h"
#include "palette_bake.h" /* palette_skin_facts, pose_cache */

/* Whether the bake asks for global timed rows for this clip: timed rows on, global qpos rows,
 * sampled (no --fit-rows), not held. */
bool global_timed_asked(const cb_bake_options *o, const cb_clip_plan *plan);

/* The clip's rows on its keys, where its keys lie on a grid, every key interval meets max_error
 * (model units) split in at most 4, and its rows and map rows are fewer than the uniform rate's
 * the plan held: the plan made timed (its fps the cell rate, sampled, row_cells its own) and
 * *choice saying so (met, error, timed_*). Elsewhere the plan keeps the uniform rate; *choice
 * has uniform_* and, where they were measured (timed_weighed), what rows on its keys take. cache:
 * the clip's pose cache from its rate search, or NULL. Fails only out of memory. */
cb_status global_clip_timed(cb_sampler *s, const cb_bake_options *o, cb_clip_plan *plan, const palette_skin_facts *facts,
                            pose_cache *cache, double max_error, cb_rate_choice *choice, cb_error *err);

/* The global palette p, baked uniform at each timed clip's cell rate, laid out timed (timed_rows.h)
 * and its timed clips' errors measured as the runtime plays them (every row, and the quarter points
 * between every two, through the map; probe: the search's poses, or NULL) into their visible_error
 * and the palette's. */
cb_status palette_time_global_rows(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *plan, uint32_t count,
                                   const palette_skin_facts *facts, const palette_probe *probe, cb_palette *p, cb_error *err);

#endif
