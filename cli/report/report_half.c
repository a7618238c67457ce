/* report_half.c - whether halving a type's frame rate keeps it within its error budget, measured
 * as the bake measures (cb_palette_bake's visible error: the runtime's blend of two rows), so the
 * report never advises a change that breaks max_error. An error-bounded clip already plays at
 * the fewest rows within it, so halving it is expected to fail; a fixed fps may have room. */
#include "report/report_runtime.h"

#include <stdlib.h>
#include <string.h>

#include "crowdbake/bake.h"
#include "crowdbake/gltf.h"
#include "roster/roster.h"

/* The model's animation a palette clip came from: its own name, or a catalog entry's rename. */
static int32_t clip_animation(const cb_model *m, const cb_catalog_animal *an, const char *name)
{
    int32_t a = cb_model_find_animation(m, name);
    char why[512];
    for (uint32_t k = 0; a < 0 && an->clips && k < an->clip_count; ++k)
        if (strcmp(an->clips[k].name, name) == 0 && m->animation_count)
            a = cb_match_clip_name(an->clips[k].source, &m->animations[0].name, m->animation_count,
                                   sizeof m->animations[0], why, sizeof why);
    return a;
}

/* A clip's budget: its catalog entry's max_error, else the type's. */
static double clip_budget(const cb_catalog_animal *an, const char *name)
{
    for (uint32_t k = 0; an->clips && k < an->clip_count; ++k)
        if (strcmp(an->clips[k].name, name) == 0 && an->clips[k].max_error_mm > 0) return an->clips[k].max_error_mm;
    return an->bake.max_error_mm;
}

void report_measure_half_rate(cb_sampler *s, const cb_roster_type *owner, cb_report_runtime *out)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_catalog_animal *an = owner->animal;
    cb_clip_plan *plan = calloc(owner->clip_count ? owner->clip_count : 1, sizeof *plan);
    if (!plan || !owner->clip_count) return free(plan);
    for (uint32_t i = 0; i < owner->clip_count; ++i) {
        const cb_roster_clip *c = &owner->clips[i];
        plan[i] = (cb_clip_plan){clip_animation(m, an, c->name), c->name, c->loops ? 1 : 0, c->fps / 2, false, false, 0, NULL};
        if (plan[i].animation < 0) return free(plan); /* not measurable: no advice */
    }
    cb_bake_options o = cb_bake_settings_options(&an->bake, CB_FORMAT_PAL, NULL, 1);
    o.layout = owner->layout, o.precision = owner->precision;
    cb_palette p;
    cb_error err = {0};
    if (!cb_palette_bake(s, &o, plan, owner->clip_count, &p, &err)) {
        out->half_rate_measured = true;
        out->half_rate_within = true;
        for (uint32_t i = 0; i < p.clip_count; ++i) {
            double mm = cb_mm_per_m(p.clips[i].visible_error, p.model_height), budget = clip_budget(an, owner->clips[i].name);
            if (mm > out->half_rate_error_mm) out->half_rate_error_mm = mm;
            if (budget > 0 && mm > budget) out->half_rate_within = false;
        }
        cb_palette_free(&p);
    }
    free(plan);
}
