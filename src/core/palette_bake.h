/* palette_bake.h - what the palette bake's files share (private to libcrowdbake): the
 * per-thread scratch and the bake's state, the u16 value ranges, and the passes that live in
 * files of their own: the rows (palette_rows.c), texel encoding (palette_codec.c), the plan
 * (palette_plan.c) and the error measure (palette_error.c). palette.c runs them. */
#ifndef CB_PALETTE_BAKE_H
#define CB_PALETTE_BAKE_H

#include <math.h>
#include <stdatomic.h>

#include "crowdbake/palette.h"
#include "cb_math.h"
#include "pose_cache.h"
#include "vertex_groups.h"

/* Canonical floats per bone and row before the final encoding: the upper 3x4 of the matrix
 * by rows (mat4, affine), or quaternion, position and scale (qpos). */
/* Floats per bone per row before encoding: the texels' values (qpos uses 8 of them). */
#define CANON(layout) ((layout) == CB_LAYOUT_QPOS ? 8u : 12u)

/* What u16 quantization needs of the values: the box of the translations (or positions) and
 * the largest linear term (or qpos scale). Kept per clip while sampling, merged after. */
typedef struct value_range {
    float lo[3], hi[3], linear;
} value_range;

static inline void range_reset(value_range *r)
{
    for (int k = 0; k < 3; ++k) r->lo[k] = INFINITY, r->hi[k] = -INFINITY;
    r->linear = 0;
}

/* Compares, not fminf/fmaxf: the values are finite and the compares inline. A qpos bone's
 * position and scale, written out per axis so a local range stays in registers. */
static inline void range_grow_qpos(value_range *r, const float *v)
{
    r->lo[0] = v[4] < r->lo[0] ? v[4] : r->lo[0];
    r->lo[1] = v[5] < r->lo[1] ? v[5] : r->lo[1];
    r->lo[2] = v[6] < r->lo[2] ? v[6] : r->lo[2];
    r->hi[0] = v[4] > r->hi[0] ? v[4] : r->hi[0];
    r->hi[1] = v[5] > r->hi[1] ? v[5] : r->hi[1];
    r->hi[2] = v[6] > r->hi[2] ? v[6] : r->hi[2];
    r->linear = v[7] > r->linear ? v[7] : r->linear;
}

/* An affine or mat4 bone's 12 canonical values (3 rows of 4). */
static inline void range_grow_affine(value_range *r, const float *v)
{
    for (int k = 0; k < 3; ++k) {
        float t = v[k * 4 + 3];
        if (t < r->lo[k]) r->lo[k] = t;
        if (t > r->hi[k]) r->hi[k] = t;
    }
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
            if (fabsf(v[i * 4 + k]) > r->linear) r->linear = fabsf(v[i * 4 + k]);
}

/* pose_batch.c: what samples a skin's every joint at a batch of times at once, for one thread. */
typedef struct pose_batch pose_batch;
pose_batch *pose_batch_create(const cb_sampler *sampler); /* NULL: out of memory */
void pose_batch_free(pose_batch *b); /* and the measurement scratch it keeps */
/* The slot for the measurement scratch a search thread keeps across its probes (palette_error.c),
 * freed with b: a probe's measurement reads every row of its clip several times (palette_error.c's
 * table), and a scratch made afresh for each probe would be fresh memory each time. */
struct measure_scratch **pose_batch_measure(pose_batch *b);
/* The slot for the lanes a search thread's probe sampled its rows from (palette_rows.c's
 * row_lanes), freed with b: a probe's baked rows are measured against those very poses. */
struct row_lanes **pose_batch_row_lanes(pose_batch *b);

/* Per-thread scratch: each worker samples its own clips with its own sampler. */
typedef struct worker {
    cb_sampler *sampler;
    double *mats;        /* bones * 16 */
    cb_quat *prev;       /* bones: the previous row's quaternion (qpos) */
    float *rows;         /* pre-encoding rows: CB_SAMPLE_BATCH of them, or a whole clip's for a fitted one */
    uint32_t rows_held;  /* the rows `rows` has room for */
    float *first;        /* bones * 4: the first row's quaternions (qpos), for the loop's wrap */
    struct measure_scratch *measure; /* palette_error.c's, made by the worker's first measurement job */
    pose_batch *batch;   /* its batches of poses (palette_prefetch_poses), made when first needed */
    double *local_lanes; /* a local bake's (st->local): bones x 8 x CB_SAMPLE_BATCH, a batch's joints as global qpos
                          * lanes (joint_into_local), for local_rows_from_lanes */
} worker;

/* A local bake's float bake (palette_bake_local): each clip whose rows come from the sampler's
 * lanes (a similarity rig's) is sampled local at once, from the double poses, where converting
 * its global floats after cost the local bake twice its sampling (the 200-joint rig at 30 fps);
 * the others are converted once baked. Owned by palette_bake_local. */
typedef struct local_sampling {
    const int32_t *parents; /* bones: each one's nearest ancestor joint, -1 for a root (palette_local_parents) */
    double *ranges;         /* clip c, bone j: its local floats' lo[3], hi[3] and scale max at ((c * bones) + j) * 7 */
    unsigned char *sampled; /* clips: 1 where its rows were sampled local (its ranges filled) */
} local_sampling;

typedef struct bake_state {
    cb_palette *p;
    const cb_model *model;
    int32_t skin;
    const cb_bake_options *opt;
    const cb_clip_info *infos;
    /* Each worker samples a clip's rows into its own buffer and encodes them from there. u16
     * waits for the ranges of every clip, half for the position offsets: until then the values
     * wait in the texels, and what does not fit there in the stash (palette_stash_bytes per
     * bone and row: qpos's encoded quaternions, the rest of mat4's and affine's floats). */
    unsigned char *stash;
    uint32_t max_clip_frames;
    const double *radius;  /* bones: bind-space reach of the vertices each joint moves, or -1 (the skin's facts) */
    uint32_t *breaks;      /* clips: hemisphere breaks at the loop wrap */
    cb_error *errors;      /* 2 x clips: the first error of each clip, then of measuring its baked rows */
    uint32_t error_stride; /* measure every n-th row of a clip (and its last) */
    const cb_vertex_groups *groups; /* the skinned vertices as measuring bounds and skins them (facts') */
    const struct palette_skin_facts *facts; /* the skin's */
    double *clip_error;    /* clips: worst vertex error measured */
    double *clip_blend_error; /* clips: worst vertex error halfway between rows, as the runtime blends them */
    value_range *ranges;   /* clips: the values' ranges */
    double *encode_seconds; /* clips: time spent encoding each, when encoded as sampled */
    pose_cache *poses;      /* the only clip's exact matrices by time, kept across bakes (one thread); or NULL */
    pose_cache *const *clip_poses; /* or per clip: those its rate search sampled (palette_probe.clip_poses) */
    const cb_clip_info *analysis; /* the only clip analyzed before the bake, or NULL */
    cb_sampler *lent;       /* the caller's sampler, for the one worker of a probe's bake; or NULL */
    struct cb_pool *pool;   /* the threads every pass runs on, or NULL for the caller's alone */
    struct kept_rows *pending; /* a probe's rows (fitted or sampled), until its measurement says whether to keep them */
    pose_batch *batch;      /* the probe's, for its one worker (on st->lent); or NULL: each worker's own */
    struct clip_memo *memo; /* the run's analyses (palette_probe.memo), or NULL */
    double baked_worst;     /* palette_measure_rest's: the worst baked row every clip's job measured */
    const cb_clip_plan *plan; /* the bake's plan, or NULL: its timed clips, baked here at their cell rate, are measured
                               * once laid out (global_timed.c), not here */
    const local_sampling *local; /* a local bake's float bake (its rows local where sampled from lanes), or NULL */
} bake_state;

/* Whether clip c is timed in the bake's plan: baked at its cell rate, measured once laid out. */
static inline bool palette_clip_timed(const bake_state *st, uint32_t c) { return st->plan && st->plan[c].timed_rows; }

/* A clip's bounds while it is sampled, kept in double: rounding the extremes to float at the
 * end gives the floats that rounding every candidate would (rounding is monotonic). */
typedef struct extent {
    double lo[3], hi[3];
} extent;

/* Grows a clip's bounds by the sphere a joint's vertices can reach: a vertex weighted to joint
 * j lies within |A_j| * r_j of c = M_j b_j, so the union over joints bounds the skinned mesh. */
static inline void grow_bounds(extent *e, cb_vec3 c, double reach)
{
    /* Compares, not fmin: no NaN reaches here. Written out per axis, so that a local extent
     * stays in registers (a loop here is not unrolled at -O2 and keeps it in memory). */
    e->lo[0] = c.x - reach < e->lo[0] ? c.x - reach : e->lo[0];
    e->lo[1] = c.y - reach < e->lo[1] ? c.y - reach : e->lo[1];
    e->lo[2] = c.z - reach < e->lo[2] ? c.z - reach : e->lo[2];
    e->hi[0] = c.x + reach > e->hi[0] ? c.x + reach : e->hi[0];
    e->hi[1] = c.y + reach > e->hi[1] ? c.y + reach : e->hi[1];
    e->hi[2] = c.z + reach > e->hi[2] ? c.z + reach : e->hi[2];
}

/* The joint's position p = M b of a mat4/affine canonical row (the upper 3x4 by rows), axis r. */
static inline double row_position(const float *c, const float *b, int r)
{
    return (double)c[r * 4] * b[0] + (double)c[r * 4 + 1] * b[1] + (double)c[r * 4 + 2] * b[2] + c[r * 4 + 3];
}

/* palette_rows.c: `count` (at most CB_SAMPLE_BATCH) qpos rows of clip c from the joint
 * similarities of frames f, f + 1, ... (each joint's lanes as the sampler makes them), into rows
 * (row f's first); grows the clip's bounds and st->ranges[c]. A local bake's (st->local): the
 * rows then local (local_rows_from_lanes), the bounds still the global poses'. */
void palette_similarity_rows(bake_state *st, worker *w, uint32_t c, uint32_t f, uint32_t count, float *rows,
                             extent *clip_bounds);

/* palette_rows.c: row f of clip c from its joint matrices, any layout (qpos checks each is a
 * similarity), growing the clip's bounds and value range. */
cb_status palette_matrix_row(bake_state *st, worker *w, uint32_t c, uint32_t f, float *row, extent *bounds,
                             cb_error *err);
/* palette_rows.c: a search's rows reused by the bake after it. A probe makes (and fits) its
 * clip's rows into the block palette_keep_rows gives (NULL: no search to keep them with, or out
 * of memory; st->pending) and records its bounds and value range once they are made
 * (palette_kept_rows_done); once measured, rows within its goal (or measured without one) go
 * with the clip's poses (palette_settle_rows), replacing the last kept of their kind: a search's
 * last probe within the goal is the lowest such rate of its kind, its answer when that kind
 * wins. The bake after the search takes them for a clip of that kind framed alike
 * (palette_take_rows, NULL: none kept: the same times, root travel, layout), the same floats
 * making them gives, with its bounds into *bounds and its value range into st->ranges[c], so
 * neither its rows nor a fitted clip's mid-rows are sampled (and fitted) again. Sampled rows too
 * since speed43j: a similarity rig's rows (Fox) had no per-pose copy (palette_matrix_row's). */
float *palette_keep_rows(bake_state *st, uint32_t c, bool fitted);
void palette_kept_rows_done(bake_state *st, uint32_t c, const extent *bounds);
void palette_settle_rows(bake_state *st, double error);
const float *palette_take_rows(bake_state *st, uint32_t c, bool fitted, extent *bounds);
/* The same rows' errors bounded, for the bake after the search to skip the points that cannot
 * reach its worst. A probe's measurement notes each blend's bound and each baked row's cap (upper
 * bounds of their errors in the probe's palette) into the array palette_pending_point_bounds
 * gives for its pending rows (4 x frames: fraction sub of `parts` at (sub - 1) x frames + row
 * interval, baked row f at 3 x frames + f; INFINITY where not noted; NULL: nothing to note), and
 * the bake that took those rows (palette_take_rows) reads them back (palette_taken_point_bounds,
 * NULL: none for clip c measured in `parts`) with *shift, how much the palette's own u16 box can
 * move any vertex's error from the probe's (u16 qpos only). */
double *palette_pending_point_bounds(bake_state *st, uint32_t parts);
const double *palette_taken_point_bounds(const bake_state *st, uint32_t c, uint32_t parts, double *shift);
/* A probe's sampled rows kept by the probe before it, met or missed (palette_settle_rows keeps
 * the last missed ones too), framed as clip c: copied into rows (the whole clip), its bounds into
 * *bounds and its value range into st->ranges[c], where a fitted probe at the rate of a sampled
 * one starts (false: none; rows made). */
bool palette_take_sampled_for_fit(bake_state *st, uint32_t c, float *rows, extent *bounds);
/* palette_rows.c: the exact values halfway through each row interval of clip c (the clip framed
 * at twice the steps, odd frames), into mids; quaternions on the side of the row before. */
cb_status palette_mid_rows(bake_state *st, worker *w, uint32_t c, const float *rows, float *mids, cb_error *err);
/* palette_rows.c, for tests: the rows' hemispheres as bone_lanes settles them, sign[i] = -1 or
 * 1 for CB_SAMPLE_BATCH rows from each row's dot with the one before as stored (dot[0] unused)
 * and whether row 0 is flipped. */
void palette_row_signs(const double *dot, bool flip, float *sign);
/* palette_rows.c: the first `count` lanes of a bone's 8 values (v[k][i]: value k of row i) stored
 * as rows, to out + i * stride. */
void palette_store_rows(const float (*v)[CB_SAMPLE_BATCH], uint32_t count, float *out, size_t stride);
/* local_rows.c: a batch of clip c's rows (frames f .. f + count - 1) local, from its joints' lanes
 * as the sampler made them (w->local_lanes): each bone in its parent's frame, computed in double
 * (local_qpos_localize's arithmetic), its quaternion on the side of the row before's (a clip's
 * first row: w >= 0; w->prev holds the batch before's last), stored as floats into rows (row f's
 * first) and grown into the clip's ranges (st->local). */
void local_rows_from_lanes(bake_state *st, worker *w, uint32_t c, uint32_t f, uint32_t count, float *rows);

/* Encodes `count` rows of canonical floats into the texels of rows first, first + 1, ... */
void palette_encode_rows(cb_palette *p, const float *rows, uint32_t first, uint32_t count);
/* qpos/u16 and qpos/half in place: the quaternions of `count` rows encoded into `stash`, and
 * the positions and scales staged in their texels as floats (palette_stage_qpos); once every
 * range and offset is known, those encoded in place and the quaternions copied back
 * (palette_finish_qpos). */
void palette_stage_qpos(cb_palette *p, const float *rows, unsigned char *stash, uint32_t first, uint32_t count);
void palette_finish_qpos(cb_palette *p, const unsigned char *stash, uint32_t first, uint32_t count);
/* mat4 and affine in place, for u16 and half: `count` rows' canonical floats staged in their
 * texels and the stash (palette_stage_rows), and row r's gathered back, to be encoded
 * (palette_gather_row). palette_stash_bytes: the stash's bytes per bone and row (qpos too). */
void palette_stage_rows(cb_palette *p, const float *rows, unsigned char *stash, uint32_t first, uint32_t count);
void palette_gather_row(const cb_palette *p, const unsigned char *stash, uint32_t r, float *row);
uint32_t palette_stash_bytes(const cb_palette *p);
/* Relative half palettes: each bone's position offset, the middle of its positions' range,
 * from the staged values. False: out of memory. */
bool palette_position_offsets(cb_palette *p, const unsigned char *stash);
/* Sets p->bounds_min/max and linear_range from every clip's range. */
void palette_merge_ranges(cb_palette *p, const value_range *clips);

/* palette_plan.c: the clips' frames and rows (p->clips, *infos_out: st->analysis framed, or
 * each clip analyzed), the texture's geometry,
 * each joint's bind-pose position, and the texels no row covers set to zero. */
cb_status palette_frame_clips(bake_state *st, cb_sampler *sampler, const cb_clip_plan *plan, uint32_t count,
                              cb_clip_info **infos_out, cb_error *err);
/* palette_plan.c: a rate search's analysis of a clip (at `fps`, with the plan's loop override
 * `loop`) kept with the clip's poses, for the bake after the search: it frames the analysis at
 * its own rate instead of analyzing the clip again (palette_frame_clips), where that gives what
 * analyzing it gives. Out of memory: not kept. */
void palette_keep_analysis(pose_cache *poses, const cb_clip_info *analysis, double fps, int loop);
/* palette_plan.c: whether `poses` keep an analysis of `animation` with loop override `loop` that
 * stands in for analyzing it at fps; palette_take_kept_analysis: that analysis into *out as
 * cb_clip_analyze (same sampler model and skin) gives it at fps, the clip's loop set on the
 * sampler as analyzing it sets it (false: analyze it). */
bool palette_kept_analysis(const pose_cache *poses, int32_t animation, int loop, double fps, const cb_limits *limits);
bool palette_take_kept_analysis(const pose_cache *poses, cb_sampler *sampler, int32_t animation, int loop, double fps,
                                const cb_limits *limits, cb_clip_info *out);
/* palette_plan.c: the analysis kept with `poses` as it was kept (any rate, any loop override), or
 * NULL (none, or poses NULL). */
const cb_clip_info *palette_kept_analysis_info(const pose_cache *poses);
/* The analysis a rate search kept with `poses` (if any) kept in a bake run's memo (clip_memo_keep,
 * with the rate and loop override it was made with): it stands in for the run's analyses of the
 * clip (the speed reference's, at 30 fps, analyzed each clip again: Cow 19.5 M instructions). */
void palette_memo_keep_search(struct clip_memo *memo, const cb_sampler *sampler, const pose_cache *poses,
                              const cb_limits *limits);
struct search_keep; /* below */
/* rate_search.c: an analysis of clip i made before the search (at fps, loop override loop) kept
 * for it: keep->poses[i] made where it is NULL (a search's pose cache), the analysis attached. */
void palette_seed_analysis(struct search_keep *keep, uint32_t i, const cb_sampler *sampler, const cb_clip_info *analysis,
                           double fps, int loop);
cb_status palette_plan_texture(cb_palette *p, uint32_t max_size, const char *source, cb_error *err);
void palette_bind_positions(const cb_skin *skin, float *bind);
void palette_zero_padding(cb_palette *p);

/* Every bone's values of one row of p->texels, 16 doubles apart, as cb_palette_decode_values
 * gives them. */
void palette_decode_row_values(const cb_palette *p, uint32_t row, double *values);
/* cb_palette_blend from two rows' decoded values of a bone. */
void palette_blend_values(const cb_palette *p, uint32_t bone, const double a[16], const double b[16], double fr,
                          double out[16]);

/* The measurement's jobs: two a clip, its blends and its baked rows, measured apart (st->errors:
 * the clip's, then the rows' after every clip's); one a clip with an error goal, where the
 * rows only count above the blends. */
uint32_t palette_measure_jobs(const bake_state *st);
/* palette.c: the measuring budget (palette.h): 1 (every row measured) up to CB_ERROR_ROWS rows or CB_ERROR_BUDGET
 * vertex-rows, or with measure_all; past both, every how many rows (or batches of intervals) an even subset measures,
 * global and local rows alike. */
uint32_t palette_error_stride(uint32_t rows, uint32_t vertices, bool measure_all);
/* After every palette_measure_job: the baked rows a job left out as within its clip's blends
 * (their probe's caps) that might still exceed every baked row measured (the palette's
 * max_error), measured by palette_measure_rest_job for each clip; returns whether any is left. */
bool palette_measure_rest(bake_state *st);
void palette_measure_rest_job(bake_state *st, worker *w, uint32_t c);
/* Measurement job k: the worst vertex errors of its clip at its rows and/or between them
 * (st->clip_error, st->clip_blend_error). */
void palette_measure_job(bake_state *st, worker *w, uint32_t k);
/* A worker's measurement scratch, kept from job to job (a clip's is about 1.4 MB for 200 bones,
 * fresh memory each time where it was allocated per job). */
void palette_measure_scratch_free(struct measure_scratch *s);
/* palette_rows.c: a search's probe of a rig of similarities measures each baked row against the
 * exact pose its row was made from, which the sampler made moments before: the lanes a probe's
 * rows were sampled from are kept (in its search thread's pose_batch, up to a few MB), and its
 * baked rows' measurement (and a fitted probe's after it, whose rows start from them) reads them
 * instead of sampling them again. The same values, handed to the same code in the same order. */
void palette_row_lanes_free(struct row_lanes *l);
/* Where the lanes of clip c's rows f .. f + CB_SAMPLE_BATCH - 1 go as they are sampled (NULL: not kept). */
double *palette_row_lanes_keep(bake_state *st, uint32_t c, uint32_t f);
/* Those rows sampled: count of them kept from `at` (palette_row_lanes_keep's). */
void palette_row_lanes_kept(bake_state *st, uint32_t f, uint32_t count, const double *at);
/* The kept lanes of clip c's rows `frames` (count of them), or NULL: joint j's 8 x CB_SAMPLE_BATCH
 * values at j * 8 * CB_SAMPLE_BATCH, as the sampler handed them to the rows. */
const double *palette_row_lanes_find(const bake_state *st, uint32_t c, const uint32_t *frames, uint32_t count);

/* What a bake needs of the skin alone, whatever the clips and the rate: its joints' bind
 * positions, how far their vertices reach, the vertices grouped for measuring and the rest
 * pose's height. A search that bakes one skin at many rates (runtime.c) settles them once
 * instead of once a bake (Cow --fps auto: 60 probe bakes). */
typedef struct palette_skin_facts {
    float *bind_positions;   /* bones * 3: each joint's bind-pose position (palette_bind_positions) */
    double *reach;           /* bones: bind-space distance to the farthest vertex the joint moves; -1: none */
    bool skinned;            /* some vertex is skinned: there is an error to measure */
    cb_vertex_groups groups; /* built when skinned */
    double *group_reach;     /* bones: the largest reach a group gives the joint (0: in none) */
    double weight_sum;       /* the largest of the groups' weight sums */
    double height;           /* cb_skin_rest_bounds's */
} palette_skin_facts;

/* palette_plan.c: the facts of the sampler's skin; palette_skin_facts_free frees them (also
 * after a failure). */
cb_status palette_skin_facts_build(cb_sampler *sampler, palette_skin_facts *out, cb_error *err);
void palette_skin_facts_free(palette_skin_facts *f);

/* palette_rows.c: clip c's joint matrices at `frame` of framing (cb_clip_frame_matrices with the bake's root
 * motion): from st->poses or the clip's st->clip_poses where they keep them, else sampled into
 * w->mats (and kept). Valid until the
 * worker's next call. extra (optional): the kept pose's extra doubles, NULL where not kept. */
const double *palette_frame_matrices(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, uint32_t frame,
                                     double **extra);
/* pose_batch.c: clip c's poses at `frames` (1..CB_SAMPLE_BATCH, increasing) of framing, those its
 * pose cache (st->poses or the clip's st->clip_poses) lacks sampled together and kept, the
 * bits palette_frame_matrices samples them with; nothing where no cache keeps them. */
void palette_prefetch_poses(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, const uint32_t *frames,
                            uint32_t count);
/* pose_batch.c: clip c's poses at `frames` (1..CB_SAMPLE_BATCH, increasing) of framing into
 * mats[i] without keeping them: the pose its cache has, else sampled into room + i x bones x 16
 * (those missing together where there are enough, as palette_prefetch_poses samples them: the
 * same bits). For poses that no later probe is likely to read: a fitted probe's quarter points
 * (palette_error.c). */
void palette_unkept_poses(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, const uint32_t *frames,
                          uint32_t count, double *room, const double **mats);
/* palette_rows.c: a pose cache for a search's probes (palette_probe.poses): each pose keeps what qpos derives
 * from its matrices alone too (a probe's rows are rows of the others); its blocks drawn from arena (NULL: its own). */
pose_cache *palette_probe_poses(pose_arena *arena, uint32_t bones, size_t max_bytes);
/* palette_rows.c: palette_qpos_similarity_pose of a pose kept in such a cache (mats: its matrices,
 * as pose_cache_find or pose_cache_add gave them), derived once and kept with it, where the
 * bake's rows take it too; NULL, nothing kept, where a joint is no similarity. */
const double *palette_kept_qpos(const double *mats, uint32_t bones);
/* qpos_lanes.c: qpos_similarity's quaternion and scale of every joint of a pose (mats: 16 doubles a
 * joint) into out (5 a joint), four joints at a time, the same bits; false, with out partly
 * written, where a joint is no similarity (qpos_similarity then says which). */
bool palette_qpos_similarity_pose(const double *mats, uint32_t bones, double *out);

/* What a search that bakes one clip at many rates (runtime.c) keeps across its bakes. */
typedef struct palette_probe {
    pose_cache *poses;            /* the clip's exact matrices by time, or NULL */
    const cb_clip_info *analysis; /* the clip analyzed once (cb_clip_analyze at any rate, the plan's loop and
                                   * limits, on the bake's sampler), or NULL */
    pose_cache *const *clip_poses; /* a bake of the plan's every clip after their rates were searched: per clip
                                    * the caches its search kept (entries may be NULL), or NULL: for global
                                    * rows their attachments, the poses released (search_keep_settle); a
                                    * clip's measurement then stays on one worker. */
    pose_batch *batch;             /* the search thread's batches of poses (on the probe's sampler), or NULL */
    struct clip_memo *memo;        /* the bake run's clip analyses (clip_memo.h): the clips are framed from those
                                    * and their own analyses kept there; or NULL */
} palette_probe;

struct search_keep;
/* Work a job runs beside its global rows' rate search (rate_search.c), reading the searches of
 * the clips reads[i] marks (NULL: none): the first of the search's threads to find all of those
 * over runs it, once, while the others go on with the clips left - the time a thread otherwise
 * waits for the longest clip, and no clip's analysis made twice. keep->poses[i] of a clip it
 * reads is not changed again before the search returns. The keep owns it (search_keep_free calls
 * release). A search that never takes it (local rows) leaves `taken` false, and its caller does
 * the work itself. */
typedef struct search_beside {
    void (*run)(struct search_beside *self, const struct search_keep *keep);
    void (*release)(struct search_beside *self);
    const bool *reads; /* per clip of the keep */
    atomic_bool taken;
} search_beside;

/* What a bake job's rate searches keep for the searches after them and the bake: each clip's
 * pose cache (poses[i], NULL: none) and the skin's facts, settled by the first search that
 * needs them for `model` and `skin` (a job's searches and its bake all measure that skin: its
 * facts were built once for the searches and once again for the bake, 1.8 M of Fox's 62.1 M
 * instructions; speed43j). search_keep_create: n clips, nothing kept yet (NULL: out of
 * memory); search_keep_free frees the caches, the facts and the work beside. */
typedef struct search_keep {
    const cb_model *model;
    int32_t skin;
    bool has_facts;
    palette_skin_facts facts;
    bool local_rates; /* the rates were chosen for local rows (local_rate_search.c), not for global ones */
    pose_arena *arena; /* what poses' blocks come from (NULL: each cache its own), freed after them */
    search_beside *beside; /* run beside the search, or NULL */
    uint32_t count;
    pose_cache *poses[];
} search_keep;
search_keep *search_keep_create(uint32_t n);
void search_keep_free(search_keep *keep);
/* What a rate search (rate_search.c, local_rate_search.c) samples a clip's poses into: one clip's
 * cache holds at most SEARCH_CLIP_POSE_BYTES (Cow's longest clip, 6 s of 42 joints, keeps 912
 * poses: 6.4 MB with their qpos derivations; 32 MB is 950 poses of 200 joints; past it, probes
 * sample the times it has no room for as without one), and the caches kept for the bake all
 * together at most SEARCH_KEPT_POSE_BYTES (Cow's twelve clips keep about 50 MB, and spare its bake
 * 150 M of its 750 M instructions). search_keep_settle adds a finished clip's cache to
 * *kept_bytes and frees it (NULL) past that budget: the bake samples that clip again, the same bits.
 * With release_poses (a search for global rows, rate_search.c) it hands the cache's poses back to
 * the arena for the next clip's search, keeping its attachments (the probes' rows, bounds,
 * analysis, worst points; pose_cache_release_poses): the bake after it takes the probes' rows
 * and reads few poses (Cow: 101 of the 3,300 kept; Husky 95), and sampling those again costs
 * less than the fresh pages the kept poses took (the kernel clears each before its first use:
 * Cow's default bake 17 huge pages, 5 with the poses released). A local-rows bake reads most of
 * its search's poses: kept. */
#define SEARCH_CLIP_POSE_BYTES ((size_t)32 << 20)
#define SEARCH_KEPT_POSE_BYTES ((size_t)128 << 20)
void search_keep_settle(pose_cache **cache, uint32_t bones, atomic_size_t *kept_bytes, bool release_poses);
/* palette_plan.c: the facts of the sampler's skin: keep's, built there the first time (keep
 * NULL, or kept for another model or skin: built into *own, which the caller frees with
 * palette_skin_facts_free; *own is zeroed either way); NULL on failure (err set). */
const palette_skin_facts *search_keep_facts(search_keep *keep, cb_sampler *sampler, palette_skin_facts *own,
                                            cb_error *err);
/* keep's facts where they were built for the sampler's model and skin, else NULL (the bake
 * settles its own). */
const palette_skin_facts *search_kept_facts(const search_keep *keep, const cb_sampler *sampler);

/* cb_choose_rates keeping what each clip's search sampled: keep->poses[i] (NULL: none yet) gets
 * clip i's pose cache, made or added to, while all the caches together stay under a budget (past
 * it a clip's is freed and left NULL), and keep the skin's facts (search_keep_facts); NULL keep:
 * nothing kept. The caller frees them (search_keep_free).
 * needed_later[i] (NULL: none): the caller searches clip i on past its max_fps where it misses
 * its goal there, so its fps_needed is not searched for (left 0): the caller's search finds it
 * from past that search's cap (bake_transients.c). */
cb_status palette_choose_rates(cb_sampler *sampler, const cb_bake_options *options, cb_clip_plan *plan, uint32_t count,
                               const cb_rate_goal *goals, cb_rate_choice *out, search_keep *keep,
                               const bool *needed_later, cb_error *err);

/* cb_palette_bake with the skin's facts settled by the caller (palette_skin_facts_build, same
 * sampler model and skin; NULL: settled here), and a probe's aids (or NULL), used when the bake
 * is of the plan's one clip on one thread (opt->threads <= 1): its one worker then samples on
 * `sampler` itself, not on a sampler made for each pass. */
cb_status palette_bake_with_facts(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                                  uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                                  cb_palette *p, cb_error *err);
/* local_rows.c: a bake with opt->bone_space local (palette_bake_with_facts sends it there): the
 * clips baked global in float and sampled, converted to local rows in opt's precision, their
 * errors measured composed. CB_ERR_SETTINGS for a layout or precision local rows cannot take; a
 * rig qpos cannot hold falls back to affine and stays global (p->bone_space says which). */
cb_status palette_bake_local(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                             uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                             cb_palette *p, cb_error *err);
/* palette.c: palette_bake_local's float bake of global qpos rows (the affine fallback included),
 * its clips sampled from lanes sampled local into `local` (local_sampling). */
cb_status palette_bake_sampled_local(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                                     uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                                     const local_sampling *local, cb_palette *p, cb_error *err);
/* local_rows.c: the clips of p (every one, or its timed ones alone) measured composed as the runtime
 * plays them (local_palette_errors: at every row, and the quarter points between every two, through a
 * timed clip's map; global qpos rows compose nothing), shared out clip by clip over up to `threads`
 * threads: each one's visible_error, and p's max_error and visible_error raised to them (and, every clip
 * measured, error_rows_measured raised by the rows measured). probe: the search's poses, or NULL. stride > 1:
 * an even subset of each clip's intervals (the measuring budget, palette.h). */
cb_status palette_measure_composed(cb_sampler *s, const cb_clip_plan *plan, const palette_skin_facts *facts,
                                   const palette_probe *probe, uint32_t threads, bool timed_only, uint32_t stride,
                                   cb_palette *p, cb_error *err);
/* local_rows.c: each joint's nearest ancestor joint in the skin (-1: a root), the .pal bone table's parent. */
void palette_local_parents(const cb_model *m, const cb_skin *skin, int32_t *parents);
/* local_rows.c: a local palette's bone composed down its chain, as qpos values (q, position, scale: 8
 * of the 16), its rows r0 and r1 blended by fr bone by bone first (r0 == r1, fr 0: the row). */
void palette_local_composed(const cb_palette *p, const void *texels, uint32_t r0, uint32_t r1, double fr, uint32_t bone,
                            double v[16]);
/* Two rows and the second's weight, as cb_runtime_frame gives them. */
typedef struct palette_frame {
    uint32_t row0, row1;
    double fr;
} palette_frame;
/* local_rows.c: every bone of a local palette composed (as palette_local_composed, 16 doubles a
 * bone: matrices), each bone's rows blended once; with `from`, a cross-fade: each bone's blended
 * local values faded from from's by fade before composing. False: out of memory (nothing written). */
bool palette_local_matrices(const cb_palette *p, const void *texels, const palette_frame *to,
                            const palette_frame *from, double fade, double *out);
/* palette_error.c: bind-space distance from each joint's bind position (bind: 3 floats a
 * joint) to the farthest vertex it moves; -1 for joints that move none. False when no vertex
 * is skinned. */
bool palette_joint_reach(const float *bind, uint32_t bones, const cb_model *m, int32_t skin, double *radius);

#endif
