/* bake.h - one bake job: a model's skin, its clips and one set of settings, baked into
 * palette files. `crowdbake bake MODEL` runs one job; a catalog (roster.h) runs one per animal
 * type. Every bake decision lives behind this header, once: the defaults, the precision each
 * file format gets, the qpos -> affine fallback, each clip's rate (the job's, the clip's own, or
 * chosen by error), the input hash a file records, and the notes a bake gives.
 *
 *     cb_bake_job job;
 *     cb_bake_job_init(&job); // its size, the default settings and limits
 *     job.model = model, job.skin = 0;
 *     cb_output_path out = {CB_FORMAT_PAL, "fox.pal"};
 *     job.outputs = &out, job.output_count = 1;
 *     cb_bake_result result;
 *     if (cb_bake_job_run(&job, &result, &err) == CB_OK) ... result.outputs[0].palette ...
 *     cb_bake_result_free(&result);
 *     cb_bake_job_free(&job);
 */
#ifndef CB_BAKE_H
#define CB_BAKE_H

#include "export.h"
#include "clip_settings.h"
#include "outputs.h"

#include "runtime.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The rates a setting may take: fps in (0, CB_FPS_LIMIT] (core.h); an auto rate's ceiling
 * (max_fps) in [CB_MAX_FPS_LOWEST, CB_FPS_LIMIT]. */
#define CB_MAX_FPS_LOWEST 2.0

/* What a bake is asked for: the command line's bake options and a catalog's [bake] and
 * [animal] keys fill the same struct. */
typedef struct cb_bake_settings {
    double fps;
    bool fps_auto;               /* fps = "auto" (the default): per clip, the fewest rows within max_error_mm */
    double max_error_mm;         /* the visible error budget, mm per metre of model height (default 1): fps = "auto"
                                  * meets it; with a fixed fps, checked only when max_error_given */
    bool max_error_given;        /* max_error was asked for: a fixed fps is then checked against it too */
    double max_fps;              /* fps = "auto" goes no higher (default CB_AUTO_MAX_FPS, 120) */
    bool allow_over_budget;      /* a clip over its budget is written anyway, with a warning (else the bake fails with
                                  * CB_ERR_VERIFY and writes nothing) */
    cb_layout layout;
    cb_precision precision;
    unsigned formats;            /* CB_FORMAT_* bits: the files a front end asks for (a job writes job->outputs) */
    const char *out_dir;         /* a catalog's: resolved against the catalog's directory */
    uint32_t max_texture_size;
    cb_root_motion root_motion;
    bool layout_set, precision_set; /* chosen explicitly (else: defaults, with fallbacks) */
    bool zstd;                   /* compress the .pal payload */
    int exr_compression;         /* exr.h's lossless codes; 0: none */
    bool fit_rows;               /* every clip's rows fitted to the runtime's linear blend (cb_bake_options.fit); else
                                  * sampled at a fixed fps, and fitted or sampled per clip with fps = "auto" */
    bool measure_all;            /* errors measured at every row, past the budget too (cb_bake_options.measure_all) */
    bool plant_feet;             /* feet locked at bake time (plant_feet.h): leg chains turned so planted feet stay */
    cb_settings_from from;       /* where fps, max_error, max_fps, fit_rows and root_motion came from (all
                                  * CB_FROM_DEFAULT in cb_default_bake_settings) */
    bool row_travel_off;         /* no per-row travel offsets (row_travel.h), where the bake would ship them */
    cb_bone_space bone_space;    /* local: a .pal's rows in each bone's parent frame (.pal version 6; qpos, u16 or
                                  * float); other formats are baked global. Default local, where a .pal can hold it */
    cb_timed_rows timed_rows;    /* an auto rate's rows on its clip's key times (.pal version 7). Local rows: auto
                                  * (default) where that costs fewer bytes, on wherever the keys allow, off never;
                                  * global rows: on where that costs fewer bytes, auto and off never */
    bool bone_space_set;         /* (API 3.2) bone_space was asked for: local where it cannot be held is refused.
                                  * Unset: local in a .pal of qpos rows, u16 or float, not fitted; else global */
} cb_bake_settings;

/* Which settings an override carries (the command line's bake options over a catalog). */
enum {
    CB_BAKE_FPS = 1u << 0, CB_BAKE_LAYOUT = 1u << 1, CB_BAKE_PRECISION = 1u << 2, CB_BAKE_FORMATS = 1u << 3,
    CB_BAKE_MAX_TEXTURE_SIZE = 1u << 4, CB_BAKE_ROOT_MOTION = 1u << 5, CB_BAKE_ZSTD = 1u << 6,
    CB_BAKE_EXR_COMPRESSION = 1u << 7, CB_BAKE_OUT_DIR = 1u << 8, CB_BAKE_FIT_ROWS = 1u << 9,
    CB_BAKE_MEASURE_ALL = 1u << 10, CB_BAKE_ALLOW_OVER_BUDGET = 1u << 11, CB_BAKE_MAX_ERROR = 1u << 12,
    CB_BAKE_MAX_FPS = 1u << 13, CB_BAKE_PLANT_FEET = 1u << 14, CB_BAKE_ROW_TRAVEL = 1u << 15,
    CB_BAKE_BONE_SPACE = 1u << 16, CB_BAKE_TIMED_ROWS = 1u << 17
};

/* fps = "auto" within 1 mm/m up to 120 fps (fps, 30, only for a fixed rate), qpos, u16, a .pal,
 * textures up to 16384 texels a side, root motion kept, no compression; out_dir NULL. */
CROWDBAKE_API cb_bake_settings cb_default_bake_settings(void);

/* Whether a clip's root travels: over the clip, more than 1% of the model's height (10 mm/m, a
 * third of a typical bake's visible blending error); less is root jitter of an in-place clip. */
CROWDBAKE_API bool cb_clip_travels(const cb_clip_info *clip, double model_height);
/* 0 < fps <= CB_FPS_LIMIT; CB_MAX_FPS_LOWEST <= max_fps <= CB_FPS_LIMIT. */
CROWDBAKE_API bool cb_fps_valid(double fps);
CROWDBAKE_API bool cb_max_fps_valid(double max_fps);

/* Whether the settings can be written: each format of settings.formats holds the precision
 * asked for (outputs.h: EXR and KTX2 hold half or float texels, never u16). A .bvat.json is
 * always float (Babylon's Float32 matrices): u16 beside it is the .pal's, and u16 for it alone
 * is refused, never ignored. */
CROWDBAKE_API bool cb_bake_settings_writable(const cb_bake_settings *settings);

/* The options of the bake for one file format (CB_FORMAT_*): the precision set, else u16 for
 * .pal and float for .exr and .ktx2 (half misses 0.5 mm/m on the samples), so writing several
 * formats gives the bytes of single bakes; the affine fallback unless a layout was set; local rows in a .pal
 * unless bone_space says global or the settings cannot hold them (qpos, u16 or float, sampled). */
CROWDBAKE_API cb_bake_options cb_bake_settings_options(const cb_bake_settings *settings, unsigned format,
                                                       const cb_limits *limits, uint32_t threads);

/* One clip as baked, against its error budget. */
typedef struct cb_clip_budget {
    double max_error_mm; /* its budget; 0: none (a fixed fps, no max_error given) */
    double error_mm;     /* the visible error it reaches in the palette */
    bool over;           /* error_mm > max_error_mm > 0 */
    double fps;          /* its effective rate */
    uint32_t rows;
    bool fitted;         /* its rows fitted, else sampled */
    double travel;       /* a loop baked with its root motion kept: how far it travels, model units a loop (its
                          * wrap jumps back that far, at any rate); else 0 */
    bool goal;           /* its budget is crowdbake's default, not one the user stated: a goal the bake reaches for,
                          * not a promise. Over it, the clip is written at the best the bake can do, with a warning */
} cb_clip_budget;

/* A catalog type's identity, which its files record instead of the single bake's options: the
 * content key (rig, planned clips and settings; equal keys share a palette), the resolved
 * catalog entry and its LOD models' bytes. */
typedef struct cb_bake_origin {
    uint64_t content_key;
    const char *canonical;
    const cb_model *const *lods;
    uint32_t lod_count;
} cb_bake_origin;

/* One file a job writes: its format (a CB_FORMAT_* bit) and path. */
typedef struct cb_output_path {
    unsigned format;
    const char *path;
} cb_output_path;

/* cb_bake_job.speed_reference: decide it from the model's clips (cb_speed_reference). */
#define CB_SPEED_REFERENCE_AUTO (-1.0)

typedef struct cb_bake_job {
    /* sizeof(cb_bake_job) in the header the caller was compiled with (cb_bake_job_init sets it):
     * the job grows at its end under one soname, and the library reads no further than this. */
    size_t size;
    const cb_model *model;
    int32_t skin;
    const cb_clip_plan *clips;      /* in row order; NULL: every clip of the model, in file order */
    uint32_t clip_count;
    const cb_clip_request *clip_requests; /* per clip, its catalog entry (clip_settings.h), or NULL */
    cb_bake_settings settings;
    cb_limits limits;
    uint32_t threads;               /* clips sampled in parallel (0: 1); the bytes do not depend on it */
    double speed_reference;         /* recorded in the files; CB_SPEED_REFERENCE_AUTO (cb_bake_job_init's): decided
                                     * by cb_bake_job_run (cb_speed_reference), why in speed_reference_from */
    const cb_output_path *outputs;  /* the files to write, each format once, in any order: they are written in
                                     * the order of the table of formats (outputs.h) */
    uint32_t output_count;
    const struct cb_babylon_state *babylon_states; /* a catalog type's states, listed in its .bvat.json, or NULL */
    uint32_t babylon_state_count;
    const cb_bake_origin *origin;   /* a catalog type, or NULL */
    /* Filled by cb_bake_job_plan (cb_bake_job_run calls it when it was not): the clips with
     * their rates, and for each clip chosen by error what its rate reached. */
    cb_clip_plan *plan;
    uint32_t plan_count;
    cb_rate_choice *rates;
    cb_clip_settings *clip_settings; /* per planned clip, its settings resolved (cb_resolve_clip_settings): what
                                      * planning, the bake, its checks and its words read */
    bool planned;
    void *search_kept; /* internal: what its rate searches kept for the bake (per clip, the poses and rows
                         * they made; the skin's facts), which the bake makes no more (cb_bake_job_free
                         * frees them) */
    char speed_reference_from[256]; /* why the speed reference it decided ("" when the caller gave one) */
    void *planted;      /* internal: with settings.plant_feet, the model copy with the planted leg keys (model
                         * points at it until cb_bake_job_free) and its report (cb_bake_job_plant_report) */
} cb_bake_job;

/* One file written. */
typedef struct cb_bake_output {
    unsigned format;        /* its CB_FORMAT_* bit (cb_output_format_of names it) */
    const char *path;
    uint64_t file_bytes;
    uint64_t input_hash;    /* recorded in the file */
    cb_palette palette;     /* the facts of the palette written (sizes, errors, timings); its tables and
                             * texels are released once written (clips, bind_positions, position_offsets,
                             * texels NULL) */
    double seconds_write;
} cb_bake_output;

typedef struct cb_bake_result {
    uint32_t output_count;
    cb_bake_output outputs[CB_OUTPUT_MAX]; /* those asked for, in the table's order */
    cb_warnings notes;         /* the layout's fallback, loops that travel, quaternion flips, clips over budget */
    cb_clip_budget *budgets;   /* per planned clip, as the first format's palette measured it (also when the bake
                                * failed for a clip over budget) */
    uint32_t budget_count, over_budget; /* over_budget: clips over a budget the user stated (they fail the bake) */
    uint32_t over_goal;        /* clips over the default budget, written with a warning each (cb_clip_budget.goal) */
} cb_bake_result;

/* A job with nothing set but its size, the default settings (cb_default_bake_settings) and
 * limits (cb_default_limits): what every job starts from. */
CROWDBAKE_API void cb_bake_job_init(cb_bake_job *job);
/* Resolves the clips and each one's rate: the clip's fps, else the job's; chosen by visible
 * error (cb_choose_rates) where the clip or the job says auto, with the options of the first
 * file the job writes. A job whose size is not one this library knows (not started by
 * cb_bake_job_init) fails with CB_ERR_INTERNAL, before anything is read past it. */
CROWDBAKE_API cb_status cb_bake_job_plan(cb_bake_job *job, cb_error *err);
/* Plans (when not yet), bakes and writes every file of job->outputs (each through a temporary
 * file and a rename); a format that cannot hold the precision or layout asked for fails with
 * CB_ERR_SETTINGS before anything is baked. A clip over its budget fails the bake with CB_ERR_VERIFY before
 * anything is written (result->budgets says which; cb_bake_budget_text words each), unless
 * settings.allow_over_budget, which writes it with a warning in result->notes; a clip over the
 * default budget (a goal, not stated by the user) is written, counted in over_goal. The result
 * references the model and the plan: free it first. */
CROWDBAKE_API cb_status cb_bake_job_run(cb_bake_job *job, cb_bake_result *out, cb_error *err);
CROWDBAKE_API void cb_bake_result_free(cb_bake_result *result);

/* Whether planned clip i's rate is chosen by error (else fixed): job->clip_settings[i].fps_auto
 * (cb_resolve_clip_settings says how). */
CROWDBAKE_API bool cb_bake_job_clip_auto(const cb_bake_job *job, uint32_t clip);
/* Planned clip i's rate: the one its search chose, else its fixed fps. */
CROWDBAKE_API double cb_bake_job_clip_fps(const cb_bake_job *job, uint32_t clip);
/* Planned clip `clip`'s per-row travel as the job's bake decides it (row_travel.h): `info` is the
 * clip analyzed on `sampler` (cb_clip_analyze), offsets info->frames floats. A front end that
 * reports the decision before or without baking (a roster's manifest) gets the bake's. */
CROWDBAKE_API void cb_bake_job_row_travel(const cb_bake_job *job, cb_sampler *sampler, const cb_clip_info *info,
                                          float *offsets, cb_row_travel *out);
CROWDBAKE_API void cb_bake_job_free(cb_bake_job *job);
/* Frees what planning kept only to save the bake work (the poses its rate searches sampled): a
 * planned job waiting its turn then holds its plan alone, and bakes the same bytes, sampling its
 * rows again. A roster holding many planned types calls it (memory follows the work). */
CROWDBAKE_API void cb_bake_job_release_search(cb_bake_job *job);

/* What a file records of what produced it: for a single bake, the crowdbake version, the
 * options that shape the file (`options`) and the model's bytes; for a catalog type
 * (job->origin), its content key, resolved entry and model and LOD bytes. Same inputs, same
 * hash: a build step whose hash is unchanged need not run. */
CROWDBAKE_API uint64_t cb_bake_input_hash(const cb_bake_job *job, const cb_bake_options *options);

#ifdef __cplusplus
}
#endif

#endif
