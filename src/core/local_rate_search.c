/* local_rate_search.c - see local_rate.h: a bake's rate choice for every clip when its rows are
 * local (palette_choose_rates hands it the clips: every rate decision of a bake is made there).
 * Each clip's rate is local_clip_rate's; clips are chosen on options->threads threads at a time,
 * each with its own sampler, each answer in its own slot, so the choices depend neither on the
 * thread count nor on the order the clips are taken in. */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "local_rate.h"
#include "pool.h"

/* The analysis the clip is framed from (rate_search.c's: the lowest common rate, the likeliest
 * within the frame limit). */
#define ANALYSIS_FPS 2.0

typedef struct local_search {
    const cb_model *model;
    int32_t skin;
    const cb_bake_options *o;
    cb_clip_plan *plan;
    uint32_t count;
    const cb_rate_goal *goals;
    cb_rate_choice *choices;
    cb_error *errors; /* per clip */
    const palette_skin_facts *facts;
    local_skeleton skeleton;
    search_keep *keep; /* or NULL */
    atomic_bool not_qpos; /* some clip's pose had a joint that is no similarity */
    atomic_uint next;
    atomic_size_t kept_bytes;
} local_search;

/* Clip i's pose cache for the bake (keep's, made where it has none yet), or NULL. */
static pose_cache *clip_cache(local_search *ls, uint32_t i)
{
    if (!ls->keep) return NULL;
    if (!ls->keep->poses[i]) ls->keep->poses[i] = palette_probe_poses(ls->keep->arena, ls->skeleton.bones, SEARCH_CLIP_POSE_BYTES);
    return ls->keep->poses[i];
}

/* Clip i's rows on its keys (local_clip_timed), weighed against the uniform rate r chose: taken
 * where they cost fewer rows (their map's rows counted) or meet the budget the uniform rate misses
 * at max_fps, or wherever possible with timed_rows on
 * (the plan's timed_rows and row_cells, its fps the map's cell rate). Only for a job's search
 * (keep: cb_choose_rates's callers own plans that nothing frees), never with timed_rows off. */
static cb_status choose_timed(local_search *ls, cb_sampler *s, uint32_t i, const cb_clip_info *info, pose_cache *cache,
                              const cb_rate_goal *goal, const local_rate *r, cb_error *err)
{
    cb_rate_choice *choice = &ls->choices[i];
    choice->uniform_fps = r->fps;
    choice->uniform_rows = cb_clip_step_count(info->duration, r->fps) + (info->loops ? 0 : 1);
    if (ls->o->timed_rows == CB_TIMED_ROWS_OFF || !ls->keep || ls->plan[i].step) return CB_OK;
    local_timed t;
    double max_error = goal->max_error_mm / 1000 * ls->facts->height;
    /* auto: only while they may come to fewer rows, or where the uniform rate misses the budget */
    bool asked = ls->o->timed_rows == CB_TIMED_ROWS_ON || !r->met;
    if (local_clip_timed(s, ls->facts, &ls->skeleton, info, ls->o->root_motion, cache, max_error,
                         ls->skeleton.bones * cb_layout_texels_per_bone(CB_LAYOUT_QPOS), asked ? 0 : choice->uniform_rows,
                         &t, err))
        return err->status;
    if (t.too_many) { /* stated as weighed: at least that many */
        choice->timed_weighed = true, choice->timed_rows = t.rows, choice->timed_map_rows = t.map_rows;
        return CB_OK;
    }
    /* A half map holds row numbers exactly only below 2049 (docs/pal-format.md). */
    if (!t.possible || (ls->o->precision == CB_PRECISION_HALF && t.rows > 2048)) return free(t.row_cells), CB_OK;
    choice->timed_weighed = true;
    choice->timed_rows = t.rows, choice->timed_map_rows = t.map_rows, choice->timed_cells = t.cells;
    choice->timed_cell_rate = t.cell_rate;
    bool fewer = t.rows + t.map_rows < choice->uniform_rows;
    if (!fewer && r->met && ls->o->timed_rows != CB_TIMED_ROWS_ON) return free(t.row_cells), CB_OK;
    cb_clip_plan *plan = &ls->plan[i];
    plan->fps = t.cell_rate, plan->timed_rows = t.rows, plan->row_cells = t.row_cells;
    choice->met = true, choice->error = t.error, choice->error_mm = cb_mm_per_m(t.error, ls->facts->height);
    choice->fps_needed = 0;
    return CB_OK;
}

static cb_status choose_clip(local_search *ls, cb_sampler *s, uint32_t i, cb_error *err)
{
    cb_clip_plan *plan = &ls->plan[i];
    pose_cache *cache = clip_cache(ls, i);
    cb_clip_info info;
    /* The analysis kept from before the choice (root motion's decision) where it stands in for
     * one; the bake after frames the clip from it too. */
    if (!(cache && palette_take_kept_analysis(cache, s, plan->animation, plan->loop, ANALYSIS_FPS, &ls->o->limits, &info)) &&
        cb_clip_analyze(s, plan->animation, ANALYSIS_FPS, plan->loop, &ls->o->limits, &info, err))
        return err->status;
    if (cache) palette_keep_analysis(cache, &info, ANALYSIS_FPS, plan->loop);
    local_rate r;
    const cb_rate_goal *goal = &ls->goals[i];
    if (local_clip_rate(s, ls->facts, &ls->skeleton, &info, ls->o->root_motion, cache, goal->max_error_mm / 1000 * ls->facts->height,
                        goal->max_fps, &r, err))
        return err->status;
    cb_clip_plan_release(plan); /* an earlier search's */
    plan->fps = r.fps, plan->fit = false; /* local rows are the sampled poses, converted */
    ls->choices[i] = (cb_rate_choice){.met = r.met, .error = r.error, .error_mm = r.error_mm, .fps_needed = r.fps_needed};
    if (!r.not_qpos && choose_timed(ls, s, i, &info, cache, goal, &r, err)) return err->status;
    if (ls->keep) search_keep_settle(&ls->keep->poses[i], ls->skeleton.bones, &ls->kept_bytes, false);
    if (r.not_qpos) atomic_store(&ls->not_qpos, true);
    return CB_OK;
}

static void choose_share(void *arg, uint32_t thread, uint32_t threads)
{
    (void)thread, (void)threads; /* clips are taken from a shared counter */
    local_search *ls = arg;
    cb_error fail = {0};
    cb_sampler *s = cb_sampler_create(ls->model, ls->skin, &fail);
    for (uint32_t n; (n = atomic_fetch_add(&ls->next, 1)) < ls->count;) {
        if (!(ls->goals[n].max_error_mm > 0)) continue;
        if (!s) ls->errors[n] = fail;
        else choose_clip(ls, s, n, &ls->errors[n]);
    }
    cb_sampler_free(s);
}

cb_status local_choose_rates(cb_sampler *s, const cb_bake_options *o, cb_clip_plan *plan, uint32_t count,
                             const cb_rate_goal *goals, cb_rate_choice *out, search_keep *keep,
                             const palette_skin_facts *facts, const bool *needed_later, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    local_search ls = {.model = m, .skin = cb_sampler_skin(s), .o = o, .plan = plan, .count = count, .goals = goals,
                       .choices = calloc(count ? count : 1, sizeof(cb_rate_choice)),
                       .errors = calloc(count ? count : 1, sizeof(cb_error)), .facts = facts, .keep = keep};
    if (!ls.choices || !ls.errors || !local_skeleton_build(m, ls.skin, &ls.skeleton)) {
        free(ls.choices), free(ls.errors);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory choosing frame rates for %s", m->source);
    }
    uint32_t threads = o->threads < 1 ? 1 : o->threads;
    cb_pool_run(threads > count ? count : threads, choose_share, &ls);
    for (uint32_t i = 0; i < count && !err->status; ++i) /* the first failure in clip order */
        if (ls.errors[i].status) *err = ls.errors[i];
    for (uint32_t i = 0; out && i < count; ++i)
        if (goals[i].max_error_mm > 0) out[i] = ls.choices[i];
    local_skeleton_free(&ls.skeleton);
    free(ls.choices), free(ls.errors);
    if (keep && !err->status) keep->local_rates = !atomic_load(&ls.not_qpos);
    if (err->status || !atomic_load(&ls.not_qpos)) return err->status;
    cb_bake_options global = *o; /* baked global (affine): chosen for global rows (the poses kept serve it too) */
    global.bone_space = CB_BONE_SPACE_GLOBAL;
    return palette_choose_rates(s, &global, plan, count, goals, out, keep, needed_later, err);
}
