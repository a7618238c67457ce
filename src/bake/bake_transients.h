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

#endif
