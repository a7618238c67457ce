/* runtime.h - what a game's vertex shader computes from a palette, on the CPU: the frame
 * position of an instance at a time, the blend of two adjacent rows, the skinned mesh. The
 * shipped shaders (runtimes/glsl/) do exactly this; verification compares it with exact
 * skinning from the glTF. */
#ifndef CB_RUNTIME_H
#define CB_RUNTIME_H

#include "export.h"

#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The four per-instance numbers. A negative frame_count marks a one-shot of -frame_count rows:
 * it clamps at its ends instead of wrapping. A negative first_row marks a clip whose rows are
 * held, not blended (cb_palette_clip.step), its first row -first_row - 1 (cb_instance_of). A
 * negative rate marks a timed clip (cb_palette_clip.timed): frame_count counts its cells, -rate
 * is cells per second, and its map says which rows to blend (cb_runtime_frame_in). */
typedef struct cb_instance {
    double first_row, frame_count, rate, phase;
} cb_instance;

/* A clip's numbers, played from its start at its own rate. */
CROWDBAKE_API cb_instance cb_instance_of(const cb_palette_clip *clip);

/* fpos = time * rate + phase * frames, wrapped (loops) or clamped (one-shots) to the clip; the
 * two rows blended and the weight of the second. */
CROWDBAKE_API void cb_runtime_frame(const cb_instance *in, double time, uint32_t *row0, uint32_t *row1, double *fr);
/* The same for any instance, a timed one's (rate < 0) through its map in the palette's texels
 * (docs/pal-format.md "Timed rows": what every runtime's frame function does). */
CROWDBAKE_API void cb_runtime_frame_in(const cb_palette *p, const void *texels, const cb_instance *in, double time,
                                       uint32_t *row0, uint32_t *row1, double *fr);

/* The cb_bind_positions texture the shipped shaders read: RGBA32F, bone_count texels wide. Row 0 xyz the
 * bind positions, row 1 xyz the position offsets (CB_POSITIONS_RELATIVE); a local palette's (.pal version
 * 6, CB_LOCAL_ROWS) also row 2 x the parent (-1 a root), row 3 (pos_min, scale_max) and row 4 (pos_max, 0)
 * from the bone range table. Returns its rows (2 or 5); fills `rgba` (bone_count x rows x 4 floats) unless
 * it is NULL. */
CROWDBAKE_API uint32_t cb_bind_texels(const cb_palette *p, float *rgba);

/* The bone transforms at `time` (16 doubles per bone): the two rows' values blended - matrices
 * term by term, qpos quaternions by normalized lerp after a hemisphere flip - then as matrices. */
CROWDBAKE_API void cb_runtime_matrices(const cb_palette *p, const void *texels, const cb_instance *in, double time,
                                       double *out);

/* A cross-fade from one instance's clip to another's, fade 0 (from) to 1 (to), as the shaders fade:
 * global rows' bone transforms mixed term by term (the same as mixing the skinned positions); a
 * local palette's (.pal version 6) bones' blended local values faded, then composed. False: out of
 * memory (out untouched). */
CROWDBAKE_API bool cb_runtime_matrices_crossfade(const cb_palette *p, const void *texels, const cb_instance *from,
                                                 const cb_instance *to, double fade, double time, double *out);

/* Verification of one clip: the runtime's skinned mesh against exact skinning from the model. */
typedef struct cb_clip_error {
    double quant_max, quant_mean;   /* at the baked rows: the encoding's error */
    double interp_max, interp_mean; /* between them (mid-frames and random times): blending's error */
    uint64_t worst_vertex;
    double worst_time;              /* clip time of the worst error */
} cb_clip_error;

/* `animation` is the model's clip baked as palette clip `clip`; random_times are drawn from a
 * fixed-seed generator, so results repeat. */
CROWDBAKE_API cb_status cb_verify_clip(cb_sampler *sampler, const cb_palette *p, const void *texels, uint32_t clip,
                                       int32_t animation, uint32_t random_times, cb_clip_error *out, cb_error *err);

/* Error-driven frame rate: the lowest of the candidate rates (common rates from 2 fps, and the
 * clip's key rate with its multiples and fractions, up to max_fps) at which the clip, baked
 * alone with `options` and the clip's own loop setting (its rows fitted where options->fit or
 * clip->fit says), has a visible error (cb_palette's: the encoding, and the blend between rows)
 * within max_error (model units). Binary search: the error falls as the rate rises. Returns
 * max_fps (and *met = false) when none does; *error is the error at the rate returned. */
CROWDBAKE_API double cb_choose_clip_fps(cb_sampler *sampler, const cb_bake_options *options, const cb_clip_plan *clip,
                                        double max_error, double max_fps, bool *met, double *error, cb_error *err);

/* The highest rate an error-bounded clip bakes at unless its goal says otherwise: every clip of
 * Cow, Fox and the samples (in place) meets 1 mm/m under it (Cow's Attack_Kick and Fox's Run
 * need 120 fps, fitted). */
#define CB_AUTO_MAX_FPS 120.0

/* How far a bake's rate search goes on for a clip over the default max_error at the default
 * max_fps, when neither max_error nor max_fps was stated: fast transients (the robot's punch
 * reaches 2.8 mm/m at 120 fps, 0.91 at 216 on its 24 fps key grid). Only that clip's rate rises;
 * a stated max_fps caps it as before. */
#define CB_TRANSIENT_MAX_FPS 240.0

/* Which rows an error-bounded clip may have. */
typedef enum cb_rows {
    CB_ROWS_BEST = 0, /* fitted or sampled, whichever meets the goal with fewer rows (ties: sampled) */
    CB_ROWS_SAMPLED,  /* the exact poses */
    CB_ROWS_FITTED    /* fitted to the runtime's linear blend (cb_bake_options.fit) */
} cb_rows;

/* fps = "auto" for a plan: per clip, the visible error to stay under (mm per metre of model
 * height; 0: keep the plan's fps), the highest rate allowed (2..CB_FPS_LIMIT; a bake's default
 * is CB_AUTO_MAX_FPS) and the rows allowed (options->fit: fitted, whatever this says). */
typedef struct cb_rate_goal {
    double max_error_mm, max_fps;
    cb_rows rows;
} cb_rate_goal;
typedef struct cb_rate_choice {
    bool met;               /* the error is within the goal */
    double error, error_mm; /* at the chosen rate: model units, and mm per metre of height */
    bool fitted;            /* the rows chosen: fitted (else sampled) */
    double other_fps;       /* 0: the search stops at the fewest rows (fitted rows chosen: sampled rows miss at
                             * that rate; sampled rows chosen: fitted rows miss under it). Kept for callers. */
    double fps_needed;      /* not met: the lowest rate up to CB_FPS_LIMIT that meets it (0: none does) */
    /* Timed rows (cb_bake_options.timed_rows): weighed where its keys lie on a grid, taken (the plan's timed_rows)
     * where they cost fewer bytes or were asked for (local rows). */
    bool timed_weighed;     /* rows on its keys were measured and within its budget */
    uint32_t timed_rows, timed_map_rows, timed_cells; /* what they take: rows, map rows, cells of the map */
    double timed_cell_rate;
    uint32_t uniform_rows;  /* what the uniform rate chosen (uniform_fps) takes */
    double uniform_fps;
} cb_rate_choice;
/* Sets plan[i].fps and plan[i].fit for every clip with a goal: per clip, the lowest rate within
 * the goal, sampled rows tried before fitted rows at each rate (a tie goes to sampled rows, the
 * exact poses), walked from the key rate (rate_search.c). Rates the probes so far predict far
 * over the goal are not baked.
 * out (optional) says what each choice reached. */
CROWDBAKE_API cb_status cb_choose_rates(cb_sampler *sampler, const cb_bake_options *options, cb_clip_plan *plan,
                                        uint32_t count, const cb_rate_goal *goals, cb_rate_choice *out, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
