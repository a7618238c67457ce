/* bake_job.c - see bake.h: the one place where a bake's policy is decided. */
#include "crowdbake/bake.h"
#include "crowdbake/locomotion.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "crowdbake_pal.h" /* XXH64 */
#include "bake_transients.h"
#include "bake_local.h"
#include "bake_travel.h"
#include "outputs.h"
#include "plant_feet.h"
#include "bake_beside.h"
#include "../core/palette_bake.h" /* palette_choose_rates, the search's poses kept for the bake */
#include "../core/pose_cache.h"
#include "../core/clip_memo.h"
#include "../core/foot_cache.h"
#include "internal/plumbing.h"
#include "internal/bake_words.h"

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* ---- settings ---- */

cb_bake_settings cb_default_bake_settings(void)
{
    cb_bake_settings s;
    memset(&s, 0, sizeof s);
    s.fps = 30; /* a fixed rate's, when fps_auto is turned off */
    s.fps_auto = true;
    s.max_error_mm = 1;
    s.max_fps = CB_AUTO_MAX_FPS;
    s.layout = CB_LAYOUT_QPOS;
    s.precision = CB_PRECISION_U16;
    s.formats = CB_FORMAT_PAL;
    s.max_texture_size = 16384;
    s.root_motion = CB_ROOT_MOTION_KEEP;
    s.timed_rows = CB_TIMED_ROWS_AUTO;
    s.bone_space = CB_BONE_SPACE_LOCAL; /* where a .pal holds it (cb_bake_settings_bone_space) */
    return s;
}

bool cb_clip_travels(const cb_clip_info *clip, double model_height)
{
    double travel = clip->ground_speed * clip->duration;
    return travel > 0 && travel > 0.01 * model_height;
}

unsigned cb_formats_parse(const char *text)
{
    if (strcmp(text, "both") == 0) return CB_FORMAT_PAL | CB_FORMAT_EXR;
    unsigned formats = 0;
    for (const char *w = text;; ++w) {
        size_t n = strcspn(w, ",");
        const cb_output_format *f = cb_output_format_named(w, n);
        if (!f || (formats & f->format)) return 0;
        formats |= f->format;
        if (!w[n]) return formats;
        w += n;
    }
}

bool cb_fps_valid(double fps) { return fps > 0 && fps <= CB_FPS_LIMIT; }
bool cb_max_fps_valid(double max_fps) { return max_fps >= CB_MAX_FPS_LOWEST && max_fps <= CB_FPS_LIMIT; }

static bool holds(const cb_output_format *f, const cb_bake_options *o)
{
    return (f->precisions >> o->precision & 1u) && (f->layouts >> o->layout & 1u);
}

/* u16 asked for a format that holds no u16 is refused; a .bvat.json's own precision is its own,
 * so u16 beside it is the other format's, and for it alone refused. */
bool cb_bake_settings_writable(const cb_bake_settings *s)
{
    if (!s->precision_set || s->precision != CB_PRECISION_U16) return true;
    bool other = false;
    for (uint32_t i = 0; i < cb_output_format_count(); ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        if (!(s->formats & f->format)) continue;
        if (!(f->precisions >> CB_PRECISION_U16 & 1u) && f->holds_palette) return false;
        other |= f->holds_palette;
    }
    return other || !s->formats;
}

cb_bake_options cb_bake_settings_options(const cb_bake_settings *s, unsigned format, const cb_limits *limits,
                                         uint32_t threads)
{
    cb_bake_options o = cb_default_bake_options();
    if (limits) o.limits = *limits;
    o.fps = s->fps;
    o.layout = s->layout;
    /* EXR holds half or float; half misses 0.5 mm/m on the samples, so float unless asked. KTX2 takes
     * the .pal's precision, half for its default u16 (ktx2_half_note says why). */
    o.precision = s->precision_set || format == CB_FORMAT_PAL ? s->precision : CB_PRECISION_FLOAT;
    if (format == CB_FORMAT_KTX2 && !s->precision_set)
        o.precision = s->precision == CB_PRECISION_U16 ? CB_PRECISION_HALF : s->precision;
    o.max_texture_size = s->max_texture_size;
    o.root_motion = s->root_motion;
    o.threads = threads ? threads : 1;
    o.affine_fallback = !s->layout_set; /* a rig qpos cannot hold bakes affine, unless a layout was asked for */
    o.fit = s->fit_rows;
    o.measure_all = s->measure_all;
    /* Babylon.js's baked vertex animation texture holds Float32 4x4 matrices: bake them exactly so. */
    if (format == CB_FORMAT_BABYLON) o.layout = CB_LAYOUT_MAT4, o.precision = CB_PRECISION_FLOAT, o.affine_fallback = false;
    /* Local rows go only in a .pal (EXR, KTX2 and Babylon have no place for the parents): every other
     * format is baked global (bake_notes says so). The rate search takes it from here too. */
    o.bone_space = cb_bake_settings_bone_space(s, format);
    o.timed_rows = format == CB_FORMAT_PAL ? s->timed_rows : CB_TIMED_ROWS_OFF; /* only a .pal has a map */
    return o;
}

/* The formats of the job's outputs (CB_FORMAT_* bits). */
static unsigned job_formats(const cb_bake_job *job)
{
    unsigned f = 0;
    for (uint32_t i = 0; i < job->output_count; ++i) f |= job->outputs[i].format;
    return f;
}

/* The first format the job writes, in the table's order: its options choose the rates. */
static unsigned first_format(const cb_bake_job *job)
{
    unsigned f = job_formats(job);
    for (uint32_t i = 0; i < cb_output_format_count(); ++i)
        if (f & cb_output_format_at(i)->format) return cb_output_format_at(i)->format;
    return CB_FORMAT_PAL;
}

/* The path the job writes `format` to, or NULL. */
static const char *output_path(const cb_bake_job *job, unsigned format)
{
    for (uint32_t i = 0; i < job->output_count; ++i)
        if (job->outputs[i].format == format) return job->outputs[i].path;
    return NULL;
}

/* ---- the input hash ---- */

static void hash_str(cbpal_xxh64_state *h, const char *s) { cbpal_xxh64_update(h, s, strlen(s) + 1); }

uint64_t cb_bake_input_hash(const cb_bake_job *job, const cb_bake_options *o)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    const cb_model *m = job->model;
    if (job->origin) {
        const cb_bake_origin *g = job->origin;
        cbpal_xxh64_update(&h, &g->content_key, sizeof g->content_key);
        hash_str(&h, g->canonical);
        cbpal_xxh64_update(&h, &m->source_hash, sizeof m->source_hash);
        for (uint32_t i = 0; i < g->lod_count; ++i)
            cbpal_xxh64_update(&h, &g->lods[i]->source_hash, sizeof g->lods[i]->source_hash);
        return cbpal_xxh64_digest(&h);
    }
    char opts[360], chosen[96] = ""; /* error-bounded rates: the goal chooses them (a fixed fps: as before it) */
    /* Timed rows other than auto (the hash as before it) where they change a file: local rows' .pal (on and off),
     * global rows' (on: auto and off take none). */
    bool timed_asked = o->timed_rows == CB_TIMED_ROWS_ON || (o->timed_rows == CB_TIMED_ROWS_OFF && o->bone_space == CB_BONE_SPACE_LOCAL);
    if (job->settings.fps_auto)
        snprintf(chosen, sizeof chosen, " auto max_error=%.17g max_fps=%.17g", job->settings.max_error_mm,
                 job->settings.max_fps);
    int n = snprintf(opts, sizeof opts, "crowdbake %s fps=%.17g layout=%s precision=%s max=%u root=%d skin=%d zstd=%d exr=%d%s%s%s%s%s%s%s%s\n",
                     CROWDBAKE_VERSION, o->fps, cb_layout_name(o->layout), cb_precision_name(o->precision),
                     o->max_texture_size, (int)o->root_motion, job->skin, job->settings.zstd,
                     job->settings.exr_compression, o->fit ? " fit-rows" : "", o->measure_all ? " measure-all" : "", chosen,
                     job->settings.plant_feet ? " plant-feet" : "", job->settings.row_travel_off ? " row-travel-off" : "",
                     o->bone_space == CB_BONE_SPACE_LOCAL ? " bone-space=local" : "",
                     timed_asked ? " timed-rows=" : "", timed_asked ? cb_timed_rows_name(o->timed_rows) : "");
    cbpal_xxh64_update(&h, opts, (size_t)n);
    cbpal_xxh64_update(&h, &m->source_hash, sizeof m->source_hash);
    return cbpal_xxh64_digest(&h);
}

/* ---- planning: the clips and their rates ---- */

bool cb_bake_job_clip_auto(const cb_bake_job *job, uint32_t i) { return job->clip_settings[i].fps_auto; }

double cb_bake_job_clip_fps(const cb_bake_job *job, uint32_t i)
{
    return job->clip_settings[i].fps_auto ? job->plan[i].fps : job->clip_settings[i].fps;
}

/* Every clip's settings, resolved once (clip_settings.h): a catalog's clip entries are its
 * own; the plan's own values otherwise came from the front end (a single model's --loop). */
static void resolve_clips(cb_bake_job *job)
{
    bool measurable = cb_model_skin_vertex_count(job->model, job->skin) > 0;
    cb_setting_from clip_from = job->clip_requests ? CB_FROM_CLIP : CB_FROM_COMMAND_LINE;
    for (uint32_t i = 0; i < job->plan_count; ++i)
        cb_resolve_clip_settings(&job->settings, &job->plan[i], job->clip_requests ? &job->clip_requests[i] : NULL,
                                 clip_from, measurable, &job->clip_settings[i]);
}

/* A STEP-keyed clip whose rate is chosen (fps auto): rows at its key times, held, not blended
 * (cb_clip_step_grid) - exact, so no search. A fixed fps bakes it blended, as before. True when
 * clip i is one; its plan then says so. */
static bool plan_step_rows(cb_bake_job *job, uint32_t i)
{
    double fps;
    if (!job->clip_settings[i].fps_auto || !cb_clip_step_grid(job->model, job->plan[i].animation, &fps)) return false;
    job->plan[i].fps = fps, job->plan[i].step = true, job->plan[i].fit = false;
    job->rates[i] = (cb_rate_choice){.met = true};
    return true;
}

/* Clip i's goal when its rate is chosen by error: the fewest rows within its budget, fitted or
 * sampled (every clip fitted under fit_rows, cb_bake_options.fit). */
static bool clip_goal(const cb_bake_job *job, uint32_t i, cb_rate_goal *goal)
{
    const cb_clip_settings *c = &job->clip_settings[i];
    if (!c->fps_auto || job->plan[i].step) return false;
    *goal = (cb_rate_goal){c->max_error_mm, c->max_fps, CB_ROWS_BEST};
    return true;
}

static void free_search_kept(cb_bake_job *job)
{
    search_keep_free(job->search_kept); /* a search_keep: the poses and the skin's facts */
    job->search_kept = NULL;
}

void cb_bake_job_init(cb_bake_job *job)
{
    memset(job, 0, sizeof *job);
    job->size = sizeof *job;
    job->settings = cb_default_bake_settings();
    job->limits = cb_default_limits();
    job->speed_reference = CB_SPEED_REFERENCE_AUTO;
}

/* The speed reference nobody gave: the slowest locomotion clip's ground speed (locomotion.h),
 * decided here so that every program baking the model records the same one - beside the rate
 * search where there was one (bake_beside.h), else now. Its clips' strides go into the run's
 * foot analyses, which the per-row travel reads again. */
static void decide_speed_reference(cb_bake_job *job, foot_cache *feet, clip_memo *memo, bool beside, double speed,
                                   const char *why)
{
    if (job->speed_reference >= 0) return;
    if (beside) {
        job->speed_reference = speed;
        snprintf(job->speed_reference_from, sizeof job->speed_reference_from, "%s", why);
        return;
    }
    job->speed_reference = speed_reference_cached(feet, memo, job->model, job->skin, job->plan, job->plan_count,
                                                  job->threads ? job->threads : 1, job->speed_reference_from, sizeof job->speed_reference_from);
}

/* A clip's analysis made while planning, kept for its rate search (palette_seed_analysis). */
typedef struct early_analysis {
    cb_clip_info info;
    double fps;
    int loop;  /* the plan's loop override it was made with */
    bool made; /* info holds it */
} early_analysis;

/* Root motion decided like the rest: a bake nobody told what to do with root travel keeps it,
 * unless a loop travels: its wrap would pull the body back at any rate, and what a crowd wants
 * is the loop in place with its velocity recorded, the game moving the instance. Then the loops
 * go in place and the one-shots keep their travel (a fall ends where it falls); bake_notes says
 * so, and --root-motion (or the catalog's root_motion) overrides. The clips it analyzes go into
 * early[] (each clip's slot), for their rate searches. */
static void decide_root_motion(cb_bake_job *job, early_analysis *early)
{
    if (job->settings.from.root_motion != CB_FROM_DEFAULT || job->settings.root_motion != CB_ROOT_MOTION_KEEP) return;
    cb_error e = {0};
    cb_sampler *s = cb_sampler_create(job->model, job->skin, &e);
    if (!s) return; /* the bake reports it */
    double lo[3], hi[3], height = cb_skin_rest_bounds(s, lo, hi);
    bool travels = false;
    for (uint32_t i = 0; i < job->plan_count && !travels; ++i) {
        early_analysis *a = &early[i];
        cb_error ce = {0};
        a->fps = cb_clip_plan_fps(&job->plan[i], job->settings.fps), a->loop = job->plan[i].loop;
        a->made = !cb_clip_analyze(s, job->plan[i].animation, a->fps, a->loop, &job->limits, &a->info, &ce);
        travels = a->made && a->info.loops && cb_clip_travels(&a->info, height);
    }
    cb_sampler_free(s);
    if (travels) job->settings.root_motion = CB_ROOT_MOTION_LOOPS_IN_PLACE, job->settings.from.root_motion = CB_FROM_TRAVEL;
}

cb_status cb_bake_job_plan(cb_bake_job *job, cb_error *err)
{
    /* The one size there is so far; a later MINOR that adds fields also takes this size and
     * gives the fields it lacks their defaults. */
    if (job->size != sizeof *job)
        return cb_fail(err, CB_ERR_INTERNAL,
                       "cb_bake_job.size is %zu, but this libcrowdbake's job is %zu bytes: start the job with "
                       "cb_bake_job_init, and build against the headers of the library it runs with",
                       job->size, sizeof *job);
    if (job->planned) return CB_OK;
    const cb_model *m = job->model;
    uint32_t n = job->clips ? job->clip_count : m->animation_count;
    free_search_kept(job);
    for (uint32_t i = 0; job->plan && i < job->plan_count; ++i) cb_clip_plan_release(&job->plan[i]);
    free(job->plan), free(job->rates), free(job->clip_settings);
    job->plan = calloc(n ? n : 1, sizeof *job->plan);
    job->rates = calloc(n ? n : 1, sizeof *job->rates);
    job->clip_settings = calloc(n ? n : 1, sizeof *job->clip_settings);
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    if (!job->plan || !job->rates || !job->clip_settings || !goals) {
        free(goals);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    bool any = false;
    for (uint32_t i = 0; i < n; ++i) job->plan[i] = job->clips ? job->clips[i] : (cb_clip_plan){(int32_t)i, NULL, -1, 0, false, false, 0, NULL};
    job->plan_count = n;
    if (job->settings.plant_feet && !job->planted && plant_feet_apply(job, err)) return free(goals), err->status;
    early_analysis *early = calloc(n ? n : 1, sizeof *early);
    bool *searched = calloc(n ? n : 1, sizeof *searched);
    if (!early || !searched) return free(goals), free(early), free(searched), cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    decide_root_motion(job, early);
    resolve_clips(job);
    for (uint32_t i = 0; i < n; ++i) plan_step_rows(job, i);
    for (uint32_t i = 0; i < n; ++i) any |= searched[i] = clip_goal(job, i, &goals[i]);
    if (any) {
        cb_sampler *s = cb_sampler_create(job->model, job->skin, err); /* planted feet: the copy */
        cb_bake_options o = cb_bake_settings_options(&job->settings, first_format(job), &job->limits, job->threads);
        search_keep *keep = search_keep_create(n); /* NULL: nothing kept, as slow */
        job->search_kept = keep;
        if (keep) keep->beside = bake_beside_create(job); /* the speed reference and travels (NULL: in the run) */
        /* Each searched clip's analysis from the root motion's decision, kept for its search
         * (which takes it where it stands in for its own: palette_take_kept_analysis). */
        for (uint32_t i = 0; s && keep && i < n; ++i)
            if (searched[i] && early[i].made)
                palette_seed_analysis(keep, i, s, &early[i].info, early[i].fps, early[i].loop);
        bool *later = bake_transient_candidates(job); /* NULL: none left for later */
        if (s && !palette_choose_rates(s, &o, job->plan, n, goals, job->rates, job->search_kept, later, err))
            bake_reach_for_transients(job, s, &o, err);
        cb_sampler_free(s), free(later);
    }
    free(goals), free(early), free(searched);
    job->planned = !err->status;
    return err->status;
}

/* ---- the bake ---- */

/* A loop whose root travels jumps back by its travel over one loop where it wraps. Under 1% of
 * the model's height (10 mm/m, a third of a typical bake's visible blending error) that jump is
 * root jitter of an in-place clip, not travel worth a note. */
static bool loop_travel_visible(const cb_palette *p, const cb_palette_clip *clip)
{
    cb_clip_info info = {.duration = clip->duration, .loops = clip->loops, .ground_speed = clip->ground_speed};
    return clip->loops && cb_clip_travels(&info, p->model_height);
}

/* What the user should know about a bake: the layout's fallback, loops that travel, quaternion
 * flips. */
static void bake_notes(const cb_bake_options *o, cb_setting_from from, const cb_palette *p, cb_warnings *w)
{
    if (p->fallback_note[0]) cb_warn(w, "note", "%s", p->fallback_note);
    for (uint32_t c = 0; from == CB_FROM_TRAVEL && c < p->clip_count; ++c)
        if (loop_travel_visible(p, &p->clips[c]))
            cb_warn(w, "note", "clip '%s' loops and travels %.3g units/s, which its wrap would pull back at any rate: the "
                    "loops are baked in place with their velocity recorded (the game moves the instance), the one-shots "
                    "keep their travel (root_motion loops-in-place; --root-motion keep keeps it)", p->clips[c].name,
                    p->clips[c].ground_speed);
    for (uint32_t c = 0; o->root_motion == CB_ROOT_MOTION_KEEP && c < p->clip_count; ++c) {
        if (loop_travel_visible(p, &p->clips[c]))
            cb_warn(w, "note", "clip '%s' loops and travels %.3g units/s: blending its last row into its first pulls the "
                    "body back; for crowds moved by the game, bake with --root-motion in-place", p->clips[c].name,
                    p->clips[c].ground_speed);
    }
    if (p->quat_hemisphere_breaks)
        cb_warn(w, "note", "%u bone(s) turn a full circle over a loop, so their last and first rows lie in opposite "
                "quaternion hemispheres; the shipped shaders flip before blending", p->quat_hemisphere_breaks);
}

/* The decision a KTX2 output's default precision makes for the user, with its reason. */
static void ktx2_half_note(const cb_bake_job *job, unsigned format, const cb_bake_options *o, cb_warnings *w)
{
    if (format != CB_FORMAT_KTX2 || job->settings.precision_set || o->precision != CB_PRECISION_HALF) return;
    cb_warn(w, "note", "%s is half (RGBA16F), the float format as wide as the .pal's default u16: KTX2 would hold u16 as "
            "RGBA16UI, an integer format three.js's KTX2Loader and most engines refuse; --precision float for float texels",
            output_path(job, format));
}

static cb_status write_output(const cb_bake_job *job, const cb_palette *p, cb_pal_mapping *mapping, cb_bake_output *out,
                              cb_error *err)
{
    double t0 = now_seconds();
    bake_output_row_of(out->format)->write(job, p, mapping, out, err);
    out->seconds_write = now_seconds() - t0;
    struct stat st;
    out->file_bytes = !err->status && stat(out->path, &st) == 0 ? (uint64_t)st.st_size : 0;
    return err->status;
}

/* Every output a known format, once, with a path, able to hold what the settings bake for it. */
static cb_status check_outputs(const cb_bake_job *job, cb_error *err)
{
    if (!job->output_count) return cb_fail(err, CB_ERR_SETTINGS, "%s: the bake job lists no output", job->model->source);
    if (job->output_count > CB_OUTPUT_MAX)
        return cb_fail(err, CB_ERR_SETTINGS, "the bake job lists %u outputs; at most %d", job->output_count, CB_OUTPUT_MAX);
    unsigned seen = 0;
    for (uint32_t i = 0; i < job->output_count; ++i) {
        const cb_output_path *o = &job->outputs[i];
        const cb_output_format *f = cb_output_format_of(o->format);
        if (!f || !o->path || (seen & o->format))
            return cb_fail(err, CB_ERR_SETTINGS, "the bake job's output %u is %s", i,
                           !f ? "no format of outputs.h" : !o->path ? "without a path" : "a format listed twice");
        seen |= o->format;
        cb_bake_options opt = cb_bake_settings_options(&job->settings, o->format, &job->limits, 1);
        if (!holds(f, &opt))
            return cb_fail(err, CB_ERR_SETTINGS, "%s: a %s file holds no %s/%s texels; choose another precision or "
                           "layout", o->path, f->name, cb_layout_name(opt.layout), cb_precision_name(opt.precision));
    }
    return bake_check_bone_space(job, seen, err);
}

/* Every clip against its budget in the palette baked: what a player sees of each. An
 * error-bounded clip met it baked alone; in the palette its u16 box is the palette's, wider,
 * so its encoding errs a little more: the palette is what is promised. Only a budget the user
 * stated (command line, catalog) is a promise: crowdbake's default is a goal, so a bare bake of
 * a punch or a death that no rate up to max_fps brings within 1 mm/m is written at the best the
 * search found, with a warning per clip (issue 43, item 0), not refused. */
static cb_status check_budgets(const cb_bake_job *job, const cb_palette *p, cb_bake_result *out, cb_error *err)
{
    out->budgets = calloc(p->clip_count ? p->clip_count : 1, sizeof *out->budgets);
    if (!out->budgets) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    out->budget_count = p->clip_count;
    for (uint32_t i = 0; i < p->clip_count; ++i) {
        cb_clip_budget *b = &out->budgets[i];
        b->max_error_mm = job->clip_settings[i].max_error_mm;
        b->error_mm = cb_mm_per_m(p->clips[i].visible_error, p->model_height);
        b->over = b->max_error_mm > 0 && b->error_mm > b->max_error_mm;
        b->goal = b->max_error_mm > 0 && job->clip_settings[i].from.max_error == CB_FROM_DEFAULT;
        b->fps = p->clips[i].fps, b->rows = p->clips[i].frames, b->fitted = p->clips[i].fitted;
        if (job->settings.root_motion == CB_ROOT_MOTION_KEEP && loop_travel_visible(p, &p->clips[i]))
            b->travel = p->clips[i].ground_speed * p->clips[i].duration;
        out->over_budget += b->over && !b->goal;
        out->over_goal += b->over && b->goal;
    }
    if (!out->over_budget || job->settings.allow_over_budget) return CB_OK;
    return cb_fail_setting(err, CB_ERR_VERIFY, CB_SETTING_ALLOW_OVER_BUDGET, "%s: %u of %u clip%s over its error budget "
                           "(max_error), each listed; nothing was written", job->model->source, out->over_budget,
                           p->clip_count, p->clip_count == 1 ? "" : "s");
}

/* A fixed fps is held to no budget unless max_error is given beside it; one that misses the
 * default max_error is still said, so a player's visible error is never a surprise. The rate that
 * would meet it is not searched for here: that search costs more than the fixed-rate bake itself
 * (25x on a 200-joint, 30-clip rig), and leaving fps out runs it and keeps its answer. */
static void warn_fixed_rates_over(const cb_bake_job *job, const cb_bake_result *out, cb_warnings *w)
{
    double budget = job->settings.max_error_mm;
    for (uint32_t i = 0; i < out->budget_count && budget > 0; ++i) {
        const cb_clip_settings *cs = &job->clip_settings[i];
        const cb_clip_budget *b = &out->budgets[i];
        if (cs->fps_auto || b->max_error_mm > 0 || !(b->error_mm > budget)) continue;
        const cb_clip_plan *one = &job->plan[i];
        char travel[160] = "";
        if (b->travel > 0)
            snprintf(travel, sizeof travel, " (no rate meets it: the loop's root travels %.3g units, which its wrap pulls "
                     "back; bake it in place: root_motion)", b->travel);
        cb_warn(w, "warning",
                "clip '%s' reaches %.3g mm/m at its fixed %g fps (%s), over max_error %g mm/m, which a fixed fps is not "
                "held to%s; leave fps out to have the rate chosen within max_error, or give max_error with the fps "
                "to hold it to one", one->name ? one->name : job->model->animations[one->animation].name, b->error_mm,
                b->fps, cb_setting_from_name(cs->from.fps), budget, travel);
    }
}

/* An error-bounded clip that met its budget baked alone can miss it in the palette by a hair:
 * u16 quantizes positions in the palette's box, wider than the clip's own (Fox's Walk: 0.996
 * mm/m alone, 1.0004 in the palette). Such clips are searched again, once, against their budget
 * less 1.5 times what the palette added; true when any was (the palette is then baked again). */
static bool replan_clips_over(cb_bake_job *job, cb_sampler *s, const cb_palette *p, cb_error *err)
{
    uint32_t n = job->plan_count;
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    cb_rate_choice *fresh = calloc(n ? n : 1, sizeof *fresh);
    bool any = false;
    for (uint32_t i = 0; goals && fresh && i < n && i < p->clip_count; ++i) {
        const cb_clip_settings *c = &job->clip_settings[i];
        double budget = c->max_error_mm, e = cb_mm_per_m(p->clips[i].visible_error, p->model_height);
        double tighter = budget - 1.5 * (e - job->rates[i].error_mm);
        if (!c->fps_auto || job->plan[i].step || !job->rates[i].met || !(e > budget) || !(tighter > 0)) continue;
        goals[i] = (cb_rate_goal){tighter, c->max_fps, CB_ROWS_BEST};
        any = true;
    }
    if (any) {
        cb_bake_options o = cb_bake_settings_options(&job->settings, first_format(job), &job->limits, job->threads);
        palette_choose_rates(s, &o, job->plan, n, goals, fresh, job->search_kept, NULL, err);
        for (uint32_t i = 0; i < n && !err->status; ++i)
            if (goals[i].max_error_mm > 0) job->rates[i] = fresh[i];
    }
    free(goals), free(fresh);
    return any;
}

/* The plan as baked: every clip at its resolved rate (the palette's "0: the options' fps" is for
 * callers without a job), into `baked` (plan_count entries). */
static void resolved_plan(const cb_bake_job *job, cb_clip_plan *baked)
{
    for (uint32_t i = 0; i < job->plan_count; ++i) baked[i] = job->plan[i], baked[i].fps = cb_bake_job_clip_fps(job, i);
}

cb_status cb_bake_job_run(cb_bake_job *job, cb_bake_result *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    if (check_outputs(job, err) || cb_bake_job_plan(job, err)) return err->status;
    /* Each clip's feet measured and each clip analyzed once for the whole run (the speed
     * reference, the palette, the per-row travel and the loop notes ask the same), freed with it. */
    foot_cache *feet;
    clip_memo *memo;
    double speed = 0;
    char why[sizeof job->speed_reference_from];
    const measured_travel *travel;
    bool beside = bake_beside_take(job->search_kept, &feet, &memo, &travel, &speed, why, sizeof why);
    if (!feet) {
        feet = foot_cache_create();
        foot_cache_screen_strides(feet); /* of a clip that does not stride, a bake reads only that it does not */
    }
    if (!memo) memo = clip_memo_create();
    cb_clip_plan *baked = malloc((job->plan_count ? job->plan_count : 1) * sizeof *baked);
    cb_sampler *s = baked ? cb_sampler_create(job->model, job->skin, err) : NULL;
    if (!baked) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    if (!s) return foot_cache_free(feet), clip_memo_free(memo), free(baked), err->status;
    /* The rate searches analyzed their clips: those analyses stand in for the run's */
    const search_keep *searched = job->search_kept;
    for (uint32_t i = 0; searched && i < searched->count; ++i) palette_memo_keep_search(memo, s, searched->poses[i], &job->limits);
    decide_speed_reference(job, feet, memo, beside, speed, why);
    cb_release_free_memory(); /* before the palette's buffers: the load's freed memory */
    cb_palette shared = {0}; /* the last palette baked, written again by a format of the same options */
    cb_bake_options shared_opt = {0};
    /* A lone uncompressed .pal is baked into its own file's payload, mapped: no copy to write,
     * and 29 MB less fresh memory on the big rig. (Other formats convert the texels as they
     * write them, and zstd compresses them: those bake into memory of their own.) */
    const char *pal_path = output_path(job, CB_FORMAT_PAL);
    cb_pal_mapping mapping;
    cb_pal_mapping_init(&mapping, pal_path, job->model, job->skin);
    bool mapped = job_formats(job) == CB_FORMAT_PAL && !job->settings.zstd, replanned = false;
    for (int f = 0; f < (int)cb_output_format_count() && !err->status; ++f) {
        unsigned format = cb_output_format_at((uint32_t)f)->format;
        if (!output_path(job, format)) continue;
        cb_bake_output *o = &out->outputs[out->output_count];
        o->format = format;
        o->path = output_path(job, format);
        cb_bake_options opt = cb_bake_settings_options(&job->settings, format, &job->limits, job->threads);
        /* (timed rows on: its rows are laid out again once baked, out of the mapping) */
        if (mapped && opt.bone_space == CB_BONE_SPACE_GLOBAL && opt.timed_rows != CB_TIMED_ROWS_ON)
            opt.texel_memory = (cb_texel_memory){cb_pal_map_texels, &mapping};
        /* A format without a map (timed rows off) takes no timed palette: its clips uniform at their cell rate */
        if (!shared.texels || shared_opt.precision != opt.precision || shared_opt.layout != opt.layout ||
            shared_opt.bone_space != opt.bone_space || (cb_palette_timed_clip(&shared) && opt.timed_rows == CB_TIMED_ROWS_OFF)) {
            cb_palette_free(&shared);
            search_keep *keep = job->search_kept; /* what the rate search sampled, and the skin's facts */
            palette_probe kept = {NULL, NULL, keep ? keep->poses : NULL, NULL, memo};
            resolved_plan(job, baked);
            if (palette_bake_with_facts(s, &opt, baked, job->plan_count, search_kept_facts(keep, s), &kept, &shared, err) ||
                bake_row_travel(job, feet, memo, s, travel, &shared, err))
                break;
            shared_opt = opt;
        }
        o->palette = shared; /* its facts; the tables and texels stay with `shared` */
        o->palette.clips = NULL, o->palette.bind_positions = NULL, o->palette.texels = NULL;
        o->palette.position_offsets = NULL, o->palette.row_travel = NULL, o->palette.parents = NULL, o->palette.bone_ranges = NULL;
        out->output_count++;
        o->input_hash = cb_bake_input_hash(job, &opt);
        if (out->output_count == 1 && !replanned && (replanned = true) && replan_clips_over(job, s, &shared, err)) {
            out->output_count = 0, --f; /* baked again with the clips' new rates */
            cb_palette_free(&shared);
            continue;
        }
        if (out->output_count == 1 && check_budgets(job, &shared, out, err)) {
            out->output_count = 0; /* nothing written */
            break;
        }
        if (out->output_count == 1)
            bake_notes(&opt, job->settings.from.root_motion, &shared, &out->notes), bake_travel_notes(&shared, &out->notes),
                bake_local_notes(job, &shared, &out->notes),
                bake_loop_notes(job, memo, s, &shared, &out->notes), warn_fixed_rates_over(job, out, &out->notes);
        ktx2_half_note(job, format, &opt, &out->notes);
        write_output(job, &shared, &mapping, o, err);
    }
    cb_pal_mapping_abort(&mapping); /* a bake that failed: its temporary */
    cb_palette_free(&shared);
    cb_sampler_free(s);
    foot_cache_free(feet);
    clip_memo_free(memo);
    free(baked); /* after the palette, which references it */
    return err->status;
}

void cb_bake_result_free(cb_bake_result *r)
{
    for (uint32_t i = 0; i < r->output_count; ++i) cb_palette_free(&r->outputs[i].palette);
    cb_warnings_free(&r->notes);
    free(r->budgets);
    memset(r, 0, sizeof *r);
}

void cb_bake_job_release_search(cb_bake_job *job) { free_search_kept(job); }

void cb_bake_job_free(cb_bake_job *job)
{
    free_search_kept(job);
    plant_feet_release(job);
    for (uint32_t i = 0; job->plan && i < job->plan_count; ++i) cb_clip_plan_release(&job->plan[i]);
    free(job->plan), free(job->rates), free(job->clip_settings);
    job->plan = NULL, job->rates = NULL, job->clip_settings = NULL;
    job->plan_count = 0;
    job->planned = false;
}
