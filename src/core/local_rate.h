/* local_rate.h - each clip's rate for local rows (.pal version 6, header flag bit 5; the spec:
 * docs/pal-format.md, issue 43 item 1). Internal to libcrowdbake.
 *
 * Local rows hold each bone's transform in its parent bone's frame; the runtime blends them bone
 * by bone (nlerp, lerp) and composes them down the skeleton. With rows on the clip's keys that is
 * the glTF's own interpolation but for nlerp against slerp, so a clip's rate is its key rate or a
 * small multiple of it, found by measuring those few rates lowest first: no search over two
 * families of rates and two kinds of rows as for global rows (rate_search.c). */
#ifndef CB_LOCAL_RATE_H
#define CB_LOCAL_RATE_H

#include <stdbool.h>
#include <stdint.h>

#include "crowdbake/crowdbake.h"
#include "palette_bake.h" /* palette_skin_facts */

/* What local_clip_rate chose, and why. */
typedef struct local_rate {
    double fps;       /* the rate chosen: the lowest candidate within max_error, else max_fps */
    double error;     /* the worst vertex error measured at fps (model units; float64 rows, before quantisation) */
    double error_mm;  /* the same in mm per metre of the skin's rest height */
    bool met;         /* error <= max_error */
    double key_fps;   /* the clip's key rate (1 / its shortest key step); 0: no key grid, the rate ladder was walked */
    bool on_keys;     /* fps is the key rate or a multiple of it (its rows land on keys) */
    double fps_needed; /* not met: the lowest candidate past max_fps up to CB_FPS_LIMIT within max_error (0: none) */
    uint32_t probes;  /* rates measured */
    bool not_qpos;    /* a joint of a pose is no similarity: qpos cannot hold the rig, whose bake falls back to
                       * global affine rows (palette.c), which this rate is not for */
} local_rate;

/* The skeleton as local rows see it: each bone's parent bone (the nearest ancestor node that is
 * a joint of the skin, -1 for a root) and an order with every parent before its children (the
 * glTF's joint order need not have it). */
typedef struct local_skeleton {
    uint32_t bones;
    int32_t *parent;
    uint32_t *order;
} local_skeleton;

/* False: out of memory. local_skeleton_free frees what it holds (also after a failure). */
bool local_skeleton_build(const cb_model *m, int32_t skin, local_skeleton *out);
void local_skeleton_free(local_skeleton *k);
/* A skeleton of `bones` roots, each bone its own parent: its local rows are global rows, blended
 * as the runtime blends global qpos rows (global_timed.c measures them so). */
bool local_skeleton_roots(uint32_t bones, local_skeleton *out);

/* Clip `clip` (analyzed on this sampler: cb_clip_analyze) baked as local rows: its lowest rate
 * within max_error (model units) up to max_fps (2..CB_FPS_LIMIT). The poses are framed with the
 * bake's root_motion; keep (or NULL): the clip's pose cache for the bake after (palette_probe_poses),
 * which gets the poses at the rows and the row midpoints of every rate measured (a matrix rig's:
 * the bake of a similarity rig samples its own), so the bake samples none of them again. Candidates, lowest first: the
 * key rate and its multiples x1, 2, 3, 4, 6, 8, 12, 16, ... up to max_fps, then max_fps itself;
 * a clip without a key grid (no key step, or a key rate over max_fps) walks the common rates of
 * rate_search.c. Each is measured as the runtime plays it (local rows sampled at the bake's row
 * times in double precision, blended and composed) against the clip's exact pose, every vertex
 * group whose bound can exceed the worst so far skinned, at the quarter points of every row
 * interval. Fails (err set) only when out of memory. */
cb_status local_clip_rate(cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *skeleton,
                          const cb_clip_info *clip, cb_root_motion root_motion, pose_cache *keep, double max_error,
                          double max_fps, local_rate *out, cb_error *err);

/* A clip's rows on its key times (timed rows, docs/pal-format.md "Timed rows"), as local_clip_timed
 * found them. */
typedef struct local_timed {
    bool possible;        /* its keys lie on a grid, and each key interval meets max_error split in at most 4 */
    double key_fps;       /* the grid of its keys (cb_key_grid_fps) */
    double cell_rate;     /* the map's grid: key_fps times the fewest divisions its splits need */
    uint32_t cells;       /* round(duration x cell_rate) */
    uint32_t rows;        /* its rows: each key interval's splits (and a one-shot's end) */
    uint32_t map_rows;    /* cb_timed_map_rows(cells, row_texels) */
    uint32_t *row_cells;  /* rows: each row's cell (malloc'd: the caller's), NULL where not possible */
    uint32_t intervals;   /* key intervals (a loop's wrap one of them) */
    uint32_t split;       /* the most rows any key interval needed */
    double error;         /* the worst error measured (model units, float64 rows, before quantisation) */
    bool too_many;        /* not possible: rows + map rows could not come under the caller's most_rows (rows and
                           * map_rows then say the least they would take, as far as measured) */
    bool not_qpos;        /* a pose had a joint that is no similarity (local_rate.not_qpos): measured as qpos rows,
                           * which the palette's are not */
} local_timed;

/* Clip `clip` (analyzed on this sampler) baked as timed local rows: rows at its key times (every
 * channel's keys merged, and a one-shot's end), each key interval split into the fewest equal
 * parts s = 1..4 whose rows, blended and composed as the runtime plays them, stay within
 * max_error at the quarter points of every row interval (local_clip_rate's measurement). Its
 * cost is rows + map_rows rows of row_texels texels. Nothing possible (out->possible false): a
 * still clip, keys on no grid, an interval over max_error split in 4, or (most_rows > 0) rows +
 * map rows that cannot come under most_rows, given up as soon as that is sure: a clip whose keys
 * fill its key grid, already its uniform rate's rows, is not measured at all (Cow). Fails only
 * out of memory. */
cb_status local_clip_timed(cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *skeleton,
                           const cb_clip_info *clip, cb_root_motion root_motion, pose_cache *keep, double max_error,
                           uint32_t row_texels, uint32_t most_rows, local_timed *out, cb_error *err);

/* The worst vertex error of clip `clip` baked as local rows at `fps` (model units), measured as
 * local_clip_rate measures a candidate, in full (no goal to stop at), root motion kept. For tests
 * and benchmarks. */
double local_rows_error(cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *skeleton,
                        const cb_clip_info *clip, double fps, cb_error *err);

/* The worst vertex error of clip `clip` of a finished local palette p, or a global qpos one (its
 * texels as the runtime decodes them, blended and composed; global rows compose nothing), against `animation`'s exact poses framed as the bake framed
 * them: at its rows into *at_rows, and at the quarter points between them into *between (held
 * rows: the row alone), where nlerp's lag peaks (a midpoint alone misses it: nlerp equals slerp
 * there). Poses the clip's pose cache `keep` holds (the rows and midpoints a search sampled; or
 * NULL) are read from it; the vertex groups' bounds skip what cannot raise the worst. stride > 1: the measuring
 * budget's even subset (palette.h), every stride-th batch of intervals and the last; *measured: the rows measured. */
cb_status local_palette_errors(cb_sampler *sampler, const palette_skin_facts *facts, const cb_palette *p, uint32_t clip,
                               int32_t animation, pose_cache *keep, uint32_t stride, double *at_rows, double *between,
                               uint32_t *measured, cb_error *err);

/* local_rate_search.c: palette_choose_rates for options->bone_space local (the goals' max_fps
 * checked, the skin's facts settled and skinned): every clip with a goal at local_clip_rate's
 * rate (plan[i].fps; plan[i].fit false: local rows are sampled) and what it reached into out[i]
 * (fitted false, other_fps 0; fps_needed where it misses at its max_fps), on options->threads
 * threads. keep (or NULL): each clip's pose cache for the bake, with its analysis. A rig qpos
 * cannot hold (local_rate.not_qpos), whose bake falls back to global affine rows: the rates of
 * palette_choose_rates with bone space global instead (needed_later is its). */
cb_status local_choose_rates(cb_sampler *sampler, const cb_bake_options *options, cb_clip_plan *plan, uint32_t count,
                             const cb_rate_goal *goals, cb_rate_choice *out, search_keep *keep,
                             const palette_skin_facts *facts, const bool *needed_later, cb_error *err);

#endif
