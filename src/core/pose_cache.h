/* pose_cache.h - exact joint matrices kept by clip time, for bakes that sample the same times
 * again (internal; see runtime.c's rate search). The probes of one clip's search bake it at
 * rates whose times coincide: a probe's blends at (2k + 1) / 2f are the rows of a probe at
 * twice the rate, and 12, 24 and 48 fps share rows. A time is the same double however it came
 * about (cb_clip_frame_time: t0 + frame x duration / steps, exact when frame and steps double),
 * so the matrices kept for it are the ones sampling gives, bit for bit. */
#ifndef CB_POSE_CACHE_H
#define CB_POSE_CACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct pose_cache pose_cache;

/* A cache of poses of `bones` joints (16 doubles each), each followed by `extra` doubles for
 * what its user derives from the matrices alone (their first is NaN until it writes them),
 * holding at most max_bytes of them (in blocks of 2 MB: up to one block more); NULL when out
 * of memory. One clip's at a time (the times say nothing of which clip), one thread's. */
pose_cache *pose_cache_create(uint32_t bones, uint32_t extra, size_t max_bytes);
void pose_cache_free(pose_cache *c);

/* Huge pages that the caches of one run share (search_keep: a cache per clip, kept for the bake
 * after the search), handed out in chunks of about 256 KB: each cache's own blocks left its last
 * huge page partly used, and the kernel clears all of a huge page on its first touch (Cow's
 * twelve clips: 25 huge pages, 50 MB cleared, for 36 MB of poses; drawn from an arena, 21).
 * Any thread may draw on it. NULL when out of memory. */
typedef struct pose_arena pose_arena;
pose_arena *pose_arena_create(void);
/* Frees its pages: after every cache that drew on it is freed. */
void pose_arena_free(pose_arena *a);
/* pose_cache_create, its blocks drawn from arena (NULL: its own, as pose_cache_create). */
pose_cache *pose_cache_create_in(pose_arena *arena, uint32_t bones, uint32_t extra, size_t max_bytes);

/* The matrices kept for time t (their extra doubles from + 16 x bones), or NULL. */
const double *pose_cache_find(const pose_cache *c, double t);
/* Room for time t's matrices, which the caller writes before the next find of t; NULL when the
 * cache is full (or out of memory): then sample without it. t must not be kept already. A
 * pointer either returns stays valid until pose_cache_free. */
double *pose_cache_add(pose_cache *c, double t);

/* Forgets every pose, keeping the memory for the next clip's (already touched: cheaper than
 * fresh). */
void pose_cache_clear(pose_cache *c);

/* Forgets every pose as pose_cache_clear does, but keeps what is attached and the worst points,
 * and hands its blocks back to its arena, which gives them to the next cache that needs one
 * (touched already: the kernel clears no page for them). Pointers to its poses are invalid
 * after it. */
void pose_cache_release_poses(pose_cache *c);

/* Malloc'ed blocks its user keeps beside the poses of the same clip, one in each of
 * POSE_CACHE_SLOTS slots (palette_rows.c: a probe's rows), each replacing and freeing the one
 * before in its slot; freed with the cache and by pose_cache_clear. NULL when none. */
enum { POSE_CACHE_SLOTS = 3 };
void pose_cache_attach(pose_cache *c, int slot, void *block);
void *pose_cache_attached(const pose_cache *c, int slot);
/* The same for a second block, the clip's analysis (rate_search.c: the search's, which the bake
 * after it frames instead of analyzing the clip again). */
void pose_cache_attach_analysis(pose_cache *c, void *block);
void *pose_cache_analysis(const pose_cache *c);

/* Where a measurement of the clip found its blends' worst (palette_error.c): the row interval
 * `frame` at fraction sub / parts, in a bake of the clip in `frames` rows. A bake after the
 * search measures that point of its own palette first (an exact floor for its maximum). */
typedef struct pose_worst {
    uint32_t frames, parts, frame, sub;
} pose_worst;
/* Keeps `at`, replacing the one of the same frames and parts (past 16 kept, the oldest). */
void pose_cache_note_worst(pose_cache *c, pose_worst at);
/* The point kept for a bake in `frames` rows measured in `parts`, into *at; false when none. */
bool pose_cache_worst(const pose_cache *c, uint32_t frames, uint32_t parts, pose_worst *at);

/* Poses kept. */
uint32_t pose_cache_count(const pose_cache *c);

#endif
