/* bake_words.c - see bake.h: a bake job's decisions in words, per clip: why it has its rate
 * and rows, and, over its error budget, what would meet it. */
#include "crowdbake/bake.h"
#include "internal/plumbing.h"
#include "internal/bake_words.h"
#include "core/key_grid.h"   /* cb_key_grid_fps */
#include "core/local_rate.h" /* search_keep's local_rates */
#include "core/palette_bake.h" /* palette_take_kept_analysis */

#include <math.h>
#include <string.h>
#include <stdio.h>

static const char *clip_name(const cb_bake_job *job, uint32_t i)
{
    const cb_clip_plan *c = &job->plan[i];
    return c->name ? c->name : job->model->animations[c->animation].name;
}

/* "--max-fps 180" (a front end's name for the setting), or the catalog's "max_fps = 180". */
static void setting_words(const char *(*setting_name)(cb_setting), cb_setting setting, const char *key, double value,
                          char *buf, size_t size)
{
    const char *flag = setting_name ? setting_name(setting) : NULL;
    if (flag) snprintf(buf, size, "%s %g", flag, value);
    else snprintf(buf, size, "%s = %g", key, value);
}

/* An error rounded up to two significant digits: a budget the clip meets as baked. */
static double budget_above(double error_mm)
{
    if (!(error_mm > 0) || !isfinite(error_mm)) return error_mm;
    double unit = pow(10, floor(log10(error_mm)) - 1);
    double up = ceil(error_mm / unit) * unit;
    return up > error_mm ? up : up + unit;
}

/* A timed clip's reason: its rows on its keys against the uniform rate's, and why they were taken. */
static void timed_reason(const cb_bake_job *job, uint32_t i, const char *rows, const char *played, char *buf, size_t size)
{
    const cb_clip_plan *c = &job->plan[i];
    const cb_rate_choice *r = &job->rates[i];
    snprintf(buf, size, "%u rows on its keys (a map of %u cells at %g Hz, %u row%s) instead of %u at %g fps, %s: %s within "
             "its budget (%.3g mm/m, %s as the runtime plays them)", c->timed_rows, r->timed_cells, r->timed_cell_rate,
             r->timed_map_rows, r->timed_map_rows == 1 ? "" : "s", r->uniform_rows, r->uniform_fps, rows,
             r->timed_rows + r->timed_map_rows < r->uniform_rows ? "fewer bytes"
             : job->settings.timed_rows == CB_TIMED_ROWS_ON     ? "asked for (timed rows on)"
                                                                : "the uniform rate over its budget",
             r->error_mm, played);
}

/* Rows on its keys weighed and not taken, said after the reason in buf; whether they were weighed. */
static bool timed_not_taken(const cb_rate_choice *r, char *buf, size_t size)
{
    size_t n = strlen(buf);
    if (r->timed_weighed && n < size)
        snprintf(buf + n, size - n, "; on its keys at least %u rows and a map of %u row%s, no fewer bytes", r->timed_rows,
                 r->timed_map_rows, r->timed_map_rows == 1 ? "" : "s");
    return r->timed_weighed;
}

/* The job writes a .pal of local rows (a fixed rate's clip reasons then say so). */
static bool pal_rows_local(const cb_bake_job *job)
{
    for (uint32_t i = 0; i < job->output_count; ++i)
        if (job->outputs[i].format == CB_FORMAT_PAL)
            return cb_bake_settings_bone_space(&job->settings, CB_FORMAT_PAL) == CB_BONE_SPACE_LOCAL;
    return false;
}

/* An auto clip's rate chosen for local rows (local_rate.c): its key rate's lowest multiple whose
 * rows, blended and composed as the runtime plays them, stay within its budget. */
static void local_reason(const cb_bake_job *job, uint32_t i, double fps, char *buf, size_t size)
{
    const cb_rate_choice *r = &job->rates[i];
    const cb_animation *a = &job->model->animations[job->plan[i].animation];
    double keys = cb_key_grid_fps(a, a->t0, 0, CB_FPS_LIMIT);
    double multiple = keys > 0 ? fps / keys : 0;
    bool on_keys = keys > 0 && fabs(multiple - round(multiple)) < 1e-6;
    char why[160];
    if (!on_keys && keys > 0)
        snprintf(why, sizeof why, "its keys lie every 1/%g s, over max_fps %g: the common rates", keys,
                 job->clip_settings[i].max_fps);
    else if (!on_keys)
        snprintf(why, sizeof why, "its keys lie on no grid: the common rates");
    else if (multiple < 1.5)
        snprintf(why, sizeof why, "its keys");
    else
        snprintf(why, sizeof why, "%g x its keys' %g fps: nlerp's lag at fewer", round(multiple), keys);
    const cb_clip_plan *c = &job->plan[i];
    size_t n;
    if (c->timed_rows) { /* rows on its keys (local_rate_search.c's choose_timed) */
        timed_reason(job, i, "local rows", "blended and composed", buf, size);
        return;
    }
    if (!r->met)
        snprintf(buf, size, "%g fps, local rows (%s): over its budget even at max_fps (%.3g mm/m)", fps, why, r->error_mm);
    else
        snprintf(buf, size, "%g fps, local rows (%s): the fewest within its budget (%.3g mm/m, blended and composed as the "
                 "runtime plays them)", fps, why, r->error_mm);
    if (!timed_not_taken(r, buf, size) && job->settings.timed_rows == CB_TIMED_ROWS_OFF && (n = strlen(buf)) < size)
        snprintf(buf + n, size - n, "; rows on its keys not weighed (timed rows off)");
}

void cb_bake_clip_reason(const cb_bake_job *job, uint32_t i, char *buf, size_t size)
{
    const cb_clip_plan *c = &job->plan[i];
    const cb_rate_choice *r = &job->rates[i];
    const cb_clip_settings *cs = &job->clip_settings[i];
    double fps = cb_bake_job_clip_fps(job, i);
    bool fitted = c->fit || cs->fit_rows;
    const char *rows = fitted ? "fitted rows" : "sampled rows";
    bool local_chosen = job->search_kept && ((const search_keep *)job->search_kept)->local_rates; /* local_rate.c's */
    if (c->step) {
        snprintf(buf, size, "%g fps, step rows: keyed with STEP, rows at its key times, held not blended (exact; a fixed "
                 "fps bakes it blended)", fps);
    } else if (!cs->fps_auto) {
        snprintf(buf, size, "%g fps, %s: a fixed fps%s", fps, rows, fitted ? " (fit_rows)" : "");
    } else if (local_chosen) {
        local_reason(job, i, fps, buf, size);
    } else if (c->timed_rows) { /* global rows on its keys, asked for (global_timed.c) */
        timed_reason(job, i, "sampled rows", "blended", buf, size);
    } else if (!r->met) {
        snprintf(buf, size, "%g fps, %s: over its budget even at max_fps (%.3g mm/m)", fps, rows, r->error_mm);
    } else if (cs->from.max_fps == CB_FROM_TRANSIENT) {
        snprintf(buf, size, "%g fps, %s: the fewest within its budget (%.3g mm/m), above the default max_fps %g: a fast "
                 "transient no rate up to it brings within the default max_error (a stated max_fps caps it)", fps, rows,
                 r->error_mm, job->settings.max_fps);
    } else if (cs->fit_rows) {
        snprintf(buf, size, "%g fps, %s: the fewest within its budget (%.3g mm/m), every clip fitted (fit_rows)", fps, rows,
                 r->error_mm);
    } else if (fitted && r->other_fps > 0) {
        snprintf(buf, size, "%g fps, %s: the fewest within its budget (%.3g mm/m); sampled rows need %g fps", fps, rows,
                 r->error_mm, r->other_fps);
    } else if (fitted) { /* the search stops at the fewest rows: sampled rows missed at this rate */
        snprintf(buf, size, "%g fps, %s: the fewest within its budget (%.3g mm/m); sampled rows need more than %g fps",
                 fps, rows, r->error_mm, fps);
    } else {
        snprintf(buf, size, "%g fps, %s: the fewest within its budget (%.3g mm/m); fitted rows do not meet it at a lower "
                 "rate", fps, rows, r->error_mm);
    }
    if (cs->fps_auto && !local_chosen && !c->timed_rows && !c->step) timed_not_taken(r, buf, size); /* global rows, on */
    size_t n = strlen(buf); /* a fixed rate's local rows (an auto rate's said so above) */
    if (pal_rows_local(job) && !c->step && !(cs->fps_auto && local_chosen) && n < size)
        snprintf(buf + n, size - n, "; baked as local rows, sampled");
}

void cb_bake_budget_text(const cb_bake_job *job, const cb_bake_result *result, uint32_t i,
                         const char *(*setting_name)(cb_setting), char *buf, size_t size)
{
    const cb_clip_plan *c = &job->plan[i];
    const cb_rate_choice *r = &job->rates[i];
    const cb_clip_budget *b = &result->budgets[i];
    double fps = cb_bake_job_clip_fps(job, i);
    bool fitted = c->fit || job->clip_settings[i].fit_rows;
    char fix[96], relax[96];
    setting_words(setting_name, CB_SETTING_MAX_ERROR, "max_error", budget_above(b->error_mm), relax, sizeof relax);
    if (b->travel > 0) { /* no rate helps: the wrap jumps back by the loop's travel */
        const char *flag = setting_name ? setting_name(CB_SETTING_ROOT_MOTION) : NULL;
        snprintf(fix, sizeof fix, flag ? "%s in-place" : "root_motion = \"in-place\"", flag);
        snprintf(buf, size, "clip '%s' reaches %.3g mm/m at %g fps (%s rows), over max_error %g: it loops and its root "
                 "travels %.3g units a loop, which its wrap pulls back at any rate; bake crowds the game moves in place "
                 "(%s), or give it %s", clip_name(job, i), b->error_mm, fps, fitted ? "fitted" : "sampled",
                 b->max_error_mm, b->travel, fix, relax);
    } else if (!cb_bake_job_clip_auto(job, i)) {
        setting_words(setting_name, CB_SETTING_FPS, "fps", fps, fix, sizeof fix);
        snprintf(buf, size, "clip '%s' reaches %.3g mm/m at %g fps (%s rows), over max_error %g; its rate is fixed (%s): "
                 "leave fps out for the fewest rows within max_error, or give it %s", clip_name(job, i), b->error_mm, fps,
                 fitted ? "fitted" : "sampled", b->max_error_mm, fix, relax);
    } else if (r->met) { /* met baked alone, not in the palette: its u16 range is the palette's */
        snprintf(buf, size, "clip '%s' reaches %.3g mm/m at %g fps (%s rows) in the palette, over max_error %g, though "
                 "%.3g baked alone (the palette's u16 range is wider); give it %s, or the precision float",
                 clip_name(job, i), b->error_mm, fps, fitted ? "fitted" : "sampled", b->max_error_mm, r->error_mm, relax);
    } else if (r->fps_needed > 0) {
        setting_words(setting_name, CB_SETTING_MAX_FPS, "max_fps", r->fps_needed, fix, sizeof fix);
        snprintf(buf, size, "clip '%s' reaches %.3g mm/m at %g fps (%s rows), over max_error %g; it meets it at %g fps "
                 "(%s), or give it %s", clip_name(job, i), b->error_mm, fps, fitted ? "fitted" : "sampled", b->max_error_mm,
                 r->fps_needed, fix, relax);
    } else {
        snprintf(buf, size, "clip '%s' reaches %.3g mm/m at %g fps (%s rows), over max_error %g; no rate up to %g fps meets "
                 "it (the encoding's own error stays over it), give it %s", clip_name(job, i), b->error_mm, fps,
                 fitted ? "fitted" : "sampled", b->max_error_mm, CB_FPS_LIMIT, relax);
    }
}

void cb_bake_goal_words(const cb_clip_budget *b, const char *(*setting_name)(cb_setting), bool allowed, char *buf,
                        size_t size)
{
    const char *flag = setting_name ? setting_name(CB_SETTING_MAX_ERROR) : NULL;
    const char *allow = setting_name ? setting_name(CB_SETTING_ALLOW_OVER_BUDGET) : NULL;
    if (b->goal)
        snprintf(buf, size, " (written at the best the bake reached: the default max_error is a goal; %s %g makes it a "
                 "promise)", flag ? flag : "max_error =", b->max_error_mm);
    else if (allowed)
        snprintf(buf, size, " (written anyway: %s)", allow ? allow : "allow_over_budget");
    else
        buf[0] = 0;
}

void cb_bake_budget_notes(const cb_bake_job *job, const cb_bake_result *result, const char *(*setting_name)(cb_setting),
                          cb_warnings *notes)
{
    uint32_t chosen = 0, fitted = 0;
    double lo = INFINITY, hi = 0, tightest = INFINITY, loosest = 0; /* rates; budgets (a clip may have its own) */
    for (uint32_t i = 0; i < result->budget_count && i < job->plan_count; ++i) {
        if (!cb_bake_job_clip_auto(job, i)) continue;
        const cb_clip_budget *b = &result->budgets[i];
        chosen++, fitted += b->fitted;
        lo = fmin(lo, b->fps), hi = fmax(hi, b->fps);
        tightest = fmin(tightest, b->max_error_mm), loosest = fmax(loosest, b->max_error_mm);
    }
    char budget[64];
    if (tightest == loosest) snprintf(budget, sizeof budget, "%g mm/m", tightest);
    else snprintf(budget, sizeof budget, "%g-%g mm/m, per clip", tightest, loosest);
    if (chosen)
        cb_warn(notes, "note", "%u clip%s error-bounded (max_error %s): %.3g-%.3g fps, %u with fitted rows, %u sampled",
                chosen, chosen == 1 ? "" : "s", budget, lo, hi, fitted, chosen - fitted);
    for (uint32_t i = 0; i < result->budget_count; ++i) {
        const cb_clip_budget *b = &result->budgets[i];
        if (!b->over) continue;
        char text[640], why[160];
        cb_bake_budget_text(job, result, i, setting_name, text, sizeof text);
        bool written = b->goal || job->settings.allow_over_budget;
        cb_bake_goal_words(b, setting_name, job->settings.allow_over_budget, why, sizeof why);
        cb_warn(notes, written ? "warning" : "error", "%s%s", text, why);
    }
}

cb_status cb_bake_clip_frames_at(const cb_bake_job *job, cb_sampler *s, uint32_t clip, double fps, uint32_t *frames,
                                 cb_error *err)
{
    const search_keep *keep = job->search_kept;
    const cb_clip_plan *plan = &job->plan[clip];
    pose_cache *poses = keep && clip < keep->count ? keep->poses[clip] : NULL;
    cb_clip_info info;
    if (!(poses && palette_take_kept_analysis(poses, s, plan->animation, plan->loop, fps, &job->limits, &info)) &&
        cb_clip_analyze(s, plan->animation, fps, plan->loop, &job->limits, &info, err))
        return err->status;
    *frames = info.frames;
    return CB_OK;
}
