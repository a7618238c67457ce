/* roster_plans.c - see roster_files.h: a type's planned rates and what sampling its clips found,
 * worked out once per plan key (the model's bytes, the skin, the clips asked for and the bake
 * settings). Types with equal plan keys bake the same palette: the first to need the plan works
 * it out, the others copy it. A roster's time then follows its distinct palettes, not its types
 * (issue 46). Nothing that is written depends on which type worked it out: equal keys give
 * bit-equal plans, the planning being deterministic. */
#include "roster_files.h"
#include "internal/bake_words.h"

#include <stdlib.h>
#include <string.h>

#include "crowdbake_pal.h" /* XXH64 */

struct roster_plan {
    uint64_t key;
    mtx_t lock;              /* held while one type works it out: the others wait, then copy */
    bool done;               /* a type worked it out without error (a failure is not kept: each type fails alone) */
    uint32_t plan_count;
    cb_clip_plan *plan;      /* the job's planned clips (names: the first type's, equal by the key) */
    cb_rate_choice *rates;
    cb_clip_settings *clip_settings;
    cb_root_motion root_motion; /* decided by the plan (decide_root_motion) */
    cb_setting_from root_motion_from;
    roster_plan_facts facts; /* clips, rows, height, sockets, VAT error */
};

static void hash_str(cbpal_xxh64_state *h, const char *s)
{
    static const char none[] = "\x01(none)";
    if (!s) s = none;
    cbpal_xxh64_update(h, s, strlen(s) + 1);
}

static void hash_double(cbpal_xxh64_state *h, double v) { cbpal_xxh64_update(h, &v, sizeof v); }

/* Every setting the planning reads, field by field (the struct's padding and out_dir left out:
 * where a palette is written does not change it). */
static void hash_settings(cbpal_xxh64_state *h, const cb_bake_settings *b)
{
    double v[] = {b->fps, b->fps_auto, b->max_error_mm, b->max_error_given, b->max_fps, b->allow_over_budget,
                  b->layout, b->precision, b->formats, b->max_texture_size, b->root_motion, b->layout_set,
                  b->precision_set, b->zstd, b->exr_compression, b->fit_rows, b->measure_all,
                  b->from.fps, b->from.max_error, b->from.max_fps, b->from.fit_rows, b->from.root_motion,
                  b->plant_feet, b->row_travel_off, cb_bake_settings_bone_space(b, CB_FORMAT_PAL), b->timed_rows};
    cbpal_xxh64_update(h, v, sizeof v); /* (the bone space: local rows' rates are their own) */
}

uint64_t roster_plan_key(const cb_model *m, int32_t skin, const cb_clip_plan *plan, const cb_clip_request *requests,
                         uint32_t n, const cb_bake_settings *b)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    hash_str(&h, "crowdbake plan " CROWDBAKE_VERSION);
    cbpal_xxh64_update(&h, &m->source_hash, sizeof m->source_hash); /* the model's file and its external files */
    hash_double(&h, skin);
    hash_double(&h, n);
    hash_settings(&h, b);
    for (uint32_t i = 0; i < n; ++i) {
        hash_str(&h, plan[i].name);
        double v[] = {plan[i].animation, plan[i].loop, plan[i].fps, plan[i].fit, plan[i].step,
                      requests ? requests[i].fps_auto : -2, requests ? requests[i].max_error_mm : -2};
        cbpal_xxh64_update(&h, v, sizeof v);
    }
    return cbpal_xxh64_digest(&h);
}

bool roster_plans_init(roster_plans *ps, uint32_t capacity)
{
    memset(ps, 0, sizeof *ps);
    ps->items = calloc(capacity ? capacity : 1, sizeof *ps->items);
    ps->capacity = capacity;
    if (ps->items && mtx_init(&ps->lock, mtx_plain) == thrd_success) return true;
    free(ps->items);
    ps->items = NULL;
    return false;
}

roster_plan *roster_plan_claim(roster_plans *ps, uint64_t key)
{
    roster_plan *p = NULL;
    mtx_lock(&ps->lock);
    for (uint32_t i = 0; i < ps->count && !p; ++i)
        if (ps->items[i].key == key) p = &ps->items[i];
    if (!p && ps->count < ps->capacity && mtx_init(&ps->items[ps->count].lock, mtx_plain) == thrd_success) {
        p = &ps->items[ps->count++];
        p->key = key;
    }
    mtx_unlock(&ps->lock);
    if (p) mtx_lock(&p->lock);
    return p; /* NULL: no room or no mutex - the type plans alone */
}

void roster_plan_release(roster_plan *p)
{
    if (p) mtx_unlock(&p->lock);
}

static void *copy_of(const void *from, size_t size)
{
    void *to = malloc(size ? size : 1);
    if (to && size) memcpy(to, from, size);
    return to;
}

static void free_facts(roster_plan_facts *f)
{
    free(f->clips), free(f->sockets);
    f->clips = NULL, f->sockets = NULL;
}

/* Each entry's timed rows' cells copied (plans are copied whole: each copy owns its cells);
 * false: out of memory (those not copied left uniform, the plan unusable). */
static bool copy_cells(cb_clip_plan *plan, uint32_t n)
{
    bool ok = true;
    for (uint32_t i = 0; plan && i < n; ++i) {
        if (!plan[i].row_cells) continue;
        uint32_t *cells = copy_of(plan[i].row_cells, plan[i].timed_rows * sizeof *cells);
        plan[i].row_cells = cells, plan[i].timed_rows = cells ? plan[i].timed_rows : 0;
        ok = ok && cells;
    }
    return ok;
}

static void release_cells(cb_clip_plan *plan, uint32_t n)
{
    for (uint32_t i = 0; plan && i < n; ++i) cb_clip_plan_release(&plan[i]);
}

static void free_plan(roster_plan *p)
{
    release_cells(p->plan, p->plan_count);
    free(p->plan), free(p->rates), free(p->clip_settings);
    p->plan = NULL, p->rates = NULL, p->clip_settings = NULL;
    free_facts(&p->facts);
    p->done = false;
}

/* The facts with their arrays copied (false: out of memory, nothing kept). */
static bool copy_facts(roster_plan_facts *to, const roster_plan_facts *from)
{
    *to = *from;
    to->clips = copy_of(from->clips, from->clip_count * sizeof *from->clips);
    to->sockets = from->sockets ? copy_of(from->sockets, from->socket_count * sizeof *from->sockets) : NULL;
    if (to->clips && (to->sockets || !from->sockets)) return true;
    free_facts(to);
    return false;
}

void roster_plan_keep(roster_plan *p, const cb_bake_job *job, const roster_plan_facts *facts)
{
    if (!p || p->done) return;
    uint32_t n = job->plan_count;
    p->plan_count = n;
    p->plan = copy_of(job->plan, n * sizeof *job->plan);
    bool cells = copy_cells(p->plan, n);
    p->rates = copy_of(job->rates, n * sizeof *job->rates);
    p->clip_settings = copy_of(job->clip_settings, n * sizeof *job->clip_settings);
    p->root_motion = job->settings.root_motion, p->root_motion_from = job->settings.from.root_motion;
    p->done = p->plan && cells && p->rates && p->clip_settings && copy_facts(&p->facts, facts);
    if (!p->done) free_plan(p); /* out of memory: the next type plans alone */
}

bool roster_plan_known(const roster_plan *p) { return p && p->done; }

bool roster_plan_copy(const roster_plan *p, cb_bake_job *job, roster_plan_facts *facts)
{
    if (!roster_plan_known(p) || (job->clips ? job->clip_count : job->model->animation_count) != p->plan_count) return false;
    cb_clip_plan *plan = copy_of(p->plan, p->plan_count * sizeof *p->plan);
    bool cells = copy_cells(plan, plan ? p->plan_count : 0);
    cb_rate_choice *rates = copy_of(p->rates, p->plan_count * sizeof *p->rates);
    cb_clip_settings *settings = copy_of(p->clip_settings, p->plan_count * sizeof *p->clip_settings);
    if (!plan || !cells || !rates || !settings || !copy_facts(facts, &p->facts)) {
        release_cells(plan, plan ? p->plan_count : 0);
        free(plan), free(rates), free(settings);
        return false;
    }
    for (uint32_t i = 0; i < p->plan_count && job->clips; ++i) plan[i].name = job->clips[i].name; /* its own (equal) names */
    release_cells(job->plan, job->plan_count);
    free(job->plan), free(job->rates), free(job->clip_settings);
    job->plan = plan, job->rates = rates, job->clip_settings = settings;
    job->plan_count = p->plan_count;
    job->settings.root_motion = p->root_motion, job->settings.from.root_motion = p->root_motion_from;
    job->planned = true;
    return true;
}

void roster_plans_free(roster_plans *ps)
{
    for (uint32_t i = 0; i < ps->count; ++i) {
        free_plan(&ps->items[i]);
        mtx_destroy(&ps->items[i].lock);
    }
    if (ps->items) mtx_destroy(&ps->lock);
    free(ps->items);
    memset(ps, 0, sizeof *ps);
}
