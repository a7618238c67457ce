/* foot_cache.c - one bake's foot analyses, measured once (foot_cache.h). */
#include "foot_cache.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/pool.h"
#include "sampler.h" /* cb_joint_subset */
#include "stride_feet.h"

/* What a stride reads of its clip: two framings equal in these measure the same. */
typedef struct framing {
    int32_t animation;
    bool loops;
    double t0, t1, duration, root_velocity[3];
} framing;

typedef struct entry {
    framing key;
    uint32_t rows;        /* the row count slide_mean_varying was measured for */
    cb_stride stride;
    stride_tracks tracks; /* to measure slide_mean_varying for another row count */
} entry;

struct foot_cache {
    const cb_model *model;
    int32_t skin;
    bool feet_found;
    bool screen; /* strides screened first (foot_cache_screen_strides) */
    stride_feet feet;
    const cb_model *height_model; /* the rest pose's height, of this model and skin */
    int32_t height_skin;
    double height;
    entry *entries;
    uint32_t count, cap, measured, reused, screened;
};

foot_cache *foot_cache_create(void) { return calloc(1, sizeof(foot_cache)); }

void foot_cache_screen_strides(foot_cache *c)
{
    if (c) c->screen = true;
}

void foot_cache_free(foot_cache *c)
{
    if (!c) return;
    for (uint32_t i = 0; i < c->count; ++i) stride_tracks_free(&c->entries[i].tracks);
    if (c->feet_found) stride_feet_free(&c->feet);
    free(c->entries);
    free(c);
}

/* The model's feet, found with the first sampler; false for a sampler of another model. */
static bool cache_feet(foot_cache *c, cb_sampler *s)
{
    if (!c) return false;
    if (c->feet_found) return c->model == cb_sampler_model(s) && c->skin == cb_sampler_skin(s);
    if (!stride_feet_find(s, &c->feet)) return false;
    c->model = cb_sampler_model(s), c->skin = cb_sampler_skin(s), c->feet_found = true;
    return true;
}

static framing framing_of(const cb_clip_info *clip)
{
    framing f;
    memset(&f, 0, sizeof f); /* padding too: keys compare with memcmp */
    f.animation = clip->animation, f.loops = clip->loops;
    f.t0 = clip->t0, f.t1 = clip->t1, f.duration = clip->duration;
    memcpy(f.root_velocity, clip->root_velocity, sizeof f.root_velocity);
    return f;
}

static entry *find(foot_cache *c, const framing *key)
{
    for (uint32_t i = 0; i < c->count; ++i)
        if (!memcmp(&c->entries[i].key, key, sizeof *key)) return &c->entries[i];
    return NULL;
}

static entry *add(foot_cache *c, const framing *key)
{
    if (c->count == c->cap) {
        uint32_t cap = c->cap ? c->cap * 2 : 16;
        entry *grown = realloc(c->entries, cap * sizeof *grown);
        if (!grown) return NULL;
        c->entries = grown, c->cap = cap;
    }
    entry *e = &c->entries[c->count++];
    memset(e, 0, sizeof *e);
    e->key = *key;
    return e;
}

void foot_cache_stride(foot_cache *c, cb_sampler *s, const cb_clip_info *clip, cb_stride *out)
{
    if (!(clip->duration > 0) || !cache_feet(c, s)) { /* no feet to find, or not this model's */
        cb_stride_measure(s, clip, out);
        return;
    }
    framing key = framing_of(clip);
    entry *e = find(c, &key);
    if (e) {
        c->reused++;
        if (e->rows != clip->steps) stride_varying_at(&e->stride, &e->tracks, clip->steps), e->rows = clip->steps;
        memcpy(out, &e->stride, sizeof *out); /* padding too: a copy is the measured bytes */
        return;
    }
    e = add(c, &key);
    if (!e) {
        cb_stride_measure(s, clip, out);
        return;
    }
    c->measured++;
    stride_measure_feet(s, clip, &c->feet, c->screen, &e->stride, &e->tracks);
    c->screened += c->screen && !e->tracks.feet && e->stride.foot_count;
    e->rows = clip->steps;
    memcpy(out, &e->stride, sizeof *out);
}

double foot_cache_rest_height(foot_cache *c, cb_sampler *s)
{
    double lo[3], hi[3];
    if (!c) return cb_skin_rest_bounds(s, lo, hi);
    if (c->height_model != cb_sampler_model(s) || c->height_skin != cb_sampler_skin(s))
        c->height = cb_skin_rest_bounds(s, lo, hi), c->height_model = cb_sampler_model(s), c->height_skin = cb_sampler_skin(s);
    return c->height;
}

/* ---- strides measured on several threads ---- */

/* The clips of one foot_cache_measure_clips whose strides are not cached yet, and what each
 * thread measured of them. */
typedef struct prefetch {
    const cb_model *model;
    int32_t skin;
    const stride_feet *feet;
    bool screen;
    const cb_clip_info **clips;
    uint32_t count;
    cb_stride *strides;
    stride_tracks *tracks;
    bool *done;
    atomic_uint next; /* the next clip a thread takes */
} prefetch;

/* The same joints as `like`, for another sampler of the model (a subset holds its lanes). */
static cb_joint_subset *subset_like(const cb_sampler *s, const cb_joint_subset *like)
{
    uint32_t joints = s->model->skins[s->skin].joint_count;
    bool *wanted = malloc((joints ? joints : 1) * sizeof *wanted);
    if (!wanted) return NULL;
    for (uint32_t j = 0; j < joints; ++j) wanted[j] = like->joint_slot[j] != UINT32_MAX;
    cb_joint_subset *sub = cb_joint_subset_create(s, wanted);
    free(wanted);
    return sub;
}

/* A thread's share: the next clip not taken yet, until none is left (a screened clip costs a
 * quarter of one measured in full, so a fixed share would leave one thread waiting on the other),
 * on a sampler and joint lanes of its own, the clip's loop set on it as cb_clip_analyze left it on
 * the caller's (which samples it so). Each clip's stride is the same whichever thread measures it. */
static void measure_share(void *ctx, uint32_t t, uint32_t threads)
{
    (void)t, (void)threads;
    prefetch *p = ctx;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(p->model, p->skin, &err);
    stride_feet own = *p->feet; /* its soles read, not written */
    own.joints = s ? subset_like(s, p->feet->joints) : NULL;
    for (uint32_t i = atomic_fetch_add(&p->next, 1); own.joints && i < p->count; i = atomic_fetch_add(&p->next, 1)) {
        if (!cb_sampler_set_loop(s, p->clips[i])) continue;
        stride_measure_feet(s, p->clips[i], &own, p->screen, &p->strides[i], &p->tracks[i]);
        p->done[i] = true;
    }
    cb_joint_subset_free(own.joints);
    cb_sampler_free(s);
}

/* The clips of `clips` a stride is measured for and not cached (nor listed before), into `out`. */
static uint32_t clips_to_measure(foot_cache *c, const cb_clip_info *clips, uint32_t count, const cb_clip_info **out)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < count; ++i) {
        framing key = framing_of(&clips[i]);
        bool listed = !(clips[i].duration > 0) || find(c, &key);
        for (uint32_t k = 0; k < n && !listed; ++k) {
            framing other = framing_of(out[k]);
            listed = !memcmp(&other, &key, sizeof key);
        }
        if (!listed) out[n++] = &clips[i];
    }
    return n;
}

void foot_cache_measure_clips(foot_cache *c, cb_sampler *s, const cb_clip_info *clips, uint32_t count, uint32_t threads)
{
    if (threads < 2 || count < 2 || !cache_feet(c, s)) return;
    prefetch p = {cb_sampler_model(s), cb_sampler_skin(s), &c->feet, c->screen, NULL, 0, NULL, NULL, NULL, 0};
    p.clips = malloc(count * sizeof *p.clips);
    p.strides = malloc(count * sizeof *p.strides);
    p.tracks = calloc(count, sizeof *p.tracks);
    p.done = calloc(count, sizeof *p.done);
    if (p.clips && p.strides && p.tracks && p.done && (p.count = clips_to_measure(c, clips, count, p.clips)) >= 2)
        cb_pool_run(threads < p.count ? threads : p.count, measure_share, &p);
    /* Into the cache in the clips' order; one a thread could not measure is measured when asked. */
    for (uint32_t i = 0; i < p.count; ++i) {
        framing key = framing_of(p.clips[i]);
        entry *e = p.done[i] ? add(c, &key) : NULL;
        if (!e) {
            stride_tracks_free(&p.tracks[i]);
            continue;
        }
        memcpy(&e->stride, &p.strides[i], sizeof e->stride); /* padding too */
        e->tracks = p.tracks[i], e->rows = p.clips[i]->steps;
        c->measured++;
        c->screened += c->screen && !e->tracks.feet && e->stride.foot_count;
    }
    free(p.clips), free(p.strides), free(p.tracks), free(p.done);
}

const stride_feet *foot_cache_feet(foot_cache *c, cb_sampler *s) { return cache_feet(c, s) ? &c->feet : NULL; }

void foot_cache_counts(const foot_cache *c, uint32_t *measured, uint32_t *reused)
{
    *measured = c ? c->measured : 0, *reused = c ? c->reused : 0;
}

uint32_t foot_cache_screened(const foot_cache *c) { return c ? c->screened : 0; }
