/* bake_beside.c - see bake_beside.h. */
#include "bake_beside.h"

#include <stdio.h>
#include <stdlib.h>

#include "../core/clip_memo.h"
#include "../core/foot_cache.h"

typedef struct bake_beside {
    search_beside task; /* first: the search hands this back */
    const cb_bake_job *job;
    uint32_t count;     /* its planned clips */
    cb_clip_plan *plan; /* the speed reference's: a copy (the searches write the job's) */
    bool *reads;        /* per clip: the speed reference may measure it (speed_reference_may_measure) */
    bool decide_speed;  /* the job has no speed reference */
    struct foot_cache *feet;
    struct clip_memo *memo;
    measured_travel *travel; /* per clip; those it reads measured */
    bool decided;
    double speed;
    char why[256];
} bake_beside;

static void run(search_beside *task, const search_keep *keep)
{
    bake_beside *b = (bake_beside *)task;
    const cb_bake_job *job = b->job;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(job->model, job->skin, &err);
    if (!s) return; /* the run measures it all */
    for (uint32_t i = 0; i < b->count; ++i) /* the analyses of the searches it reads */
        if (b->reads[i]) palette_memo_keep_search(b->memo, s, keep->poses[i], &job->limits);
    if (b->decide_speed) {
        b->speed = speed_reference_cached(b->feet, b->memo, job->model, job->skin, b->plan, b->count, 1, b->why,
                                          sizeof b->why);
        b->decided = true;
    }
    for (uint32_t i = 0; i < b->count; ++i) /* their rates are chosen: their travels (out of memory: later) */
        if (b->reads[i] && !bake_clip_travel(job, i, b->feet, b->memo, s, &b->travel[i])) break;
    cb_sampler_free(s);
}

static void release(search_beside *task)
{
    bake_beside *b = (bake_beside *)task;
    for (uint32_t i = 0; b->travel && i < b->count; ++i) free(b->travel[i].offsets);
    foot_cache_free(b->feet);
    clip_memo_free(b->memo);
    free(b->travel), free(b->plan), free(b->reads);
    free(b);
}

search_beside *bake_beside_create(const cb_bake_job *job)
{
    bake_beside *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    uint32_t n = job->plan_count ? job->plan_count : 1;
    *b = (bake_beside){.job = job, .count = job->plan_count, .decide_speed = job->speed_reference < 0};
    b->task.run = run, b->task.release = release;
    atomic_init(&b->task.taken, false);
    b->plan = malloc(n * sizeof *b->plan);
    b->reads = malloc(n * sizeof *b->reads);
    b->travel = calloc(n, sizeof *b->travel);
    b->feet = foot_cache_create();
    b->memo = clip_memo_create();
    if (!b->plan || !b->reads || !b->travel || !b->feet || !b->memo) return release(&b->task), NULL;
    for (uint32_t i = 0; i < b->count; ++i) {
        b->plan[i] = job->plan[i];
        b->plan[i].timed_rows = 0, b->plan[i].row_cells = NULL; /* the reference reads neither: not shared */
        b->reads[i] = speed_reference_may_measure(job->model, job->plan[i].animation);
    }
    b->task.reads = b->reads;
    foot_cache_screen_strides(b->feet); /* as the run's own: of a clip that does not stride, only that it does not */
    return &b->task;
}

bool bake_beside_take(search_keep *keep, struct foot_cache **feet, struct clip_memo **memo,
                      const measured_travel **travel, double *speed, char *why, size_t size)
{
    bake_beside *b = keep ? (bake_beside *)keep->beside : NULL;
    *feet = b ? b->feet : NULL, *memo = b ? b->memo : NULL, *travel = b ? b->travel : NULL;
    if (!b) return false;
    b->feet = NULL, b->memo = NULL;
    if (b->decided) *speed = b->speed, snprintf(why, size, "%s", b->why);
    return b->decided;
}
