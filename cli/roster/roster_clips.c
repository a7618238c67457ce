/* roster_clips.c - which clips a type bakes: the catalog's clips list as written; else, with
 * states, the clips the states play and extra_clips, in the model's order, with a note naming
 * what was left out and how to keep it; else every clip. Names are found as --clip finds them
 * (cb_match_clip_name), so `clips = ["Walk"]` picks "AnimalArmature|Walk". */
#include "roster_files.h"

#include <stdlib.h>
#include <string.h>

#include "crowdbake/gltf.h"

/* The model's animation a catalog entry names, or -1 with err set (the entry's place, why, and
 * did-you-mean). */
static int32_t find_entry(const cb_catalog *cat, const cb_catalog_animal *an, const cb_model *m,
                          const cb_catalog_clip *c, const char *key, cb_error *err)
{
    char where[1100], why[768];
    roster_at(cat, c->pos, where, sizeof where);
    const struct cb_skipped_clip *skip = cb_model_find_skipped_clip(m, c->source);
    if (skip && cb_model_find_animation(m, c->source) < 0) /* asked for by name: an error, not a warning */
        return cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] %s", where, an->name, skip->reason), -1;
    int a = m->animation_count
                ? cb_match_clip_name(c->source, &m->animations[0].name, m->animation_count, sizeof m->animations[0], why,
                                     sizeof why)
                : (snprintf(why, sizeof why, "no clip '%s'; the model has none", c->source), -1);
    if (a < 0) cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] %s: %s: %s", where, an->name, m->source, key, why);
    return a;
}

/* The entry's plan: its animation, its name in the palette (the model's name when the catalog
 * gives only a source to match), loop and rate. */
static void plan_entry(const cb_model *m, const cb_catalog_clip *c, int32_t a, cb_clip_plan *p, cb_clip_request *req)
{
    const char *name = c->name == c->source ? m->animations[a].name : c->name;
    *p = (cb_clip_plan){a, name, c->loop, c->fps, false, false, 0, NULL};
    *req = (cb_clip_request){c->fps_auto, c->max_error_mm};
}

/* Which animations the states play (their keywords, as roster_match_states matches them) and
 * which extra_clips names (extra[a]: its entry + 1). A state that matches nothing is left to
 * roster_match_states to report. */
static cb_status states_choose(const cb_catalog *cat, const cb_catalog_animal *an, const cb_model *m, bool *chosen,
                               uint32_t *extra, cb_error *err)
{
    const char **names = calloc(m->animation_count + 1, sizeof *names);
    if (!names) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t a = 0; a < m->animation_count; ++a) names[a] = m->animations[a].name;
    for (uint32_t s = 0; s < an->state_count && !err->status; ++s) {
        const cb_catalog_state *st = &an->states[s];
        int a = cb_match_state(names, m->animation_count, st->keywords, st->keyword_count);
        if (a >= 0) chosen[a] = true;
        else roster_state_matches_none(cat, an, st, names, m->animation_count, err);
    }
    free(names);
    if (err->status) return err->status;
    for (uint32_t e = 0; e < an->extra_clip_count; ++e) {
        int32_t a = find_entry(cat, an, m, &an->extra_clips[e], "extra_clips", err);
        if (a < 0) return err->status;
        chosen[a] = true, extra[a] = e + 1;
    }
    return CB_OK;
}

/* "note: baked 4 of 12 clips ...": what was left out, and how to keep it. */
static void note_left_out(const cb_model *m, const bool *chosen, uint32_t kept, cb_warnings *w)
{
    if (kept == m->animation_count) return;
    char list[1024] = "", keep[1024] = "";
    for (uint32_t a = 0, listed = 0; a < m->animation_count; ++a) {
        if (chosen[a]) continue;
        const char *name = m->animations[a].name, *bar = strrchr(name, '|');
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", listed ? ", " : "", name);
        snprintf(keep + strlen(keep), sizeof keep - strlen(keep), "%s\"%s\"", listed++ ? ", " : "", bar ? bar + 1 : name);
    }
    cb_warn(w, "note",
            "baked %u of %u clips, the ones its states play: left out %s (keep them with extra_clips = [%s], or list "
            "every clip to bake in clips)",
            kept, m->animation_count, list, keep);
}

static cb_status plan_from_states(const cb_catalog *cat, const cb_catalog_animal *an, const cb_model *m,
                                  cb_clip_plan *plan, cb_clip_request *req, uint32_t *n, cb_roster_type *t, cb_error *err)
{
    bool *chosen = calloc(m->animation_count + 1, sizeof *chosen);
    uint32_t *extra = calloc(m->animation_count + 1, sizeof *extra);
    if (!chosen || !extra) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    else if (!states_choose(cat, an, m, chosen, extra, err)) {
        *n = 0;
        for (uint32_t a = 0; a < m->animation_count; ++a) {
            if (!chosen[a]) continue;
            if (extra[a]) plan_entry(m, &an->extra_clips[extra[a] - 1], (int32_t)a, &plan[*n], &req[*n]);
            else plan[*n] = (cb_clip_plan){(int32_t)a, m->animations[a].name, -1, 0, false, false, 0, NULL}, req[*n] = (cb_clip_request){-1, 0};
            ++*n;
        }
        note_left_out(m, chosen, *n, &t->warnings);
    }
    free(chosen);
    free(extra);
    return err->status;
}

cb_status roster_plan_clips(const cb_catalog *cat, const cb_catalog_animal *an, const cb_model *m, cb_clip_plan **plan,
                            cb_clip_request **requests, cb_roster_type *t, cb_error *err)
{
    uint32_t n = an->clips ? an->clip_count : m->animation_count;
    *plan = calloc(n ? n : 1, sizeof **plan);
    *requests = calloc(n ? n : 1, sizeof **requests);
    t->clips = calloc(n ? n : 1, sizeof *t->clips);
    if (!*plan || !*requests || !t->clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    if (an->clips) {
        char where[1100];
        for (uint32_t i = 0; i < n; ++i) {
            int32_t a = find_entry(cat, an, m, &an->clips[i], "clips", err);
            if (a < 0) return err->status;
            plan_entry(m, &an->clips[i], a, &(*plan)[i], &(*requests)[i]);
            for (uint32_t k = 0; k < i; ++k)
                if (strcmp((*plan)[k].name, (*plan)[i].name) == 0)
                    return cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] two clips are named '%s'; rename one with name = \"...\"",
                                   roster_at(cat, an->clips[i].pos, where, sizeof where), an->name, (*plan)[i].name);
        }
    } else if (an->state_count && m->animation_count) {
        if (plan_from_states(cat, an, m, *plan, *requests, &n, t, err)) return err->status;
    } else {
        for (uint32_t i = 0; i < n; ++i)
            (*plan)[i] = (cb_clip_plan){(int32_t)i, m->animations[i].name, -1, 0, false, false, 0, NULL}, (*requests)[i] = (cb_clip_request){-1, 0};
    }
    t->clip_count = n;
    return CB_OK;
}
