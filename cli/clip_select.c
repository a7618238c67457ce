/* clip_select.c - --clip and --exclude-clip, as bake, vat and verify take them; --loop and
 * --one-shot, as bake takes them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "catalog/catalog.h"
#include "cli.h"
#include "internal/plumbing.h"

cb_status cli_for_each_name(const char *list, cb_status (*fn)(const char *name, void *ctx), void *ctx)
{
    char name[256];
    for (const char *p = list; p && *p;) {
        const char *comma = strchr(p, ',');
        size_t n = comma ? (size_t)(comma - p) : strlen(p);
        snprintf(name, sizeof name, "%.*s", (int)(n < sizeof name ? n : sizeof name - 1), p);
        cb_status rc = fn(name, ctx);
        if (rc) return rc;
        p = comma ? comma + 1 : p + n;
    }
    return CB_OK;
}

int cli_match_clip(const char *typed, const char *const *names, size_t count, size_t stride, char *why, size_t size)
{
    return cb_match_clip_name(typed, names, count, stride, why, size);
}

typedef struct clip_check {
    const cb_palette *p;
    const char *palette, *option;
    bool *named; /* per palette clip: the list names it */
    cb_error *err;
} clip_check;

static cb_status mark_palette_clip(const char *name, void *ctx)
{
    const clip_check *c = ctx;
    char why[512];
    int i = c->p->clip_count ? cli_match_clip(name, &c->p->clips[0].name, c->p->clip_count, sizeof c->p->clips[0], why,
                                              sizeof why)
                             : (snprintf(why, sizeof why, "the palette has no clip"), -1);
    if (i < 0) return cb_fail(c->err, CB_ERR_SETTINGS, "%s: %s %s: %s (see 'crowdbake inspect')", c->palette, c->option, name, why);
    c->named[i] = true;
    return CB_OK;
}

cb_status cli_palette_clip_options(const cb_palette *p, const char *palette, const char *clips, const char *excluded,
                                    bool *skip, cb_error *err)
{
    if (clips && excluded) return cb_fail(err, CB_ERR_SETTINGS, "give --clip or --exclude-clip, not both");
    clip_check c = {p, palette, clips ? "--clip" : "--exclude-clip", skip, err};
    if (cli_for_each_name(clips ? clips : excluded, mark_palette_clip, &c)) return err->status;
    for (uint32_t i = 0; clips && i < p->clip_count; ++i) skip[i] = !skip[i]; /* named: verified */
    return CB_OK;
}

typedef struct selection {
    const cb_model *model;
    bool *chosen;         /* per animation */
    cb_clip_plan *plan;
    uint32_t count;
    const char *option;
    cb_error *err;
} selection;

/* The model's animation that `name` picks (cli_match_clip); an error naming why when none does. */
static int32_t find_clip(selection *s, const char *name)
{
    const cb_model *m = s->model;
    const struct cb_skipped_clip *skip = cb_model_find_skipped_clip(m, name);
    if (skip && cb_model_find_animation(m, name) < 0)
        return cb_fail(s->err, CB_ERR_INPUT, "%s (%s %s asked for it)", skip->reason, s->option, name), -1;
    char why[512];
    int a = m->animation_count ? cli_match_clip(name, &m->animations[0].name, m->animation_count, sizeof m->animations[0],
                                                why, sizeof why)
                               : (snprintf(why, sizeof why, "no clip '%s'; the model has none", name), -1);
    if (a < 0) cb_fail(s->err, CB_ERR_SETTINGS, "%s: %s %s: %s", m->source, s->option, name, why);
    return a;
}

static cb_status include(const char *name, void *ctx)
{
    selection *s = ctx;
    int32_t a = find_clip(s, name);
    if (a < 0) return s->err->status;
    if (s->chosen[a]) return cb_fail(s->err, CB_ERR_SETTINGS, "%s: --clip names '%s' twice", s->model->source, name);
    s->chosen[a] = true;
    s->plan[s->count++] = (cb_clip_plan){a, NULL, -1, 0, false, false, 0, NULL};
    return CB_OK;
}

static cb_status exclude(const char *name, void *ctx)
{
    selection *s = ctx;
    if (cb_model_find_skipped_clip(s->model, name)) return CB_OK; /* left out already */
    int32_t a = find_clip(s, name);
    if (a < 0) return s->err->status;
    s->chosen[a] = true;
    return CB_OK;
}

cb_status cli_select_clips(const cb_model *m, const char *clips, const char *excluded, cb_clip_plan **plan,
                           uint32_t *count, cb_error *err)
{
    *plan = NULL;
    *count = 0;
    if (!clips && !excluded) return CB_OK;
    selection s = {m, calloc(m->animation_count + 1, sizeof(bool)), calloc(m->animation_count + 1, sizeof(cb_clip_plan)),
                   0, clips ? "--clip" : "--exclude-clip", err};
    if (!s.chosen || !s.plan) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    else if (clips && excluded) cb_fail(err, CB_ERR_SETTINGS, "give --clip or --exclude-clip, not both");
    else if (clips) cli_for_each_name(clips, include, &s);
    else if (!cli_for_each_name(excluded, exclude, &s))
        for (uint32_t a = 0; a < m->animation_count; ++a)
            if (!s.chosen[a]) s.plan[s.count++] = (cb_clip_plan){(int32_t)a, NULL, -1, 0, false, false, 0, NULL};
    if (!err->status && s.count == 0)
        cb_fail(err, CB_ERR_SETTINGS, "%s: no clip left to bake after %s", m->source, s.option);
    free(s.chosen);
    if (err->status) {
        free(s.plan);
        return err->status;
    }
    *plan = s.plan;
    *count = s.count;
    return CB_OK;
}

/* One --loop or --one-shot name: its clip's entry in the plan gets `loop`. */
typedef struct loop_override {
    const cb_model *model;
    cb_clip_plan *plan;
    uint32_t count;
    int loop;            /* 1: --loop, 0: --one-shot */
    const char *option, *other; /* the flag, and the other flag's list (a clip in both is an error) */
    cb_error *err;
} loop_override;

static cb_status override_loop(const char *name, void *ctx)
{
    loop_override *o = ctx;
    selection s = {o->model, NULL, NULL, 0, o->option, o->err};
    int32_t a = find_clip(&s, name);
    if (a < 0) return o->err->status;
    if (cli_list_has(o->other, name))
        return cb_fail(o->err, CB_ERR_SETTINGS, "%s: '%s' is given to both --loop and --one-shot", o->model->source, name);
    bool found = false;
    for (uint32_t i = 0; i < o->count; ++i)
        if (o->plan[i].animation == a) o->plan[i].loop = o->loop, found = true;
    if (!found)
        return cb_fail(o->err, CB_ERR_SETTINGS, "%s: %s %s: the clip is not among those baked (see --clip, --exclude-clip)",
                       o->model->source, o->option, name);
    return CB_OK;
}

cb_status cli_override_loops(const cb_model *m, const char *loops, const char *one_shots, cb_clip_plan **plan,
                             uint32_t *count, cb_error *err)
{
    if (!loops && !one_shots) return CB_OK;
    if (!*plan) { /* every clip, in file order, as a bake without a plan takes them */
        if (!(*plan = calloc(m->animation_count + 1, sizeof **plan))) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        for (uint32_t a = 0; a < m->animation_count; ++a) (*plan)[a] = (cb_clip_plan){(int32_t)a, NULL, -1, 0, false, false, 0, NULL};
        *count = m->animation_count;
    }
    loop_override o = {m, *plan, *count, 1, "--loop", one_shots, err};
    if (cli_for_each_name(loops, override_loop, &o)) return err->status;
    o.loop = 0, o.option = "--one-shot", o.other = loops;
    return cli_for_each_name(one_shots, override_loop, &o);
}

bool cli_list_has(const char *list, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = list; p && *p;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if (len == n && strncmp(p, name, n) == 0) return true;
        p = comma ? comma + 1 : p + len;
    }
    return false;
}

void cli_print_warnings(const cb_warnings *w, bool notes)
{
    for (uint32_t i = 0; i < w->count; ++i)
        if (notes || strcmp(w->items[i].kind, "note") != 0)
            fprintf(stderr, "crowdbake: %s: %s\n", w->items[i].kind, w->items[i].message);
}

void cli_json_warnings(cb_json *j, const cb_warnings *w)
{
    cb_json_array(j, "warnings");
    for (uint32_t i = 0; i < w->count; ++i) {
        cb_json_object(j, NULL);
        cb_json_string(j, "kind", w->items[i].kind);
        cb_json_string(j, "message", w->items[i].message);
        cb_json_end(j);
    }
    cb_json_end(j);
}
