/* roster.c - see roster.h. Three passes: prepare every type (load, plan clips, match states,
 * measure speeds, check LODs, hash the rig and clips) in parallel; let types with equal hashes
 * share one palette; bake the owners that are out of date in parallel. Then the manifest and
 * the depfile. Nothing that is written, the log included, depends on the thread count or on timing. */
#define _GNU_SOURCE /* open_memstream, strcasecmp */
#include "roster_cache.h"
#include "roster_files.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <threads.h>
#include <time.h>

#include "crowdbake/babylon.h"
#include "internal/plumbing.h"
#include "crowdbake/bake.h"
#include "crowdbake/gltf.h"
#include "crowdbake/pool.h"
#include "crowdbake/runtime.h"
#include "crowdbake/vat.h"
#include "internal/bake_words.h"

typedef struct type_work {
    const cb_model *model;    /* the catalog's copy (roster_models), shared with every type naming it */
    int32_t skin;
    cb_clip_plan *plan;       /* the catalog's clips, before their rates are planned */
    cb_clip_request *clip_requests; /* the catalog's clip entries */
    const cb_model **lod_models;
    cb_bake_job job;          /* job.plan: the clips with their rates */
    cb_output_path outputs[CB_OUTPUT_MAX]; /* the job's files */
    cb_bake_origin origin;
    unsigned char *record;    /* what preparing found, for the type's record (roster_cache.h) */
    size_t record_size;
    uint64_t record_key;
} type_work;

typedef struct roster_run {
    const cb_catalog *cat;
    const cb_roster_options *opt;
    cb_roster *r;
    type_work *work;
    atomic_uint next;
    mtx_t log_lock;
    roster_log log;           /* guarded by log_lock */
    double start;
    uint32_t threads_per_bake;
    roster_models models;     /* each model loaded once */
    roster_plans plans;       /* each plan worked out once (roster_plans.c) */
} roster_run;

static double now_seconds(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

const char *roster_at(const cb_catalog *cat, cb_source_pos pos, char *buf, size_t size)
{
    snprintf(buf, size, "%s:%u:%u", cat->path, pos.line, pos.column);
    return buf;
}

/* Appends a model's files to the type's inputs (for the depfile): its path even when it failed
 * to load (m NULL), so that fixing it makes the build out of date; its external files when it
 * loaded. */
static cb_status add_inputs(cb_roster_type *t, const char *path, const cb_model *m, cb_error *err)
{
    uint32_t externals = m ? m->external_file_count : 0;
    char **grown = realloc(t->inputs, (t->input_count + 1 + externals) * sizeof *grown);
    if (!grown) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    t->inputs = grown;
    for (uint32_t i = 0; i <= externals; ++i) {
        if (!(t->inputs[t->input_count] = strdup(i ? m->external_files[i - 1] : path)))
            return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        ++t->input_count;
    }
    return CB_OK;
}

/* ---- pass 1: prepare a type ---- */

static int pick_skin(const cb_model *m)
{
    for (uint32_t s = 0; s < m->skin_count; ++s)
        if (cb_model_skin_vertex_count(m, (int32_t)s) > 0) return (int)s;
    return m->skin_count ? 0 : -1;
}

/* A clip's per-row travel as its bake will decide it: the manifest says it, the bake ships it. */
static cb_status row_travel(const cb_bake_job *job, cb_sampler *s, const cb_clip_info *info, cb_row_travel *out,
                            cb_error *err)
{
    float *offsets = malloc((info->frames ? info->frames : 1) * sizeof *offsets);
    if (!offsets) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    cb_bake_job_row_travel(job, s, info, offsets, out);
    free(offsets);
    return CB_OK;
}

/* The animation LOD's cost over the type's clips, every frame at ROSTER_LOD_FPS: a vertex's
 * error under fewer influences changes with the pose as smoothly as the pose does, so 30 frames a
 * second find its worst within a few percent of 60's (Cow, Husky), for about 0.07 s a type. */
enum { ROSTER_LOD_FPS = 30 };

static void measure_lod_error(cb_sampler *s, const cb_bake_job *job, cb_roster_type *t, cb_error *err)
{
    int32_t *animations = malloc((t->clip_count ? t->clip_count : 1) * sizeof *animations);
    if (!animations) {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        return;
    }
    for (uint32_t i = 0; i < t->clip_count; ++i) animations[i] = job->plan[i].animation;
    if (t->clip_count) cb_measure_lod_error(s, ROSTER_LOD_FPS, animations, t->clip_count, &t->lod_error, err);
    free(animations);
}

static cb_status analyze_clips(const cb_limits *limits, type_work *w, cb_roster_type *t, cb_error *err)
{
    /* The job's model: with plant_feet, the copy whose planted clips' legs were turned (what the
     * palette holds, so the manifest's ground speed and slide are of the feet as baked). */
    cb_sampler *s = cb_sampler_create(w->job.model, w->skin, err);
    if (!s) return err->status;
    uint32_t row = 0;
    for (uint32_t i = 0; i < t->clip_count && !err->status; ++i) {
        cb_clip_info info;
        const cb_clip_plan *plan = &w->job.plan[i];
        if (cb_clip_analyze(s, plan->animation, cb_bake_job_clip_fps(&w->job, i), plan->loop, limits, &info, err)) break;
        cb_roster_clip *c = &t->clips[i];
        snprintf(c->name, sizeof c->name, "%s", plan->name);
        if (plan->timed_rows) { /* rows on its keys (qpos rows, local or global), its map before them */
            c->cells = info.loops ? info.frames : info.frames - 1, c->cell_rate = cb_bake_job_clip_fps(&w->job, i);
            c->map_rows = cb_timed_map_rows(c->cells, w->job.model->skins[w->skin].joint_count *
                                                          cb_layout_texels_per_bone(CB_LAYOUT_QPOS));
            row += c->map_rows;
        }
        c->first_row = row;
        c->frames = plan->timed_rows ? plan->timed_rows : info.frames;
        c->fps = plan->timed_rows && info.duration > 0 ? c->frames / info.duration : info.effective_fps;
        c->duration = info.duration;
        c->loops = info.loops, c->step = plan->step;
        c->in_place = cb_root_motion_in_place(w->job.settings.root_motion, &info);
        c->visible_error_mm = -1; /* the bake measures it */
        cb_loop_reason_text(&info, c->loop_reason, sizeof c->loop_reason);
        cb_bake_clip_reason(&w->job, i, c->rate_reason, sizeof c->rate_reason); /* while its search is at hand */
        cb_measure_ground_speed(s, &info, &c->speed);
        if (row_travel(&w->job, s, &info, &c->travel, err)) break;
        row += c->frames;
    }
    t->rows = row;
    double lo[3], hi[3];
    if (!err->status) t->model_height = cb_skin_rest_bounds(s, lo, hi);
    if (!err->status) t->socket_count = cb_find_sockets(s, &t->sockets);
    if (!err->status) measure_lod_error(s, &w->job, t, err);
    cb_sampler_free(s);
    return err->status;
}

static cb_status check_lods(roster_run *run, const cb_catalog_animal *an, type_work *w, cb_roster_type *t,
                            cb_error *err)
{
    t->lod_count = an->lod_count;
    t->lods = calloc(an->lod_count ? an->lod_count : 1, sizeof *t->lods);
    w->lod_models = calloc(an->lod_count ? an->lod_count : 1, sizeof *w->lod_models);
    if (!t->lods || !w->lod_models) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    char where[1100];
    for (uint32_t i = 0; i < an->lod_count; ++i) {
        cb_error inner = {0};
        const cb_model *lod = w->lod_models[i] = roster_model_get(&run->models, an->lods[i], &inner);
        if (add_inputs(t, an->lods[i], lod, err)) return err->status;
        int skin = lod ? pick_skin(lod) : -1;
        if (lod && skin < 0) cb_fail(&inner, CB_ERR_INPUT, "%s: has no skin", an->lods[i]);
        cb_roster_lod *l = &t->lods[i];
        if (!inner.status) {
            l->path = an->lods[i];
            l->joint_count = lod->skins[skin].joint_count;
            l->remap = calloc(l->joint_count, sizeof *l->remap);
            l->vertices = cb_model_skin_vertex_count(lod, skin);
            for (uint32_t p = 0; p < lod->primitive_count; ++p) l->indices += lod->primitives[p].index_count;
            if (!l->remap) cb_fail(&inner, CB_ERR_INTERNAL, "out of memory");
            else cb_lod_remap(w->model, w->skin, lod, skin, l->remap, &inner);
        }
        if (inner.status)
            return cb_fail_setting(err, inner.status, inner.setting, "%s: [animal.%s] LOD %u: %s",
                                   roster_at(run->cat, an->lod_pos[i], where, sizeof where), an->name, i, inner.message);
    }
    return CB_OK;
}

/* The error a VAT of the same frames would have: half-float positions against exact skinning. */
static void measure_vat(const cb_catalog_animal *an, const cb_limits *limits, type_work *w, cb_roster_type *t)
{
    cb_bake_options o = cb_bake_settings_options(&an->bake, CB_FORMAT_PAL, limits, 1);
    o.max_texture_size = 1u << 30; /* only measured: no texture is made */
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(w->model, w->skin, &err);
    cb_vat vat = {0};
    if (s && !cb_vat_bake(s, &o, w->job.plan, t->clip_count, false, &vat, &err)) t->vat_error = vat.max_error;
    cb_vat_free(&vat);
    cb_sampler_free(s);
}

static void output_paths(const cb_catalog_animal *an, cb_roster_type *t)
{
    for (uint32_t k = 0; k < cb_output_format_count(); ++k)
        snprintf(t->paths[k], sizeof t->paths[k], "%s/%s%s", an->bake.out_dir, an->name, cb_output_format_at(k)->extension);
}

/* A type that failed before its LODs were loaded still lists them: they are its inputs. */
static void list_unloaded_lods(const cb_catalog_animal *an, const type_work *w, cb_roster_type *t)
{
    for (uint32_t l = 0; !w->lod_models && l < an->lod_count; ++l)
        if (add_inputs(t, an->lods[l], NULL, &t->error)) break;
}

/* The type's bake job (bake.h): its clips, settings and outputs, not yet planned. */
static void set_up_job(const roster_run *run, const cb_catalog_animal *an, type_work *w, const cb_roster_type *t)
{
    cb_bake_job *job = &w->job;
    cb_bake_job_init(job);
    job->model = w->model, job->skin = w->skin;
    job->clips = w->plan, job->clip_count = t->clip_count, job->clip_requests = w->clip_requests;
    job->settings = an->bake;
    job->limits = run->opt->limits ? *run->opt->limits : cb_default_limits();
    job->outputs = w->outputs, job->output_count = 0;
    for (uint32_t k = 0; k < cb_output_format_count(); ++k)
        if (an->bake.formats & cb_output_format_at(k)->format)
            w->outputs[job->output_count++] = (cb_output_path){cb_output_format_at(k)->format, t->paths[k]};
    job->threads = run->threads_per_bake; /* clips whose rates are searched at once */
}

/* What sampling the planned clips found, as the type holds it. */
static roster_plan_facts facts_of(const cb_roster_type *t)
{
    return (roster_plan_facts){t->clip_count, t->rows, t->clips, t->model_height, t->socket_count, t->sockets,
                               t->vat_measured, t->vat_error, t->lod_error};
}

static void take_facts(cb_roster_type *t, const roster_plan_facts *f)
{
    free(t->clips), free(t->sockets);
    t->clips = f->clips, t->rows = f->rows, t->model_height = f->model_height;
    t->socket_count = f->socket_count, t->sockets = f->sockets;
    t->vat_measured = f->vat_measured, t->vat_error = f->vat_error;
    t->lod_error = f->lod_error;
}

/* The job planned (its clips with fps = "auto" get their rates) and its clips sampled for the
 * manifest (and the report's VAT error), once per plan key (roster_plans.c): a type whose key
 * another type planned copies what that one found, so types that share a palette cost one
 * planning between them. */
static cb_status plan_and_sample(roster_run *run, const cb_catalog_animal *an, type_work *w, cb_roster_type *t,
                                 cb_error *err)
{
    set_up_job(run, an, w, t);
    uint64_t key = roster_plan_key(w->model, w->skin, w->plan, w->clip_requests, t->clip_count, &an->bake);
    /* A job that plants feet samples the planted copy of the model its own planning makes: it plans alone. */
    roster_plan *memo = an->bake.plant_feet ? NULL : roster_plan_claim(&run->plans, key);
    roster_plan_facts facts;
    if (roster_plan_copy(memo, &w->job, &facts)) {
        take_facts(t, &facts);
    } else if (!cb_bake_job_plan(&w->job, err) && !analyze_clips(run->opt->limits, w, t, err)) {
        if (run->opt->measure_vat) measure_vat(an, run->opt->limits, w, t), t->vat_measured = true;
        facts = facts_of(t);
        roster_plan_keep(memo, &w->job, &facts);
    }
    roster_plan_release(memo);
    return err->status;
}

/* Preparing from the model: load, plan, sample what the manifest states, hash. */
static void prepare_from_model(roster_run *run, uint32_t i)
{
    const cb_catalog_animal *an = &run->cat->animals[i];
    cb_roster_type *t = &run->r->types[i];
    type_work *w = &run->work[i];
    cb_error *err = &t->error;
    char where[1100];
    cb_error inner = {0};
    w->model = roster_model_get(&run->models, an->model, &inner);
    if (add_inputs(t, an->model, w->model, err)) return;
    if (!w->model) {
        cb_fail_setting(err, inner.status, inner.setting, "%s: [animal.%s] %s", roster_at(run->cat, an->model_pos, where, sizeof where),
                        an->name, inner.message);
        list_unloaded_lods(an, w, t);
        return;
    }
    w->skin = pick_skin(w->model);
    if (w->skin < 0) {
        cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] %s has no skin to bake", roster_at(run->cat, an->model_pos, where, sizeof where),
                an->name, an->model);
        list_unloaded_lods(an, w, t);
        return;
    }
    cb_model_warnings(w->model, !an->clips, &t->warnings);
    t->bones = w->model->skins[w->skin].joint_count;
    t->vertices = cb_model_skin_vertex_count(w->model, w->skin);
    t->mesh_bytes = cb_model_skin_mesh_bytes(w->model, w->skin);
    for (uint32_t p = 0; p < w->model->primitive_count; ++p)
        if (w->model->primitives[p].skin == w->skin) t->indices += w->model->primitives[p].index_count;
    if (roster_plan_clips(run->cat, an, w->model, &w->plan, &w->clip_requests, t, err) || plan_and_sample(run, an, w, t, err) ||
        roster_match_states(run->cat, an, t, err) ||
        roster_decide_states(run->cat, an, t, err) || check_lods(run, an, w, t, err)) {
        list_unloaded_lods(an, w, t);
        return;
    }
    roster_warn_foot_slide(t);
    roster_note_planted(&w->job, t);
    t->key = roster_content_key(w->model, w->skin, w->job.plan, t->clip_count, &an->bake);
    w->origin = (cb_bake_origin){t->key, an->canonical, (const cb_model *const *)w->lod_models, an->lod_count};
    w->job.origin = &w->origin;
    t->input_hash = cb_bake_input_hash(&w->job, NULL);
    /* The rate search's poses would save the bake one sampling pass, but held by every type
     * waiting to bake they made a roster's memory grow with its types: only the plan is kept. */
    cb_bake_job_release_search(&w->job);
    uint64_t key;
    if (cb_prep_key(an, run->opt->limits, t->inputs, t->input_count, &key))
        cb_prep_record_encode(t, key, &w->record, &w->record_size), w->record_key = key;
}

/* The per-clip errors a record holds (NULL: out of memory), for a type prepared again from its
 * model while its palette stays up to date: only a bake measures them. */
static double *kept_clip_errors(const cb_roster_type *t)
{
    double *e = malloc((t->clip_count ? t->clip_count : 1) * sizeof *e);
    for (uint32_t c = 0; e && c < t->clip_count; ++c) e[c] = t->clips[c].visible_error_mm;
    return e;
}

/* A type's record, when it matches its files, stands in for loading and sampling: an
 * up-to-date type then costs the hashing of its files and the check of its palette. */
static void prepare_type(roster_run *run, uint32_t i)
{
    const cb_catalog_animal *an = &run->cat->animals[i];
    cb_roster_type *t = &run->r->types[i];
    t->animal = an;
    t->owner = i;
    output_paths(an, t);
    char path[4096];
    bool from_record = !run->opt->force && cb_prep_record_path(an, path, sizeof path) &&
                       cb_prep_record_load(path, an, run->opt->limits, t);
    double *clip_errors = NULL; /* the bake's per-clip errors, which preparing from the model cannot know */
    uint64_t record_key = t->key;
    if (from_record && run->opt->measure_vat && !t->vat_measured) { /* a report needs the VAT error too */
        clip_errors = kept_clip_errors(t);
        cb_prep_clear(t);
        from_record = false;
    }
    if (from_record) {
        if (!roster_decide_states(run->cat, an, t, &t->error)) {
            t->prepared_from_record = true;
            return;
        }
        cb_prep_clear(t); /* out of memory: prepared again from the model */
        t->error = (cb_error){0};
    }
    prepare_from_model(run, i);
    for (uint32_t c = 0; clip_errors && t->key == record_key && c < t->clip_count; ++c)
        if (t->clips[c].visible_error_mm < 0) t->clips[c].visible_error_mm = clip_errors[c];
    free(clip_errors);
}

/* What preparing a type kept, once it is baked or settled (its model stays: other types share it). */
static void free_work(type_work *w)
{
    cb_bake_job_free(&w->job);
    cb_bake_job_init(&w->job);
    free(w->plan), free(w->clip_requests), free(w->lod_models), free(w->record);
    w->plan = NULL, w->clip_requests = NULL, w->lod_models = NULL, w->record = NULL;
}

/* ---- pass 3: bake an owner ---- */

static uint64_t file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
}

static cb_status bake_files(roster_run *run, const cb_catalog_animal *an, type_work *w, cb_roster_type *t, cb_error *err)
{
    w->job.threads = run->threads_per_bake;
    w->job.speed_reference = t->speed_reference;
    if (roster_make_directories(an->bake.out_dir, err)) return err->status;
    cb_babylon_state *states = roster_babylon_states(an, t); /* the .bvat.json lists them */
    if (!states) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    w->job.babylon_states = states, w->job.babylon_state_count = an->state_count;
    cb_bake_result r;
    cb_bake_job_run(&w->job, &r, err);
    free(states);
    w->job.babylon_states = NULL;
    if (r.output_count) {
        const cb_palette *p = &r.outputs[0].palette;
        t->width = p->width, t->height = p->height, t->blocks = p->blocks;
        t->layout = p->layout, t->precision = p->precision;
        t->max_error = (float)p->max_error;
        t->visible_error = (float)p->visible_error;
        t->error_rows_measured = p->error_rows_measured;
        t->palette_bytes = p->texel_bytes;
    }
    for (uint32_t i = 0; i < r.budget_count && i < t->clip_count; ++i) t->clips[i].visible_error_mm = r.budgets[i].error_mm;
    for (uint32_t i = 0; i < r.notes.count; ++i) cb_warn(&t->warnings, r.notes.items[i].kind, "%s", r.notes.items[i].message);
    cb_bake_budget_notes(&w->job, &r, NULL, &t->warnings); /* in the catalog's words */
    cb_bake_result_free(&r);
    return err->status;
}

/* "[done/all] name: outcome", as each type is done (cb_roster_options.progress). */
static void progress_line(roster_run *run, const cb_roster_type *t)
{
    FILE *f = run->opt->progress;
    if (!f) return;
    mtx_lock(&run->log_lock);
    const cb_roster *r = run->r;
    fprintf(f, "crowdbake: [%u/%u] %s: ", r->baked + r->up_to_date + r->shared + r->failed, r->type_count, t->animal->name);
    if (t->outcome == CB_TYPE_BAKED) fprintf(f, "baked %u rows in %.0f ms\n", t->rows, t->seconds * 1000);
    else if (t->outcome == CB_TYPE_SHARED) fprintf(f, "shares %s's palette\n", r->types[t->owner].animal->name);
    else fprintf(f, "%s\n", t->outcome == CB_TYPE_UP_TO_DATE ? "up to date" : "failed");
    fflush(f), mtx_unlock(&run->log_lock);
}

/* The type's lines, printed in catalog order (roster_log); on a terminal, the progress after them. */
static void log_type(roster_run *run, const cb_roster_type *t)
{
    progress_line(run, t);
    if (!run->opt->log) return;
    mtx_lock(&run->log_lock);
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) f = run->opt->log; /* no memory: as it comes */
    const char *clear = run->opt->tty ? "\r\033[K" : "";
    const cb_roster_type *owner = &run->r->types[t->owner];
    switch (t->outcome) {
    case CB_TYPE_BAKED: {
        char subset[64] = ""; /* past the measuring budget: say so (measure_all = true measures every row) */
        if (t->error_rows_measured && t->error_rows_measured < t->rows)
            snprintf(subset, sizeof subset, ", measured at %u of %u rows", t->error_rows_measured, t->rows);
        /* the palette's file named; both sizes as `bake MODEL` gives them */
        fprintf(f, "%s  %-16s baked    %s (%.1f KiB texture, %.1f KiB file, %ux%u, %s/%s, encoding error %.3g mm/m, "
                "visible %.3g mm/m%s) in %.0f ms\n", clear, t->animal->name, roster_palette_path(t),
                t->palette_bytes / 1024.0, t->file_bytes / 1024.0, t->width, t->height,
                cb_layout_name(t->layout), cb_precision_name(t->precision),
                cb_mm_per_m(t->max_error, t->model_height), cb_mm_per_m(t->visible_error, t->model_height), subset,
                t->seconds * 1000);
        break;
    }
    case CB_TYPE_UP_TO_DATE: fprintf(f, "%s  %-16s up to date\n", clear, t->animal->name); break;
    case CB_TYPE_SHARED:
        fprintf(f, "%s  %-16s shares %s's palette (same rig, bind pose and clips)\n", clear, t->animal->name,
                owner->animal->name);
        break;
    case CB_TYPE_FAILED: {
        const char *fix = run->opt->setting_name && t->error.setting ? run->opt->setting_name(t->error.setting) : NULL;
        fprintf(f, "%s  %-16s FAILED: %s%s%s%s\n", clear, t->animal->name, t->error.message, fix ? " [" : "",
                fix ? fix : "", fix ? "]" : "");
        break;
    }
    }
    for (uint32_t i = 0; i < t->warnings.count; ++i)
        fprintf(f, "  %-16s %s: %s\n", "", t->warnings.items[i].kind, t->warnings.items[i].message);
    if (f != run->opt->log) fclose(f);
    else text = NULL;
    roster_log_put(&run->log, (uint32_t)(t - run->r->types), text);
    f = run->opt->log;
    if (run->opt->tty)
        fprintf(f, "\r\033[K  [%u/%u done, %.1f s]", run->r->baked + run->r->up_to_date + run->r->shared + run->r->failed,
                run->r->type_count, now_seconds() - run->start);
    fflush(f);
    mtx_unlock(&run->log_lock);
}

/* Saves the record of a type prepared from its model (unless the file holds it already); a
 * record that cannot be written only costs the next run the preparation. */
static void write_record(roster_run *run, uint32_t i)
{
    type_work *w = &run->work[i];
    const cb_roster_type *t = &run->r->types[i];
    char path[4096];
    if (w->record && t->outcome == CB_TYPE_BAKED) { /* again, with what the bake measured (each clip's error) */
        free(w->record), w->record = NULL;
        cb_prep_record_encode(t, w->record_key, &w->record, &w->record_size);
    }
    if (w->record && cb_prep_record_path(run->r->types[i].animal, path, sizeof path))
        roster_write_record(path, w->record, w->record_size);
}

static void bake_type(roster_run *run, uint32_t i)
{
    cb_roster_type *t = &run->r->types[i];
    const cb_catalog_animal *an = t->animal;
    double t0 = now_seconds();
    if (t->error.status) {
        t->outcome = CB_TYPE_FAILED;
    } else if (t->owner != i) {
        return; /* shared types are settled once their owner is */
    } else {
        if (!run->opt->force && roster_outputs_up_to_date(t, an->bake.formats)) {
            t->outcome = CB_TYPE_UP_TO_DATE;
        } else {
            if (t->prepared_from_record) { /* the palette is not: bake it from the model */
                cb_prep_clear(t);
                t->prepared_from_record = false;
                prepare_from_model(run, i);
            }
            t->outcome = t->error.status || bake_files(run, an, &run->work[i], t, &t->error) ? CB_TYPE_FAILED : CB_TYPE_BAKED;
        }
        if (t->outcome != CB_TYPE_FAILED) write_record(run, i);
        free_work(&run->work[i]);
        t->file_bytes = file_size(roster_palette_path(t));
    }
    t->seconds = now_seconds() - t0;
    mtx_lock(&run->log_lock);
    if (t->outcome == CB_TYPE_BAKED) run->r->baked++;
    else if (t->outcome == CB_TYPE_UP_TO_DATE) run->r->up_to_date++;
    else run->r->failed++;
    mtx_unlock(&run->log_lock);
    log_type(run, t);
}

/* ---- parallel passes ---- */

typedef struct pass {
    roster_run *run;
    void (*fn)(roster_run *, uint32_t);
    const uint32_t *order; /* the types, longest first (roster_order.c) */
} pass;

/* Each share takes the next type until none is left (types take very different times), on the
 * library's threads (cb_pool_run): the calling thread and threads - 1 more. */
static void pass_share(void *arg, uint32_t thread, uint32_t threads)
{
    (void)thread, (void)threads;
    pass *p = arg;
    for (uint32_t i; (i = atomic_fetch_add(&p->run->next, 1)) < p->run->r->type_count;) p->fn(p->run, p->order[i]);
}

static void run_pass(roster_run *run, void (*fn)(roster_run *, uint32_t), uint32_t *order)
{
    uint32_t threads = run->opt->jobs ? run->opt->jobs : 1;
    if (threads > run->r->type_count) threads = run->r->type_count ? run->r->type_count : 1;
    for (uint32_t i = 0; i < run->r->type_count; ++i) order[i] = i; /* one thread: catalog order */
    if (threads > 1) roster_order_types(run->cat, run->r, fn == bake_type, order); /* changes no output */
    atomic_store(&run->next, 0);
    pass p = {run, fn, order};
    cb_pool_run(threads, pass_share, &p);
}

/* ---- the whole bake ---- */

cb_status cb_roster_bake(const cb_catalog *cat, const cb_roster_options *opt, cb_roster *r, cb_error *err)
{
    memset(r, 0, sizeof *r);
    r->catalog = cat;
    r->type_count = cat->animal_count;
    r->types = calloc(cat->animal_count ? cat->animal_count : 1, sizeof *r->types);
    roster_run run;
    memset(&run, 0, sizeof run);
    run.cat = cat, run.opt = opt, run.r = r, run.start = now_seconds();
    run.work = calloc(cat->animal_count ? cat->animal_count : 1, sizeof(type_work));
    uint32_t *order = calloc(cat->animal_count ? cat->animal_count : 1, sizeof *order);
    roster_log_init(&run.log, opt->log, r->type_count); /* without memory, lines print as they come */
    if (!r->types || !run.work || !order || !roster_models_init(&run.models, cat, opt->limits) ||
        !roster_plans_init(&run.plans, cat->animal_count) ||
        mtx_init(&run.log_lock, mtx_plain) != thrd_success) {
        free(run.work), free(order), roster_log_free(&run.log), roster_models_free(&run.models);
        roster_plans_free(&run.plans);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    /* Types are the unit of parallel work; fewer types than threads spread their clips too. */
    run.threads_per_bake = cat->animal_count && opt->jobs > cat->animal_count ? opt->jobs / cat->animal_count : 1;
    run_pass(&run, prepare_type, order);
    roster_assign_owners(r);
    run_pass(&run, bake_type, order);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        cb_roster_type *t = &r->types[i];
        if (t->owner == i || t->error.status) continue;
        if (roster_settle_shared(r, i)) write_record(&run, i);
        free_work(&run.work[i]);
        log_type(&run, t);
    }
    if (opt->log && opt->tty) fputs("\r\033[K", opt->log);
    if (opt->fragment) snprintf(r->manifest_path, sizeof r->manifest_path, "%s", opt->fragment->path);
    else if (opt->manifest) snprintf(r->manifest_path, sizeof r->manifest_path, "%s", opt->manifest);
    else snprintf(r->manifest_path, sizeof r->manifest_path, "%s/roster.json", cat->defaults.out_dir);
    cb_status rc = roster_make_parent_directories(r->manifest_path, err);
    if (!rc && opt->fragment) rc = roster_write_fragment(r, opt->fragment, err);
    else if (!rc) rc = roster_write_manifest(cat, r, r->manifest_path, err);
    if (!rc && opt->depfile && !(rc = roster_make_parent_directories(opt->depfile, err))) rc = roster_write_depfile(cat, r, opt, err);
    if (!rc) roster_settle_times(r, opt->tool);
    for (uint32_t i = 0; i < r->type_count && !rc; ++i)
        if (r->types[i].outcome == CB_TYPE_FAILED && !err->status) *err = r->types[i].error, rc = err->status;
    for (uint32_t i = 0; i < r->type_count; ++i) free_work(&run.work[i]);
    roster_models_free(&run.models);
    roster_plans_free(&run.plans);
    free(run.work), free(order), roster_log_free(&run.log);
    mtx_destroy(&run.log_lock);
    return rc;
}

void cb_roster_free(cb_roster *r)
{
    for (uint32_t i = 0; i < r->type_count; ++i) {
        free(r->types[i].clips);
        free(r->types[i].state_clip);
        free(r->types[i].state_sync);
        for (uint32_t l = 0; l < r->types[i].lod_count; ++l) free(r->types[i].lods[l].remap);
        free(r->types[i].lods);
        free(r->types[i].sockets);
        for (uint32_t k = 0; k < r->types[i].input_count; ++k) free(r->types[i].inputs[k]);
        free(r->types[i].inputs);
        cb_warnings_free(&r->types[i].warnings);
    }
    free(r->types);
    memset(r, 0, sizeof *r);
}
