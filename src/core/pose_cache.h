/* pose_cache.h - exact joint matrices kept by clip time, for bakes that sample the same times
 * again (internal; see runtime.c's rate search). The probes of one clip's search bake it at
 * rates whose times coincide: a probe's blends at (2k + 1) / 2f are the rows of a probe at
 * twice the rate, and 12, 24 and 48 fps share rows. A time is the same double however it came
 * about (cb_clip_frame_time: t0 + frame x duration / steps, exact when frame and steps double),
 * so the matrices kept for it are the ones sampling gives, bit for bit. */
#ifndef CB_POSE_CACHE_H
#define CB_POSE_CACHE_H

#include <stddef.h>
#include <stdint.h>

typedef struct pose_cache pose_cache;

/* A cache of poses of `bones` joints (16 doubles each), each followed by `extra` doubles for
 * what its user derives from the matrices alone (their first is NaN until it writes them),
 * holding at most max_bytes of them (in blocks of 2 MB: up to one block more); NULL when out
 * of memory. One clip's at a time (the times say nothing of which clip), one thread's. */
pose_cache *pose_cache_create(uint32_t bones, uint32_t extra, size_t max_bytes);
void pose_cache_free(pose_cache *c);

/* The matrices kept for time t (their extra doubles from + 16 x bones), or NULL. */
const double *pose_cache_find(const pose_cache *c, double t);
/* Room for time t's matrices, which the caller writes before the next find of t; NULL when the
 * cache is full (or out of memory): then sample without it. t must not be kept already. A
 * pointer either returns stays valid until pose_cache_free. */
double *pose_cache_add(pose_cache *c, double t);

/* Forgets every pose, keeping the memory for the next clip's (already touched: cheaper than
 * fresh). */
void pose_cache_clear(pose_cache *c);

/* One malloc'ed block its user keeps beside the poses of the same clip (palette.c: a probe's
 * fitted rows), replacing and freeing the one before; freed with the cache and by
 * pose_cache_clear. NULL when none. */
void pose_cache_attach(pose_cache *c, void *block);
void *pose_cache_attached(const pose_cache *c);
/* The same for a second block, the clip's analysis (rate_search.c: the search's, which the bake
 * after it frames instead of analyzing the clip again). */
void pose_cache_attach_analysis(pose_cache *c, void *block);
void *pose_cache_analysis(const pose_cache *c);

/* Poses kept. */
uint32_t pose_cache_count(const pose_cache *c);

#endif
