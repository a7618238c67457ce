/* bake_transients.h (internal) - the bake job's fast transients: a clip the default goal is out
 * of reach for at the default max_fps searched on to CB_TRANSIENT_MAX_FPS (runtime.h). */
#ifndef CB_BAKE_TRANSIENTS_H
#define CB_BAKE_TRANSIENTS_H

#include "crowdbake/bake.h"
#include "crowdbake/runtime.h"

/* After the job's rate search (job->rates, job->plan): every error-bounded clip over crowdbake's
 * default max_error at the default max_fps, neither of them stated by the user, is searched
 * again up to CB_TRANSIENT_MAX_FPS. A clip that meets the goal there takes the fewest rows that
 * do, and its settings say why (max_fps CB_TRANSIENT_MAX_FPS, from CB_FROM_TRANSIENT); one that
 * does not keeps its first answer (no more rows for an error still over the goal). */
cb_status bake_reach_for_transients(cb_bake_job *job, cb_sampler *s, const cb_bake_options *o, cb_error *err);
/* The clips bake_reach_for_transients searches on where the job's rate search finds them over
 * the goal (per clip, malloc'd; NULL: out of memory): that search leaves their fps_needed to it
 * (palette_choose_rates' needed_later), which searches on from past its own cap. Robot_Punch:
 * the rates past 120 fps that would meet it, searched at 180 and 240 fps fitted (80 M
 * instructions of the robot's 900 M), only to be searched again to 240 fps by the next search. */
bool *bake_transient_candidates(const cb_bake_job *job);

#endif
