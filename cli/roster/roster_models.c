/* roster_models.c - see roster_files.h: each model a catalog names is loaded once, however many
 * types use it (as their model or a LOD), when the first of them needs it; the types share it
 * read-only. Its memory then follows the models, not the types. */
#include "roster_files.h"

#include <stdlib.h>
#include <string.h>

#include "crowdbake/gltf.h"

typedef struct roster_model {
    const char *path;     /* the catalog's (it outlives the roster) */
    mtx_t lock;           /* held while it loads: another type wanting it waits, then shares it */
    bool loaded;
    cb_model *model;      /* NULL when it failed: error says why */
    cb_error error;
} roster_model;

static bool listed(const roster_models *ms, const char *path)
{
    for (uint32_t i = 0; i < ms->count; ++i)
        if (strcmp(ms->items[i].path, path) == 0) return true;
    return false;
}

static bool add(roster_models *ms, const char *path)
{
    if (listed(ms, path)) return true;
    roster_model *m = &ms->items[ms->count];
    memset(m, 0, sizeof *m);
    m->path = path;
    if (mtx_init(&m->lock, mtx_plain) != thrd_success) return false;
    ms->count++;
    return true;
}

bool roster_models_init(roster_models *ms, const cb_catalog *cat, const cb_limits *limits)
{
    size_t n = 0;
    for (uint32_t i = 0; i < cat->animal_count; ++i) n += 1 + cat->animals[i].lod_count;
    ms->items = calloc(n ? n : 1, sizeof *ms->items);
    ms->count = 0;
    ms->limits = limits;
    if (!ms->items) return false;
    for (uint32_t i = 0; i < cat->animal_count; ++i) {
        if (!add(ms, cat->animals[i].model)) return false;
        for (uint32_t l = 0; l < cat->animals[i].lod_count; ++l)
            if (!add(ms, cat->animals[i].lods[l])) return false;
    }
    return true;
}

const cb_model *roster_model_get(roster_models *ms, const char *path, cb_error *err)
{
    roster_model *m = NULL;
    for (uint32_t i = 0; i < ms->count && !m; ++i)
        if (strcmp(ms->items[i].path, path) == 0) m = &ms->items[i];
    if (!m) { /* not a path of the catalog: loaded for the caller alone (never the case today) */
        cb_fail(err, CB_ERR_INTERNAL, "%s: not among the catalog's models", path);
        return NULL;
    }
    mtx_lock(&m->lock);
    if (!m->loaded) {
        m->model = cb_gltf_load(path, ms->limits, &m->error);
        m->loaded = true;
    }
    mtx_unlock(&m->lock);
    if (!m->model) *err = m->error;
    return m->model;
}

void roster_models_free(roster_models *ms)
{
    for (uint32_t i = 0; i < ms->count; ++i) {
        cb_model_free(ms->items[i].model);
        mtx_destroy(&ms->items[i].lock);
    }
    free(ms->items);
    memset(ms, 0, sizeof *ms);
}
