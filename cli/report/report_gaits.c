/* report_gaits.c - the report's foot-sync section: each state that follows the instance's speed,
 * its ground speed and how far its planted feet slide there (cb_stride), as a share of that
 * speed; a gait whose feet slide past CB_SLIDE_WARN at any rate is a warning (herd_slide.h decides both). */
#include "report_parts.h"
#include "crowdbake/herd_slide.h"

#include <stdlib.h>
#include <string.h>

void report_fill_gaits(const cb_roster_type *rt, cb_report_type *t)
{
    const cb_catalog_animal *an = rt->animal;
    t->gaits = calloc(an->state_count ? an->state_count : 1, sizeof *t->gaits);
    for (uint32_t s = 0; t->gaits && s < an->state_count; ++s) {
        if (!rt->state_sync[s].speed) continue;
        const cb_roster_clip *c = &rt->clips[rt->state_clip[s]];
        cb_report_gait *g = &t->gaits[t->gait_count++];
        g->state = an->states[s].name;
        snprintf(g->clip, sizeof g->clip, "%s", c->name);
        g->ground_speed = c->speed.speed > 0 ? c->speed.speed : rt->speed_reference;
        cb_herd_slide slide; /* what a herd shows: the slide the offsets leave, where they ship */
        cb_herd_slide_decide(&c->speed.stride, &c->travel, &slide);
        g->stride = slide.measured;
        g->slide_mean = slide.mean, g->slide_worst = slide.worst, g->slides = slide.warn;
        if ((g->row_travel = slide.with_travel)) g->slide_without = slide.without;
    }
}

uint32_t report_gait_warnings(const cb_report_type *t)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < t->gait_count; ++i) n += t->gaits[i].slides;
    return n;
}

/* "49% (worst 235%)", "12% with its per-row travel (35% without)", or why nothing is measured. */
static const char *slide_text(const cb_report_gait *g, char *buf, size_t size)
{
    if (!g->stride) snprintf(buf, size, "not measured (no stride: its speed is its root's travel)");
    else if (g->row_travel)
        snprintf(buf, size, "%.0f%% with its per-row travel (%.0f%% without)%s", 100 * g->slide_mean,
                 100 * g->slide_without, g->slides ? ": FEET SLIDE AT ANY RATE" : "");
    else snprintf(buf, size, "%.0f%% (worst %.0f%%)%s", 100 * g->slide_mean, 100 * g->slide_worst,
                  g->slides ? ": FEET SLIDE AT ANY RATE" : "");
    return buf;
}

void report_gaits_text(FILE *f, const cb_report *r)
{
    bool any = false;
    char slide[96];
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].gait_count; ++k) {
            const cb_report_gait *g = &r->types[i].gaits[k];
            if (!any) fprintf(f, "\nFoot-sync (states that follow the speed; planted feet's slide as a share of the ground speed):\n");
            any = true;
            fprintf(f, "%-14s %-10s %-28s %9.3g units/s  slide %s\n", r->types[i].name, g->state, g->clip, g->ground_speed,
                    slide_text(g, slide, sizeof slide));
        }
    if (any) fputc('\n', f);
}

void report_gaits_markdown(FILE *f, const cb_report *r)
{
    bool any = false;
    char slide[96];
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].gait_count; ++k) {
            const cb_report_gait *g = &r->types[i].gaits[k];
            if (!any) fputs("\n### Foot-sync\n\n| type | state | clip | ground speed (units/s) | feet slide (share of the ground "
                            "speed) |\n|---|---|---|--:|---|\n", f);
            any = true;
            fprintf(f, "| %s | %s | %s | %.3g | %s |\n", r->types[i].name, g->state, g->clip, g->ground_speed,
                    slide_text(g, slide, sizeof slide));
        }
}

void report_gaits_json(cb_json *j, const cb_report_type *t)
{
    cb_json_array(j, "gaits");
    for (uint32_t k = 0; k < t->gait_count; ++k) {
        const cb_report_gait *g = &t->gaits[k];
        cb_json_object(j, NULL);
        cb_json_string(j, "state", g->state);
        cb_json_string(j, "clip", g->clip);
        cb_json_number(j, "ground_speed", g->ground_speed);
        cb_json_bool(j, "stride", g->stride);
        if (g->stride) {
            cb_json_number(j, "slide_mean", g->slide_mean);
            cb_json_number(j, "slide_worst", g->slide_worst);
            cb_json_bool(j, "row_travel", g->row_travel);
            if (g->row_travel) cb_json_number(j, "slide_mean_without_row_travel", g->slide_without);
        }
        cb_json_bool(j, "feet_slide_at_any_rate", g->slides);
        cb_json_end(j);
    }
    cb_json_end(j);
}

/* Two sliding gaits are one warning when they are the same clip of the same model (types on one
 * model, or two states on one clip): same name and the same measured slide. */
static bool same_warning(const cb_report_gait *a, const cb_report_gait *b)
{
    return strcmp(a->clip, b->clip) == 0 && a->slide_mean == b->slide_mean && a->slide_worst == b->slide_worst;
}

/* Whether gait k of type i is the first of its group (no earlier type or state has it). */
static bool first_of_group(const cb_report *r, uint32_t i, uint32_t k)
{
    for (uint32_t a = 0; a <= i; ++a)
        for (uint32_t b = 0; b < (a == i ? k : r->types[a].gait_count); ++b)
            if (r->types[a].gaits[b].slides && same_warning(&r->types[a].gaits[b], &r->types[i].gaits[k])) return false;
    return true;
}

/* The bake's own warnings (a fixed fps over max_error, ...) beside the gaits' (whose foot-slide
 * lines the gaits above group), each text once with the types that have it. */
static bool is_foot_slide(const char *message) { return strstr(message, "its planted feet slide") != NULL; }

static bool bake_warnings_html(FILE *f, const cb_report *r, bool any)
{
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_warnings *w = r->types[i].bake_warnings;
        for (uint32_t k = 0; w && k < w->count; ++k) {
            const char *m = w->items[k].message;
            if (strcmp(w->items[k].kind, "warning") != 0 || is_foot_slide(m)) continue;
            bool seen = false;
            for (uint32_t a = 0; a < i && !seen; ++a)
                for (uint32_t b = 0; r->types[a].bake_warnings && b < r->types[a].bake_warnings->count; ++b)
                    seen |= strcmp(r->types[a].bake_warnings->items[b].message, m) == 0;
            if (seen) continue;
            if (!any) fputs("<h2>Warnings</h2>\n<ul id=\"warnings\">", f);
            any = true;
            fputs("<li class=\"warn\">", f);
            for (uint32_t a = i, listed = 0; a < r->type_count; ++a)
                for (uint32_t b = 0; r->types[a].bake_warnings && b < r->types[a].bake_warnings->count; ++b)
                    if (strcmp(r->types[a].bake_warnings->items[b].message, m) == 0) {
                        fputs(listed++ ? ", " : "", f);
                        report_html_escape(f, r->types[a].name);
                    }
            fputs(": ", f);
            report_html_escape(f, m);
            fputs("</li>", f);
        }
    }
    return any;
}

void report_warnings_html(FILE *f, const cb_report *r)
{
    char limits[192], slide[96];
    bool any = false;
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        if (!report_limit_warnings(t, limits, sizeof limits)[0]) continue;
        if (!any) fputs("<h2>Warnings</h2>\n<ul id=\"warnings\">", f);
        any = true;
        fputs("<li class=\"warn\">", f);
        report_html_escape(f, t->name);
        fprintf(f, ": %s</li>", limits);
    }
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].gait_count; ++k) {
            const cb_report_gait *g = &r->types[i].gaits[k];
            if (!g->slides || !first_of_group(r, i, k)) continue;
            if (!any) fputs("<h2>Warnings</h2>\n<ul id=\"warnings\">", f);
            any = true;
            uint32_t count = 0;
            for (uint32_t a = i; a < r->type_count; ++a)
                for (uint32_t b = 0; b < r->types[a].gait_count; ++b)
                    count += r->types[a].gaits[b].slides && same_warning(&r->types[a].gaits[b], g);
            fputs("<li class=\"warn\">clip <b>", f);
            report_html_escape(f, g->clip);
            fprintf(f, "</b> (%.3g units/s): feet slide %s &middot; <span class=\"count\">%u&times;</span> (", g->ground_speed,
                    slide_text(g, slide, sizeof slide), count);
            for (uint32_t a = i, listed = 0; a < r->type_count; ++a)
                for (uint32_t b = 0; b < r->types[a].gait_count; ++b)
                    if (r->types[a].gaits[b].slides && same_warning(&r->types[a].gaits[b], g)) {
                        fputs(listed++ ? ", " : "", f);
                        report_html_escape(f, r->types[a].name);
                        fputc(' ', f);
                        report_html_escape(f, r->types[a].gaits[b].state);
                    }
            fputs("): the asset's feet slide; re-time them in the animation, or accept it</li>", f);
        }
    any |= bake_warnings_html(f, r, any);
    if (any) fputs("</ul>\n", f);
}
