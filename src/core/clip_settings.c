/* clip_settings.c - see clip_settings.h: each clip's settings, resolved once. */
#include "crowdbake/clip_settings.h"

#include <stdio.h>

#include "crowdbake/bake.h"

const char *cb_setting_from_name(cb_setting_from from)
{
    switch (from) {
    case CB_FROM_CATALOG: return "catalog [bake]";
    case CB_FROM_ANIMAL: return "catalog animal";
    case CB_FROM_COMMAND_LINE: return "command line";
    case CB_FROM_CLIP: return "catalog clip";
    case CB_FROM_RIG: return "rig: no skinned mesh";
    case CB_FROM_TRAVEL: return "a loop travels";
    default: return "default";
    }
}

/* The rate: chosen by error or fixed, at which fps, and who said so. */
static void resolve_rate(const cb_bake_settings *job, const cb_clip_plan *clip, const cb_clip_request *request,
                         cb_setting_from clip_from, bool measurable, cb_clip_settings *out)
{
    bool own_fps = clip->fps > 0 || (request && request->fps_auto == 0);
    out->fps = clip->fps > 0 ? clip->fps : job->fps;
    if (request && request->fps_auto == 1) { /* asked for by name: a skin with no mesh then fails, saying so */
        out->fps_auto = true, out->from.fps = clip_from;
    } else if (own_fps) {
        out->fps_auto = false, out->from.fps = clip_from;
    } else if (!measurable && job->fps_auto) { /* nothing to measure: the fixed fps */
        out->fps_auto = false, out->from.fps = CB_FROM_RIG;
    } else {
        out->fps_auto = job->fps_auto, out->from.fps = job->from.fps;
    }
}

/* The error budget: an error-bounded clip's goal; a fixed fps is checked only against a
 * max_error asked for beside it (the clip's own, or the job's for the job's fixed fps: a clip
 * pinned to an fps of its own is not held to the job's max_error). */
static void resolve_budget(const cb_bake_settings *job, const cb_clip_plan *clip, const cb_clip_request *request,
                           cb_setting_from clip_from, cb_clip_settings *out)
{
    bool own_fps = clip->fps > 0 || (request && request->fps_auto == 0);
    if (request && request->max_error_mm > 0)
        out->max_error_mm = request->max_error_mm, out->from.max_error = clip_from;
    else if (out->fps_auto || (!own_fps && job->max_error_given))
        out->max_error_mm = job->max_error_mm, out->from.max_error = job->from.max_error;
    else /* none: decided by whoever fixed the rate */
        out->max_error_mm = 0, out->from.max_error = out->from.fps;
}

void cb_resolve_clip_settings(const cb_bake_settings *job, const cb_clip_plan *clip, const cb_clip_request *request,
                              cb_setting_from clip_from, bool measurable, cb_clip_settings *out)
{
    resolve_rate(job, clip, request, clip_from, measurable, out);
    resolve_budget(job, clip, request, clip_from, out);
    out->max_fps = job->max_fps, out->from.max_fps = job->from.max_fps;
    out->fit_rows = job->fit_rows, out->from.fit_rows = job->from.fit_rows;
    out->root_motion = job->root_motion, out->from.root_motion = job->from.root_motion;
    out->loop = clip->loop < 0 ? -1 : clip->loop;
    out->from.loop = clip->loop < 0 ? CB_FROM_DEFAULT : clip_from;
}

void cb_clip_settings_text(const cb_clip_settings *s, char *buf, size_t size)
{
    char fps[32], budget[48];
    if (s->fps_auto) snprintf(fps, sizeof fps, "auto");
    else snprintf(fps, sizeof fps, "%g", s->fps);
    if (s->max_error_mm > 0) snprintf(budget, sizeof budget, "%g mm/m", s->max_error_mm);
    else snprintf(budget, sizeof budget, "none");
    snprintf(buf, size, "fps %s (%s), max_error %s (%s), max_fps %g (%s), rows %s (%s), root_motion %s (%s), loop %s (%s)",
             fps, cb_setting_from_name(s->from.fps), budget, cb_setting_from_name(s->from.max_error), s->max_fps,
             cb_setting_from_name(s->from.max_fps), s->fit_rows ? "fitted" : "fitted or sampled",
             cb_setting_from_name(s->from.fit_rows), cb_root_motion_name(s->root_motion),
             cb_setting_from_name(s->from.root_motion),
             s->loop < 0 ? "from the poses" : s->loop ? "true" : "false", cb_setting_from_name(s->from.loop));
}
