/* clip_memo.c - one bake run's clip analyses, each made once (clip_memo.h). */
#include "clip_memo.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "crowdbake/pool.h"

/* One analysis and what it was made with. */
typedef struct memo_entry {
    const cb_model *model;
    int32_t skin;
    int loop;             /* the loop override */
    uint32_t max_frames;  /* the one limit an analysis reads */
    double fps;
    cb_clip_info info;    /* as cb_clip_analyze gave it at fps */
} memo_entry;

struct clip_memo {
    memo_entry *entries;
    uint32_t count, cap;
};

clip_memo *clip_memo_create(void) { return calloc(1, sizeof(clip_memo)); }

void clip_memo_free(clip_memo *memo)
{
    if (!memo) return;
    free(memo->entries);
    free(memo);
}

bool clip_feet_weighed_alike(const cb_clip_info *c, double a, double b, const cb_limits *limits)
{
    if (!c->loop_feet_weighed) return true;
    bool closes = c->loop_reason == CB_LOOP_CLOSED || c->loop_reason == CB_LOOP_CLOSED_CORRECTED;
    double span = c->t1 - c->t0, duration = span + (closes ? 0 : c->key_interval); /* weigh_feet's */
    bool at_a = a > 0 && isfinite(a) && a <= CB_FPS_LIMIT && !(duration * a > (double)limits->max_frames);
    bool at_b = b > 0 && isfinite(b) && b <= CB_FPS_LIMIT && !(duration * b > (double)limits->max_frames);
    return at_a == at_b;
}

uint32_t clip_memo_count(const clip_memo *memo) { return memo ? memo->count : 0; }

static uint32_t max_frames_of(const cb_limits *limits) { return limits ? limits->max_frames : cb_default_limits().max_frames; }

/* The entry that stands in for analyzing `animation` at fps with this loop override, or NULL. */
static const memo_entry *find(const clip_memo *memo, const cb_sampler *s, int32_t animation, double fps, int loop,
                              const cb_limits *limits)
{
    cb_limits l = limits ? *limits : cb_default_limits();
    for (uint32_t i = 0; memo && i < memo->count; ++i) {
        const memo_entry *e = &memo->entries[i];
        if (e->model == cb_sampler_model(s) && e->skin == cb_sampler_skin(s) && e->info.animation == animation &&
            e->loop == loop && e->max_frames == l.max_frames && clip_feet_weighed_alike(&e->info, e->fps, fps, &l))
            return e;
    }
    return NULL;
}

bool clip_memo_take(clip_memo *memo, cb_sampler *s, int32_t animation, double fps, int loop, const cb_limits *limits,
                    cb_clip_info *out)
{
    const memo_entry *e = find(memo, s, animation, fps, loop, limits);
    if (!e) return false;
    cb_clip_info info = e->info;
    cb_error ignored = {0};
    /* As analyzing ends: the clip's loop set on the sampler, then framed at fps. */
    if (cb_clip_frame_at(cb_sampler_model(s), fps, limits, &info, &ignored) || !cb_sampler_set_loop(s, &info)) return false;
    *out = info;
    return true;
}

void clip_memo_keep(clip_memo *memo, const cb_sampler *s, const cb_clip_info *info, double fps, int loop,
                    const cb_limits *limits)
{
    if (!memo || find(memo, s, info->animation, fps, loop, limits)) return;
    if (memo->count == memo->cap) {
        uint32_t cap = memo->cap ? memo->cap * 2 : 16;
        memo_entry *grown = realloc(memo->entries, cap * sizeof *grown);
        if (!grown) return; /* not kept: analyzed again when asked */
        memo->entries = grown, memo->cap = cap;
    }
    memo->entries[memo->count++] = (memo_entry){cb_sampler_model(s), cb_sampler_skin(s), loop, max_frames_of(limits), fps, *info};
}

cb_status clip_memo_analyze(clip_memo *memo, cb_sampler *s, int32_t animation, double fps, int loop,
                            const cb_limits *limits, cb_clip_info *out, cb_error *err)
{
    if (clip_memo_take(memo, s, animation, fps, loop, limits, out)) return CB_OK;
    cb_status rc = cb_clip_analyze(s, animation, fps, loop, limits, out, err);
    if (!rc) clip_memo_keep(memo, s, out, fps, loop, limits);
    return rc;
}

/* ---- analyses made side by side ---- */

typedef struct prefetch {
    const cb_model *model;
    int32_t skin;
    const clip_ask *asks;
    const uint32_t *todo; /* indices into asks */
    uint32_t count;
    const cb_limits *limits;
    cb_clip_info *infos;  /* per todo entry */
    bool *made;
    atomic_uint next;
} prefetch;

static void prefetch_share(void *ctx, uint32_t thread, uint32_t threads)
{
    (void)thread, (void)threads;
    prefetch *p = ctx;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(p->model, p->skin, &err);
    for (uint32_t i = atomic_fetch_add(&p->next, 1); s && i < p->count; i = atomic_fetch_add(&p->next, 1)) {
        const clip_ask *a = &p->asks[p->todo[i]];
        cb_error ignored = {0};
        p->made[i] = !cb_clip_analyze(s, a->animation, a->fps, a->loop, p->limits, &p->infos[i], &ignored);
    }
    cb_sampler_free(s); /* a share without a sampler leaves its clips to clip_memo_analyze */
}

/* The asks with no stand-in in the memo nor an equal ask before them, into todo. */
static uint32_t asks_to_analyze(const clip_memo *memo, const cb_sampler *s, const clip_ask *asks, uint32_t count,
                                const cb_limits *limits, uint32_t *todo)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < count; ++i) {
        bool listed = find(memo, s, asks[i].animation, asks[i].fps, asks[i].loop, limits) != NULL;
        for (uint32_t k = 0; k < n && !listed; ++k) {
            const clip_ask *o = &asks[todo[k]];
            listed = o->animation == asks[i].animation && o->fps == asks[i].fps && o->loop == asks[i].loop;
        }
        if (!listed) todo[n++] = i;
    }
    return n;
}

void clip_memo_prefetch(clip_memo *memo, const cb_sampler *s, const clip_ask *asks, uint32_t count,
                        const cb_limits *limits, uint32_t threads)
{
    if (!memo || threads < 2 || count < 2) return;
    prefetch p = {cb_sampler_model(s), cb_sampler_skin(s), asks, NULL, 0, limits, NULL, NULL, 0};
    uint32_t *todo = malloc(count * sizeof *todo);
    p.infos = malloc(count * sizeof *p.infos), p.made = calloc(count, sizeof *p.made);
    if (todo && p.infos && p.made && (p.count = asks_to_analyze(memo, s, asks, count, limits, todo)) >= 2) {
        p.todo = todo;
        cb_pool_run(threads < p.count ? threads : p.count, prefetch_share, &p);
    }
    for (uint32_t i = 0; i < p.count; ++i) /* kept in the asks' order */
        if (p.made[i]) clip_memo_keep(memo, s, &p.infos[i], asks[todo[i]].fps, asks[todo[i]].loop, limits);
    free(todo), free(p.infos), free(p.made);
}
