/* model.c - cb_model ownership (an arena per model), the default limits and lookups.
 * model_validate.c checks a loaded model; key_scan.c is its pre-scan of animation keys. */
#include "crowdbake/core.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

cb_limits cb_default_limits(void)
{
    cb_limits l;
    l.max_joints = 4096;
    l.max_frames = 1u << 20;
    l.max_accessor_count = 1u << 24;
    l.max_file_bytes = (uint64_t)2 << 30;
    l.max_palette_bytes = (uint64_t)1 << 30;
    return l;
}

/* ---- arena: one owner for everything a model holds ---- */

typedef struct cb_arena_block {
    struct cb_arena_block *next;
    size_t used, size;
    max_align_t data[];
} cb_arena_block;

typedef struct cb_arena_adopted {
    struct cb_arena_adopted *next;
    void *ptr;
    void (*release)(void *);
} cb_arena_adopted;

struct cb_arena {
    cb_arena_block *head;
    cb_arena_adopted *adopted;
};

static void *arena_alloc(cb_arena *arena, size_t bytes)
{
    const size_t align = sizeof(max_align_t);
    bytes = (bytes + align - 1) / align * align;
    cb_arena_block *b = arena->head;
    if (!b || b->size - b->used < bytes) {
        size_t size = bytes > 65536 ? bytes : 65536;
        b = calloc(1, sizeof *b + size);
        if (!b) return NULL;
        b->size = size;
        b->next = arena->head;
        arena->head = b;
    }
    void *p = (char *)b->data + b->used;
    b->used += bytes;
    return p; /* calloc'd and never reused, so already zero */
}

cb_arena *cb_arena_create(void) { return calloc(1, sizeof(cb_arena)); }

bool cb_arena_adopt(cb_arena *arena, void *ptr, void (*release)(void *))
{
    cb_arena_adopted *a = cb_arena_alloc(arena, 1, sizeof *a);
    if (!a) return false;
    *a = (cb_arena_adopted){arena->adopted, ptr, release};
    arena->adopted = a;
    return true;
}

void cb_arena_free(cb_arena *arena)
{
    if (!arena) return;
    for (cb_arena_adopted *a = arena->adopted; a; a = a->next) a->release(a->ptr);
    cb_arena_block *b = arena->head;
    while (b) {
        cb_arena_block *next = b->next;
        free(b);
        b = next;
    }
    free(arena);
}

void *cb_arena_alloc(cb_arena *arena, size_t count, size_t size)
{
    if (size && count > SIZE_MAX / size) return NULL;
    size_t bytes = count * size;
    return arena_alloc(arena, bytes ? bytes : 1);
}

const char *cb_arena_strdup(cb_arena *arena, const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = cb_arena_alloc(arena, n, 1);
    if (p) memcpy(p, s, n);
    return p;
}

cb_model *cb_model_create(const char *source)
{
    cb_model *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->arena = cb_arena_create();
    if (!m->arena) {
        free(m);
        return NULL;
    }
    m->source = cb_model_strdup(m, source ? source : "<memory>");
    return m;
}

void cb_model_free(cb_model *model)
{
    if (!model) return;
    cb_arena_free(model->arena);
    free(model);
}

void *cb_model_alloc(cb_model *model, size_t count, size_t size) { return cb_arena_alloc(model->arena, count, size); }

const char *cb_model_strdup(cb_model *model, const char *s) { return cb_arena_strdup(model->arena, s); }

int32_t cb_model_find_skin(const cb_model *model, const char *name)
{
    for (uint32_t i = 0; i < model->skin_count; ++i)
        if (strcmp(model->skins[i].name, name) == 0) return (int32_t)i;
    char *end;
    long idx = strtol(name, &end, 10);
    if (*name && !*end && idx >= 0 && idx < (long)model->skin_count) return (int32_t)idx;
    return -1;
}

int32_t cb_model_find_animation(const cb_model *model, const char *name)
{
    for (uint32_t i = 0; i < model->animation_count; ++i)
        if (strcmp(model->animations[i].name, name) == 0) return (int32_t)i;
    return -1;
}

const struct cb_skipped_clip *cb_model_find_skipped_clip(const cb_model *model, const char *name)
{
    for (uint32_t i = 0; i < model->skipped_clip_count; ++i)
        if (strcmp(model->skipped_clips[i].name, name) == 0) return &model->skipped_clips[i];
    return NULL;
}

void cb_model_release_clip(const cb_model *model, int32_t animation)
{
    if (!model->release || animation < 0 || (uint32_t)animation >= model->animation_count) return;
    const cb_animation *anim = &model->animations[animation];
    cb_byte_range *ranges = malloc(2 * (size_t)anim->channel_count * sizeof *ranges);
    if (!ranges) return; /* a hint: nothing lost */
    size_t n = 0;
    const float *times = NULL;
    for (uint32_t c = 0; c < anim->channel_count; ++c) {
        const cb_channel *ch = &anim->channels[c];
        size_t per_key = (ch->path == CB_PATH_ROTATION ? 4 : 3) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
        if (ch->times != times) /* channels often share their times */
            ranges[n++] = (cb_byte_range){times = ch->times, (size_t)ch->key_count * sizeof(float)};
        ranges[n++] = (cb_byte_range){ch->values, (size_t)ch->key_count * per_key * sizeof(float)};
    }
    model->release(model->release_ctx, ranges, n);
    free(ranges);
}

uint64_t cb_model_skin_vertex_count(const cb_model *model, int32_t skin)
{
    uint64_t n = 0;
    for (uint32_t p = 0; p < model->primitive_count; ++p)
        if (model->primitives[p].skin == skin) n += model->primitives[p].vertex_count;
    return n;
}

uint64_t cb_model_skin_mesh_bytes(const cb_model *model, int32_t skin)
{
    uint64_t bytes = 0;
    for (uint32_t p = 0; p < model->primitive_count; ++p) {
        const cb_primitive *prim = &model->primitives[p];
        if (prim->skin == skin)
            bytes += (uint64_t)prim->vertex_count * prim->vertex_bytes + (uint64_t)prim->index_count * prim->index_bytes;
    }
    return bytes;
}
