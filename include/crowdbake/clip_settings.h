/* clip_settings.h - the settings one clip is baked with, resolved once (cb_resolve_clip_settings,
 * src/clip_settings.c) from the layers that may state them, and where each value came from.
 *
 * The layers, the later over the earlier: the defaults (cb_default_bake_settings); a catalog's
 * [bake]; its [animal.NAME]; the options given for one run (the command line); a catalog's clip
 * entry (its own fps and max_error; also the command line's --loop/--one-shot of a single
 * model). A clip's own fps or max_error thus still applies under a run's --fps/--max-error: it
 * names that one clip. Every field of cb_clip_settings is concrete: nothing in it inherits. */
#ifndef CB_CLIP_SETTINGS_H
#define CB_CLIP_SETTINGS_H

#include <stddef.h>

#include "export.h"
#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where a setting's value came from. */
typedef enum cb_setting_from {
    CB_FROM_DEFAULT = 0,  /* crowdbake's default */
    CB_FROM_CATALOG,      /* a catalog's [bake] */
    CB_FROM_ANIMAL,       /* a catalog's [animal.NAME] */
    CB_FROM_COMMAND_LINE, /* the options given for one run */
    CB_FROM_CLIP,         /* a catalog's clip entry */
    CB_FROM_RIG,          /* the rig: a skin with no skinned mesh has no error to bound, so a fixed fps */
    CB_FROM_TRAVEL,       /* root_motion: a loop travels, so loops go in place (cb_bake_job_plan) */
    CB_FROM_TRANSIENT     /* max_fps: a fast transient the default max_error is out of reach for at the default
                           * max_fps, searched on up to CB_TRANSIENT_MAX_FPS (cb_bake_job_plan) */
} cb_setting_from;

/* "default", "catalog [bake]", "catalog animal", "command line", "catalog clip", "rig: no skinned mesh". */
CROWDBAKE_API const char *cb_setting_from_name(cb_setting_from from);

/* Where a bake's job-wide settings (cb_bake_settings.from) came from: fps covers fps and auto. */
typedef struct cb_settings_from {
    cb_setting_from fps, max_error, max_fps, fit_rows, root_motion;
} cb_settings_from;

/* One clip's effective settings. */
typedef struct cb_clip_settings {
    bool fps_auto;       /* its rate chosen by error (the fewest rows within max_error_mm); else fixed at fps */
    double fps;          /* the fixed rate (with fps_auto, the one a fixed bake would take) */
    double max_error_mm; /* its error budget, mm per metre of model height; 0: none (a fixed fps, no max_error beside it) */
    double max_fps;      /* the highest rate fps_auto may choose */
    bool fit_rows;       /* every row fitted to the runtime's blend (else fitted or sampled as the rate search finds) */
    cb_root_motion root_motion;
    int loop;            /* -1: decided from the poses; 0: one-shot; 1: loop */
    struct {
        cb_setting_from fps, max_error, max_fps, fit_rows, root_motion, loop;
    } from;
} cb_clip_settings;

/* What a catalog's clip entry says beyond cb_clip_plan (whose fps and loop it also fills). */
typedef struct cb_clip_request {
    int fps_auto;        /* -1: as the job's settings; 0: the plan's fixed fps; 1: chosen by error */
    double max_error_mm; /* 0: not given; given, a fixed fps is checked against it */
} cb_clip_request;

struct cb_bake_settings;

/* The one place a clip's settings are resolved: `job` the bake's settings (defaults, catalog
 * and command line already layered, each value's origin in job->from); `clip` the clip's plan
 * entry (its own fps > 0 and loop >= 0 win), `request` its catalog entry or NULL; `clip_from`
 * names who wrote the clip's own values (CB_FROM_CLIP for a catalog, CB_FROM_COMMAND_LINE for a
 * single model's --loop); `measurable`: the skin has a skinned mesh to measure errors on.
 * The rules:
 *  - rate: the clip's fps = "auto"; else its own fixed fps; else, on a skin with nothing to
 *    measure, the job's fixed fps; else the job's (auto or fixed);
 *  - budget: the clip's max_error; else the job's for an error-bounded clip; else none for a
 *    clip with a fixed fps of its own; else the job's if max_error was given beside its fixed
 *    fps; else none;
 *  - max_fps, fit_rows, root_motion: the job's. */
CROWDBAKE_API void cb_resolve_clip_settings(const struct cb_bake_settings *job, const cb_clip_plan *clip,
                                            const cb_clip_request *request, cb_setting_from clip_from, bool measurable,
                                            cb_clip_settings *out);

/* The settings and their origins in one line: "fps auto (default), max_error 1 mm/m (catalog
 * animal), max_fps 120 (default), rows fitted or sampled (default), root_motion keep (default),
 * loop from the poses (default)". */
CROWDBAKE_API void cb_clip_settings_text(const cb_clip_settings *settings, char *buf, size_t size);

#ifdef __cplusplus
}
#endif

#endif
