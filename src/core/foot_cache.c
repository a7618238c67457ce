/* foot_cache.c - one bake's foot analyses, measured once (foot_cache.h). */
#include "foot_cache.h"

#include <stdlib.h>
#include <string.h>

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
    stride_feet feet;
    entry *entries;
    uint32_t count, cap, measured, reused;
};

foot_cache *foot_cache_create(void) { return calloc(1, sizeof(foot_cache)); }

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
    stride_measure_feet(s, clip, &c->feet, &e->stride, &e->tracks);
    e->rows = clip->steps;
    memcpy(out, &e->stride, sizeof *out);
}

const stride_feet *foot_cache_feet(foot_cache *c, cb_sampler *s) { return cache_feet(c, s) ? &c->feet : NULL; }

void foot_cache_counts(const foot_cache *c, uint32_t *measured, uint32_t *reused)
{
    *measured = c ? c->measured : 0, *reused = c ? c->reused : 0;
}
