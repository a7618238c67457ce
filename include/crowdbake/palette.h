/* palette.h - bone-matrix palettes: the baked rows of every clip of one skin, encoded in one
 * of three layouts and three precisions, wrapped to fit a texture-size limit.
 *
 * Texel (x, y) of the texture holds RGBA. Baked row r lives in block b = r / height at
 * y = r % height; bone j's texel k of that row is at x = b * row_texels + j * texels_per_bone + k.
 */
#ifndef CB_PALETTE_H
#define CB_PALETTE_H

#include "export.h"

#include "core.h"
#include "row_travel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cb_layout { CB_LAYOUT_MAT4 = 0, CB_LAYOUT_AFFINE = 1, CB_LAYOUT_QPOS = 2 } cb_layout;
typedef enum cb_precision { CB_PRECISION_FLOAT = 0, CB_PRECISION_HALF = 1, CB_PRECISION_U16 = 2 } cb_precision;
/* What a row holds for each bone: its global skinning transform (every file before version 6),
 * or its transform in its parent's frame, which the runtime blends bone by bone and then composes
 * down the skeleton (.pal version 6, header flag bit 5; qpos with u16 or float only). */
typedef enum cb_bone_space { CB_BONE_SPACE_GLOBAL = 0, CB_BONE_SPACE_LOCAL = 1 } cb_bone_space;

CROWDBAKE_API const char *cb_layout_name(cb_layout layout);
CROWDBAKE_API const char *cb_precision_name(cb_precision precision);
CROWDBAKE_API const char *cb_bone_space_name(cb_bone_space bone_space); /* "global", "local" */
/* Whether rows of this layout and precision can hold local rows: qpos with u16 or float (half's
 * 2^-11 would compound down each chain). */
CROWDBAKE_API bool cb_holds_local_rows(cb_layout layout, cb_precision precision);
CROWDBAKE_API uint32_t cb_layout_texels_per_bone(cb_layout layout);
CROWDBAKE_API uint32_t cb_precision_texel_bytes(cb_precision precision); /* 16, 8, 8 */

/* Where a bake's texels go: memory the caller provides (say, the output file's payload, mapped,
 * so that the texels are encoded where they are written). acquire(ctx, p) gets the planned
 * palette (layout, precision, geometry, clips and texel_bytes set; no texel written yet) and
 * returns p->texel_bytes of zeroed, writable memory that stays valid until the caller releases it,
 * or NULL: the bake then allocates its own. A bake may call it more than once (qpos falling back
 * to affine): the latest answer is the one used. */
struct cb_palette;
typedef struct cb_texel_memory {
    void *(*acquire)(void *ctx, const struct cb_palette *p);
    void *ctx;
} cb_texel_memory;

/* Whether a rate search may place a clip's rows on its key times (docs/pal-format.md "Timed rows"). */
typedef enum cb_timed_rows { CB_TIMED_ROWS_AUTO = 0, CB_TIMED_ROWS_ON = 1, CB_TIMED_ROWS_OFF = 2 } cb_timed_rows;
CROWDBAKE_API const char *cb_timed_rows_name(cb_timed_rows t); /* "auto", "on", "off" */

typedef struct cb_bake_options {
    double fps;
    cb_layout layout;
    cb_precision precision;
    uint32_t max_texture_size;
    cb_root_motion root_motion;
    cb_limits limits;
    uint32_t threads; /* clips sampled in parallel; the output does not depend on it */
    bool affine_fallback; /* qpos was not chosen explicitly: bake affine when qpos cannot hold the rig */
    double error_goal;    /* > 0: only the visible error is measured, and only as far as the goal needs (model
                           * units): exact when within it, a lower bound above it; max_error is then a lower
                           * bound and model_height 0. For searches that ask "within the goal?". 0: all exact. */
    bool fit;             /* every clip's rows fitted to the linear blend (src/fit.c), not sampled: half the error
                           * between rows (cb_clip_plan.fit: one clip's) */
    cb_texel_memory texel_memory; /* {NULL}: the bake allocates the texels */
    bool measure_all;     /* the errors measured at every row and between every two, however many (else past
                           * CB_ERROR_ROWS and CB_ERROR_BUDGET, at an even subset of them) */
    cb_bone_space bone_space; /* local: rows in each bone's parent frame (qpos, u16 or float; src/core/local_rows.c),
                               * sampled (never fitted: a fit is to the global blend), errors measured composed */
    cb_timed_rows timed_rows; /* an auto rate's rows on its clip's key times (timed rows, .pal version 7). Local rows:
                               * where that costs fewer bytes (auto), wherever its keys allow (on), or never (off);
                               * global qpos rows: where that costs fewer bytes (on), or never (auto, off) */
} cb_bake_options;

/* A bake measures its errors at every row while it has at most CB_ERROR_ROWS rows or at most
 * CB_ERROR_BUDGET vertex-rows (rows x skinned vertices): measuring takes 12-16 us a row on the
 * shared rigs, 2.2-3.1 ns a vertex-row. Past both, an even subset of about CB_ERROR_BUDGET
 * vertex-rows, each clip's last always (cb_palette.error_rows_measured), unless measure_all. A
 * subset finds the encoding error to within a percent, but it can miss the one fast interval
 * where the blend errs most: see docs/speed.md. */
#define CB_ERROR_ROWS 1024u
#define CB_ERROR_BUDGET (4u << 20)

CROWDBAKE_API cb_bake_options cb_default_bake_options(void);

typedef struct cb_palette_clip {
    const char *name;        /* owned by the model the palette was baked from */
    uint32_t first_row, frames;
    double fps, duration, start;
    bool loops;
    float root_velocity[3];
    float bounds_min[3], bounds_max[3]; /* encloses the skinned mesh over the clip (conservative), model units */
    double ground_speed;     /* the root's horizontal travel over the clip per second (cb_clip_info.ground_speed) */
    bool fitted;             /* its rows fitted to the runtime's linear blend, not sampled (clip flag bit 1) */
    double visible_error;    /* the clip's visible error (cb_palette.visible_error's, for this clip alone), model units */
    bool step;               /* its rows are held, not blended: the runtime shows the row at or before the time (clip
                              * flag bit 2, .pal version 4) */
    cb_row_travel travel;    /* its per-row travel offset, applied or not and why (row_travel.h; cb_bake_job_run fills it) */
    bool timed;              /* its rows lie on cells of a grid and the runtime reads which two it blends from the map
                              * rows before first_row (clip flag bit 3, .pal version 7; docs/pal-format.md "Timed rows") */
    uint32_t cells;          /* timed: the grid's steps over the clip (a loop wraps at cell `cells`) */
    uint32_t map_rows;       /* timed: the map's rows, just before first_row (cb_timed_map_rows) */
    double cell_rate;        /* timed: cells per second of clip time */
} cb_palette_clip;

typedef struct cb_palette {
    cb_layout layout;
    cb_precision precision;
    bool fitted;                    /* every clip's rows fitted to the runtime's linear blend, not sampled (header flag
                                     * bit 3); a palette may mix fitted and sampled clips (cb_palette_clip.fitted) */
    uint32_t bone_count, texels_per_bone, row_texels;
    uint32_t rows;                  /* baked frames over all clips */
    uint32_t width, height, blocks; /* texture size: blocks of `height` rows side by side */
    double fps;
    uint32_t clip_count;
    cb_palette_clip *clips;
    float *bind_positions;          /* 3 per bone: the joints' bind-pose positions (qpos pivots) */
    bool positions_relative;        /* qpos/half: the position texel holds p - o, the joint's position less its bone's
                                     * offset, which stays small (and precise in half floats) far from the origin */
    float *position_offsets;        /* 3 per bone: o, the centre of the bone's positions over every row (.pal version
                                     * 3; version 2 files used the bind position); zeros unless positions_relative */
    float bounds_min[3], bounds_max[3]; /* u16: the box positions are quantized in */
    float linear_range;             /* u16: |3x3 terms| (mat4, affine) or scale (qpos) stay below this */
    uint32_t quat_hemisphere_breaks; /* loops whose rotation ends on -q of its start (a full turn) */
    void *texels;                   /* width * height * texel bytes, little-endian */
    size_t texel_bytes;
    bool texels_borrowed;           /* texels came from options.texel_memory: cb_palette_free leaves them */
    double model_height;            /* rest-pose height of the skinned meshes */
    double max_error;               /* encoding error: worst vertex displacement vs exact skinning at the baked rows, model units */
    double visible_error;           /* what a player sees: the worst of max_error and the error of the runtime's blend of
                                     * two adjacent rows halfway between them (every row interval, wraps included) */
    uint32_t error_rows_measured;   /* rows the error was measured at: all, or an even subset */
    char fallback_note[512];        /* why qpos fell back to affine, or empty */
    double seconds_sample, seconds_encode, seconds_measure;
    float *row_travel;              /* rows floats: each row's travel offset along its clip's heading (.pal version 5),
                                     * 0 in clips without it; NULL when no clip has it (row_travel.h) */
    cb_bone_space bone_space;       /* local: row r of bone j holds L_j = M_parent^-1 M_j as qpos (.pal version 6) */
    int32_t *parents;               /* local: per bone, the nearest ancestor joint (the .pal bone table's), -1 a root */
    float *bone_ranges;             /* local: per bone 8 floats as the file's range table: pos_min[3], scale_max,
                                     * pos_max[3], 0 (u16 decodes with them) */
} cb_palette;

/* Which clips a palette holds, in row order. */
typedef struct cb_clip_plan {
    int32_t animation;  /* index into the model's animations */
    const char *name;   /* the name in the palette (a rename), or NULL for the clip's own */
    int loop;           /* -1 decide from the poses, 0 one-shot, 1 loop */
    double fps;         /* 0: the bake's fps */
    bool fit;           /* its rows fitted to the runtime's linear blend (as cb_bake_options.fit does for every clip) */
    bool step;          /* its rows are held, not blended (.pal clip flag bit 2): a STEP-keyed clip at the rate of its
                         * key grid (cb_clip_step_grid), exact */
    /* Timed rows (the rate search's choice, docs/pal-format.md "Timed rows"): fps is then the cell rate, and the clip
     * keeps only the rows on row_cells (timed_rows of them, increasing from 0; a one-shot's last at its last cell).
     * row_cells is owned by whoever chose it: cb_bake_job_free frees its plan's (cb_clip_plan_release). */
    uint32_t timed_rows;  /* 0: uniform rows */
    uint32_t *row_cells;
} cb_clip_plan;

/* Frees a plan entry's timed rows (row_cells), leaving it uniform. */
CROWDBAKE_API void cb_clip_plan_release(cb_clip_plan *plan);

/* Whether animation `animation` is keyed with STEP on one grid: every channel with two keys or
 * more is STEP, and every key time lies on start + k / fps (to 1e-3 of a step) for the lowest
 * such rate up to CB_FPS_LIMIT, into *fps. Rows at that rate, held, are its poses exactly: no
 * blend across a step (cb_clip_plan.step). */
CROWDBAKE_API bool cb_clip_step_grid(const cb_model *model, int32_t animation, double *fps);

/* The rate a planned clip bakes at: its own, else the bake's. */
static inline double cb_clip_plan_fps(const cb_clip_plan *clip, double fps) { return clip->fps > 0 ? clip->fps : fps; }

/* Samples the planned clips (every clip, in file order, when plan is NULL) of the sampler's
 * skin and encodes them. The palette references names in the model and the plan: free it
 * before them. */
CROWDBAKE_API cb_status cb_palette_bake(cb_sampler *sampler, const cb_bake_options *options, const cb_clip_plan *plan,
                                        uint32_t plan_count, cb_palette *out, cb_error *err);
CROWDBAKE_API void cb_palette_free(cb_palette *palette);

/* The rows a timed clip's map takes: one texel per cell, ceil(cells / row_texels). */
CROWDBAKE_API uint32_t cb_timed_map_rows(uint32_t cells, uint32_t row_texels);
/* The palette's first timed clip, or NULL: only a .pal holds timed rows (EXR, KTX2 and Babylon
 * writers refuse them, naming it). */
CROWDBAKE_API const cb_palette_clip *cb_palette_timed_clip(const cb_palette *p);
/* Texel coordinates of a bone's first texel in a baked row. */
CROWDBAKE_API void cb_palette_texel_xy(const cb_palette *p, uint32_t row, uint32_t bone, uint32_t *x, uint32_t *y);

/* Decodes one bone of one row back to a 4x4 column-major matrix. texels points at the
 * palette's texel data (as in cb_palette, or mapped from a file). */
CROWDBAKE_API void cb_palette_decode(const cb_palette *p, const void *texels, uint32_t row, uint32_t bone,
                                     double out[16]);
/* The bone's 4 x texels_per_bone values as a shader reads them (u16 already scaled; relative
 * positions with the bind position added back, as the shader does under CB_POSITIONS_RELATIVE). */
CROWDBAKE_API void cb_palette_decode_values(const cb_palette *p, const void *texels, uint32_t row, uint32_t bone,
                                            double v[16]);
/* Those values (or a blend of two rows of them) as a 4x4 matrix. */
CROWDBAKE_API void cb_palette_values_to_matrix(const cb_palette *p, uint32_t bone, const double v[16], double out[16]);
/* What the shipped shaders compute for a bone between two rows: the rows' values blended by
 * fr (0: row0, 1: row1) - matrices term by term, qpos quaternions the shorter way round (a
 * hemisphere flip) and normalized - as a 4x4 matrix. */
CROWDBAKE_API void cb_palette_blend(const cb_palette *p, const void *texels, uint32_t row0, uint32_t row1, double fr,
                                    uint32_t bone, double out[16]);

/* Moves each of `frames` rows (bones x values floats each) outward so that the linear blend
 * errs about evenly at the rows and halfway between them (about half the sagitta of its
 * intervals; per value, the offset minimising the worst of the two, src/core/fit.c): mids holds the exact values halfway through each interval
 * (frames of them for a loop, whose last interval wraps to row 0; frames - 1 otherwise). qpos
 * rows (8 values: quaternion, position, scale) keep unit quaternions. */
CROWDBAKE_API void cb_fit_rows(float *rows, const float *mids, uint32_t frames, uint32_t bones, uint32_t values,
                               bool loops, bool qpos);

/* ---- conversions ---- */
CROWDBAKE_API uint16_t cb_float_to_half(float f);
CROWDBAKE_API float cb_half_to_float(uint16_t h);

#ifdef __cplusplus
}
#endif

#endif
