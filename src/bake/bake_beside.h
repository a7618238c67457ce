/* bake_beside.h - the bake job's work beside its rate search (internal).
 *
 * The speed reference (locomotion.c) reads none of the searched rates: it analyzes at 30 fps
 * each clip whose name may say a gait, and measures the feet of those that loop. A clip's per-row
 * travel (bake_travel.c) reads only that clip's rate. So both are work beside the search
 * (search_beside): the first search thread to find those clips' searches over does it, from
 * their analyses, while the other threads go on with the clips left; the run then takes the
 * foot and clip analyses made, the reference and the travels (at -j 2 on Cow, before: 5 ms of
 * reference and 3.5 ms of travel after a 38 ms search). Nothing it writes is read before the
 * search's threads are joined; of the job it reads the settings and, of the clips it reads, what
 * their searches wrote before they were over. */
#ifndef CB_BAKE_BESIDE_H
#define CB_BAKE_BESIDE_H

#include <stdbool.h>
#include <stddef.h>

#include "crowdbake/bake.h"
#include "bake_travel.h"
#include "../core/palette_bake.h" /* search_beside, search_keep */

struct foot_cache;
struct clip_memo;

/* The work beside job's search (its plan made, its rates about to be searched): the speed
 * reference where the job has none, and the clips' travels. NULL when out of memory: the run
 * does it all after the search. */
search_beside *bake_beside_create(const cb_bake_job *job);

/* What the run takes from keep's work beside the search (keep, or its beside, NULL: nothing):
 * the foot and clip analyses made there (moved out: the caller frees them; NULL: none), the
 * clips' travels measured (per planned clip, kept by keep; NULL: none), and true with the speed
 * reference and why it was chosen where it was decided there. */
bool bake_beside_take(search_keep *keep, struct foot_cache **feet, struct clip_memo **memo,
                      const measured_travel **travel, double *speed, char *why, size_t size);

#endif
