/* roster_share.c - which types share a palette, for the one-step bake and the merge of fragments
 * alike, so that both write the same manifest. */
#include "roster_files.h"

#include <string.h>

void roster_assign_owners(cb_roster *r)
{
    for (uint32_t i = 0; i < r->type_count; ++i) {
        cb_roster_type *t = &r->types[i];
        if (t->error.status) continue;
        for (uint32_t k = 0; k < i; ++k)
            if (!r->types[k].error.status && r->types[k].owner == k && r->types[k].key == t->key) {
                t->owner = k;
                t->outcome = CB_TYPE_SHARED;
                break;
            }
    }
}

bool roster_settle_shared(cb_roster *r, uint32_t i)
{
    cb_roster_type *t = &r->types[i];
    const cb_roster_type *o = &r->types[t->owner];
    if (o->outcome == CB_TYPE_FAILED) {
        t->outcome = CB_TYPE_FAILED;
        cb_fail(&t->error, o->error.status, "its palette is %s's, which failed", o->animal->name);
        r->failed++;
        return false;
    }
    memcpy(t->paths, o->paths, sizeof t->paths);
    t->layout = o->layout, t->precision = o->precision, t->palette_bytes = o->palette_bytes;
    t->width = o->width, t->height = o->height, t->blocks = o->blocks, t->max_error = o->max_error;
    t->visible_error = o->visible_error;
    for (uint32_t c = 0; c < t->clip_count && c < o->clip_count; ++c) t->clips[c].visible_error_mm = o->clips[c].visible_error_mm;
    r->shared++;
    return true;
}
