/* bake_local.c - see bake_local.h. */
#include "bake_local.h"

#include <stdio.h>
#include <string.h>

#include "crowdbake/outputs.h"
#include "internal/bake_words.h"

/* Why unasked-for local rows do not fit these settings, or NULL where they do. */
static const char *local_unfit(const cb_bake_settings *s)
{
    if (s->layout != CB_LAYOUT_QPOS) return "a layout other than qpos (local rows need qpos)";
    if (s->precision == CB_PRECISION_HALF) return "precision half (its 2^-11 compounds down a chain; local rows need u16 "
                                                  "or float)";
    if (s->fit_rows) return "fitted rows (a fit is to the global blend; local rows are sampled)";
    return NULL;
}

cb_bone_space cb_bake_settings_bone_space(const cb_bake_settings *s, unsigned format)
{
    if (format != CB_FORMAT_PAL) return CB_BONE_SPACE_GLOBAL;
    if (s->bone_space_set || s->bone_space == CB_BONE_SPACE_GLOBAL) return s->bone_space;
    return local_unfit(s) ? CB_BONE_SPACE_GLOBAL : CB_BONE_SPACE_LOCAL;
}

void cb_bake_bone_space_why(const cb_bake_settings *s, unsigned format, cb_bone_space got, const char *fallback_note,
                            char *buf, size_t size)
{
    if (format != CB_FORMAT_PAL)
        snprintf(buf, size, "global rows, which any vertex shader skins as they are: only a .pal holds local rows (no "
                 "place for the parents)");
    else if (got == CB_BONE_SPACE_LOCAL)
        snprintf(buf, size, "local rows (%s): each bone in its parent's frame, blended bone by bone and composed by the "
                 "runtime, the glTF's own interpolation, in fewer rows than global rows need; a bone pass composes them "
                 "once per instance, a vertex shader without one at every vertex (--bone-space global, catalog "
                 "bone_space = \"global\", for such a shader)",
                 s->bone_space_set ? "bone space local, asked for" : "the default for a .pal of qpos rows");
    else if (s->bone_space == CB_BONE_SPACE_GLOBAL) /* set or not: a library caller may set bone_space alone */
        snprintf(buf, size, "global rows (bone space global, asked for), which any vertex shader skins as they are");
    else if (!s->bone_space_set && local_unfit(s))
        snprintf(buf, size, "global rows, not the default local: %s", local_unfit(s));
    else
        snprintf(buf, size, "global rows, not local: %s", fallback_note && fallback_note[0] ? fallback_note :
                 "the rig's palette is not qpos");
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
    if (!s->bone_space_set || s->bone_space != CB_BONE_SPACE_LOCAL) return CB_OK; /* the default: where it fits */
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

void bake_local_notes(const cb_bake_job *job, const cb_palette *p, cb_warnings *w)
{
    if (cb_bake_settings_bone_space(&job->settings, CB_FORMAT_PAL) != CB_BONE_SPACE_LOCAL) return;
    if (p->bone_space != CB_BONE_SPACE_LOCAL) { /* asked for: a note; the default's summary says why */
        if (!job->settings.bone_space_set) return;
        cb_warn(w, "note", "%s: bone space global, not local: %s", pal_path(job),
                p->fallback_note[0] ? p->fallback_note : "the rig's palette is not qpos");
        return;
    }
    for (uint32_t i = 0; i < job->output_count; ++i)
        if (job->outputs[i].format != CB_FORMAT_PAL)
            cb_warn(w, "note", "%s is baked global: only a .pal holds local rows (no place for the parents)", job->outputs[i].path);
}
