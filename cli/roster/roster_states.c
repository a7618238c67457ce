/* roster_states.c - what a type's states play: each state's clip, whether it follows the
 * instance's speed (and why), the speed reference, and the feet that slide whatever the rate. */
#include "roster_files.h"
#include "crowdbake/herd_slide.h"
#include "crowdbake/plant_feet.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

cb_status roster_state_matches_none(const cb_catalog *cat, const cb_catalog_animal *an, const cb_catalog_state *st,
                                   const char *const *names, uint32_t count, cb_error *err)
{
    char list[512] = "", words[256] = "", where[1100];
    for (uint32_t i = 0; i < count; ++i)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", names[i]);
    for (uint32_t k = 0; k < st->keyword_count; ++k)
        snprintf(words + strlen(words), sizeof words - strlen(words), "%s\"%s\"", k ? ", " : "", st->keywords[k]);
    return cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] state '%s' matches no clip (keywords %s); the clips are: %s",
                   roster_at(cat, st->pos, where, sizeof where), an->name, st->name, words, list);
}

cb_status roster_match_states(const cb_catalog *cat, const cb_catalog_animal *an, cb_roster_type *t, cb_error *err)
{
    t->state_clip = calloc(an->state_count ? an->state_count : 1, sizeof *t->state_clip);
    const char **names = calloc(t->clip_count ? t->clip_count : 1, sizeof *names);
    if (!t->state_clip || !names) {
        free(names);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    for (uint32_t i = 0; i < t->clip_count; ++i) names[i] = t->clips[i].name;
    for (uint32_t s = 0; s < an->state_count && !err->status; ++s) {
        const cb_catalog_state *st = &an->states[s];
        t->state_clip[s] = cb_match_state(names, t->clip_count, st->keywords, st->keyword_count);
        if (t->state_clip[s] < 0) roster_state_matches_none(cat, an, st, names, t->clip_count, err);
    }
    free(names);
    return err->status;
}

/* The speed at which locomotion plays at rate 1: given, or measured on a state that follows the
 * speed: the default state's clip if it does, else the state the catalog names, else the
 * slowest such state. t->speed_reference_from says which. */
static bool measures_speed(const cb_roster_type *t, uint32_t s)
{
    return t->state_sync[s].speed && t->clips[t->state_clip[s]].speed.speed > 0;
}

static void speed_reference(const cb_catalog_animal *an, cb_roster_type *t)
{
    t->speed_reference = an->speed_reference;
    snprintf(t->speed_reference_from, sizeof t->speed_reference_from, "the catalog");
    if (!an->speed_auto) return;
    t->speed_reference = 0;
    snprintf(t->speed_reference_from, sizeof t->speed_reference_from,
             "none: no state is locomotion (none follows the speed), so nothing is foot-synced");
    int pick = -1;
    const char *rule = "";
    for (uint32_t s = 0; s < an->state_count && pick < 0; ++s)
        if (strcmp(an->states[s].name, an->default_state) == 0 && measures_speed(t, s))
            pick = (int)s, rule = "the default state";
    for (uint32_t s = 0; s < an->state_count && pick < 0 && an->speed_state; ++s)
        if (strcmp(an->states[s].name, an->speed_state) == 0 && measures_speed(t, s))
            pick = (int)s, rule = "the catalog's speed_reference state";
    for (uint32_t s = 0; s < an->state_count && !(pick >= 0 && *rule); ++s) {
        const cb_roster_clip *c = &t->clips[t->state_clip[s]];
        if (measures_speed(t, s) && (pick < 0 || c->speed.speed < t->clips[t->state_clip[pick]].speed.speed))
            pick = (int)s;
    }
    if (pick < 0) return;
    const cb_roster_clip *c = &t->clips[t->state_clip[pick]];
    t->speed_reference = c->speed.speed;
    snprintf(t->speed_reference_from, sizeof t->speed_reference_from, "%s '%s' (clip '%s', %s)",
             *rule ? rule : "the slowest locomotion state", an->states[pick].name, c->name, c->speed.method);
}

cb_status roster_decide_states(const cb_catalog *cat, const cb_catalog_animal *an, cb_roster_type *t, cb_error *err)
{
    free(t->state_sync);
    t->state_sync = calloc(an->state_count ? an->state_count : 1, sizeof *t->state_sync);
    if (!t->state_sync) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t s = 0; s < an->state_count; ++s) {
        const cb_roster_clip *c = &t->clips[t->state_clip[s]];
        cb_decide_sync(&an->states[s], c->name, c->loops, &c->speed, !an->speed_auto, &t->state_sync[s]);
    }
    speed_reference(an, t);
    for (uint32_t s = 0; s < an->state_count; ++s) {
        const cb_roster_clip *c = &t->clips[t->state_clip[s]];
        if (!t->state_sync[s].speed || c->speed.speed > 0 || t->speed_reference > 0) continue;
        char where[1100];
        return cb_fail(err, CB_ERR_INPUT,
                       "%s: [animal.%s] state '%s' follows the speed (%s), but clip '%s' has no ground speed (no stride, "
                       "no root travel) and no other state gives one; give the animal speed_reference = UNITS_PER_S, or the "
                       "state sync = \"time\"",
                       roster_at(cat, an->states[s].pos, where, sizeof where), an->name, an->states[s].name,
                       t->state_sync[s].reason, c->name);
    }
    return CB_OK;
}

void roster_warn_foot_slide(cb_roster_type *t)
{
    const cb_catalog_animal *an = t->animal;
    for (uint32_t c = 0; c < t->clip_count; ++c) {
        const cb_stride *st = &t->clips[c].speed.stride;
        cb_herd_slide slide; /* what a herd shows: with the per-row travel, the slide it leaves */
        cb_herd_slide_decide(st, &t->clips[c].travel, &slide);
        bool synced = false;
        for (uint32_t s = 0; s < an->state_count; ++s) synced |= t->state_clip[s] == (int)c && t->state_sync[s].speed;
        if (!synced || !slide.warn) continue;
        double lo = INFINITY, hi = 0;
        for (uint32_t k = 0; k < st->foot_count; ++k)
            if (st->feet[k].strides) lo = fmin(lo, st->feet[k].step_speed), hi = fmax(hi, st->feet[k].step_speed);
        /* The words follow the numbers: feet whose mean speeds differ by a quarter or more cannot all
         * be planted by one rate; feet that agree on average slide within each stance instead. */
        const char *why = hi > 1.25 * lo ? "so no one rate plants them all"
                                         : "together on average, but each slides back and forth within its stance";
        char how[64]; /* the worst moment is measured without the travel */
        if (slide.with_travel) snprintf(how, sizeof how, " with its per-row travel");
        else snprintf(how, sizeof how, " (worst %.0f%%)", 100 * slide.worst);
        cb_warn(&t->warnings, "warning",
                "clip '%s': its planted feet slide %.0f%% of the ground speed on average%s at any speed: "
                "its feet step back at %.3g to %.3g units/s, %s; the asset itself slides (plant_feet = true or "
                "--plant-feet turns its legs at bake time so planted feet stay; or re-time the feet in the animation)",
                t->clips[c].name, 100 * slide.mean, how, lo, hi, why);
    }
}

void roster_note_planted(const cb_bake_job *job, cb_roster_type *t)
{
    const cb_plant_report *r = cb_bake_job_plant_report(job);
    for (uint32_t c = 0; r && c < r->clip_count && c < t->clip_count; ++c)
        if (r->clips[c].planted) {
            t->clips[c].plant = r->clips[c];
            cb_warn(&t->warnings, "note", "clip '%s' (plant_feet): %s", t->clips[c].name, r->clips[c].why);
        }
}
