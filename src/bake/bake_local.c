/* bake_local.c - see bake_local.h. */
#include "bake_local.h"

#include <stdio.h>
#include <string.h>

#include "crowdbake/outputs.h"

cb_bone_space bake_bone_space(const cb_bake_job *job, unsigned format)
{
    return cb_bake_settings_options(&job->settings, format, NULL, 1).bone_space; /* decided there, for the search too */
}

static const char *pal_path(const cb_bake_job *job)
{
    for (uint32_t i = 0; i < job->output_count; ++i)
        if (job->outputs[i].format == CB_FORMAT_PAL) return job->outputs[i].path;
    return job->output_count ? job->outputs[0].path : "";
}

cb_status bake_check_bone_space(const cb_bake_job *job, unsigned formats, cb_error *err)
{
    const cb_bake_settings *s = &job->settings;
    if (s->bone_space != CB_BONE_SPACE_LOCAL) return CB_OK;
    if (!(formats & CB_FORMAT_PAL))
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_BONE_SPACE, "%s: bone space local: only a .pal holds local "
                               "rows (EXR, KTX2 and Babylon have no place for the parents); add pal to the formats or use "
                               "bone space global", pal_path(job));
    if (s->layout != CB_LAYOUT_QPOS)
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_BONE_SPACE, "%s: bone space local needs layout qpos, not %s; "
                               "use layout qpos or bone space global", pal_path(job), cb_layout_name(s->layout));
    if (s->precision == CB_PRECISION_HALF)
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_BONE_SPACE, "%s: bone space local needs precision u16 or "
                               "float, not half (its 2^-11 compounds down a chain); use precision u16 or bone space global",
                               pal_path(job));
    return CB_OK;
}

/* The clips' rates as baked, "name fps, ..." (cut short where the buffer ends). */
static void clip_rates(const cb_palette *p, char *out, size_t size)
{
    size_t n = 0;
    out[0] = 0;
    for (uint32_t c = 0; c < p->clip_count && n < size; ++c) {
        const cb_palette_clip *k = &p->clips[c];
        if (k->timed) /* its rows on its keys: the map's grid, not a rate */
            n += (size_t)snprintf(out + n, size - n, "%s%s %u rows on its keys (a %g Hz map)", c ? ", " : "", k->name,
                                  k->frames, (float)k->cell_rate);
        else
            n += (size_t)snprintf(out + n, size - n, "%s%s %g fps", c ? ", " : "", k->name, (float)k->fps);
    }
}

void bake_local_notes(const cb_bake_job *job, const cb_palette *p, cb_warnings *w)
{
    if (job->settings.bone_space != CB_BONE_SPACE_LOCAL) return;
    if (p->bone_space != CB_BONE_SPACE_LOCAL) {
        cb_warn(w, "note", "%s: bone space global, not the local asked for: %s", pal_path(job),
                p->fallback_note[0] ? p->fallback_note : "the rig's palette is not qpos");
        return;
    }
    char rates[400];
    clip_rates(p, rates, sizeof rates);
    cb_warn(w, "note", "%s: bone space local: each row holds every bone's transform in its parent's "
            "frame (.pal version 6; 7 with timed rows), blended bone by bone and composed by the runtime, the glTF's own interpolation; "
            "rows sampled, not fitted (a fit is to the global blend); errors measured composed", pal_path(job));
    if (job->settings.fps_auto)
        cb_warn(w, "note", "%s: local rows at each clip's key rate, or its lowest multiple within max_error measured "
                "blended and composed as the runtime plays them (a clip whose keys lie on no grid up to max_fps: the "
                "common rates), or on its keys where that takes fewer rows (timed rows, .pal version 7); each clip's reason "
                "says which: %s", pal_path(job), rates);
    for (uint32_t i = 0; i < job->output_count; ++i)
        if (job->outputs[i].format != CB_FORMAT_PAL)
            cb_warn(w, "note", "%s is baked global: only a .pal holds local rows (no place for the parents)", job->outputs[i].path);
}
