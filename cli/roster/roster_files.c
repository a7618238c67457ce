/* roster_files.c - what a roster bake writes beside the palettes: the manifest (roster.json),
 * the Make/Ninja depfile, the output folders, and the modification times build tools read. */
#define _GNU_SOURCE /* open_memstream */
#include "roster_files.h"

#include <errno.h>
#include <fcntl.h> /* AT_FDCWD */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#include "internal/atomic_file.h"
#include "internal/json.h"
#include "internal/bake_words.h"

/* mkdir -p: the output directory and any missing parents. */
cb_status roster_make_directories(const char *dir, cb_error *err)
{
    char path[4096];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path)
        return cb_fail(err, CB_ERR_IO, "%s: output directory path too long", dir);
    for (char *p = path + 1;; ++p) {
        if (*p != '/' && *p != '\0') continue;
        char end = *p;
        *p = '\0';
        struct stat st;
        if (stat(path, &st) != 0 && mkdir(path, 0777) != 0 && errno != EEXIST)
            return cb_fail(err, CB_ERR_IO, "%s: cannot create the output directory %s: %s (check the path and its "
                           "permissions)", dir, path, strerror(errno));
        if (stat(path, &st) == 0 && !S_ISDIR(st.st_mode))
            return cb_fail(err, CB_ERR_IO, "%s: cannot create the output directory: %s is a file", dir, path);
        if (!(*p = end)) return CB_OK;
    }
}

/* ---- the manifest and the depfile ---- */

/* The speed a state's clip plays at rate 1: its own ground speed, or the animal's given (or
 * measured) speed reference where the clip has none or the catalog gives one. */
static double state_speed(const cb_roster_type *t, const cb_roster_clip *c)
{
    return t->animal->speed_auto && c->speed.speed > 0 ? c->speed.speed : t->speed_reference;
}

static void write_state(cb_json *j, const cb_roster_type *t, uint32_t s)
{
    const cb_catalog_state *st = &t->animal->states[s];
    const cb_roster_clip *c = &t->clips[t->state_clip[s]];
    const cb_sync_decision *sync = &t->state_sync[s];
    cb_json_object(j, st->name);
    cb_json_string(j, "clip", c->name);
    cb_json_inline_array(j, "keywords");
    for (uint32_t k = 0; k < st->keyword_count; ++k) cb_json_string(j, NULL, st->keywords[k]);
    cb_json_end(j);
    /* Locomotion follows the instance's speed (rate = speed * rate_per_speed, feet planted);
     * everything else plays at its own rate, also at standstill (a dying animal still dies). */
    cb_json_string(j, "sync", sync->speed ? "speed" : "time");
    cb_json_string(j, "sync_reason", sync->reason);
    /* The four numbers of the per-instance data, exactly as the shader wants them. */
    cb_json_object(j, "instance");
    /* < 0: the clip's rows are held, not blended (a STEP-keyed clip), its first row -first_row - 1 */
    cb_json_int(j, "first_row", c->step ? -(long long)c->first_row - 1 : (long long)c->first_row);
    /* A timed clip (docs/pal-format.md "Timed rows"): its cells where rows were, and minus its cell rate. */
    long long frames = c->cells ? (long long)c->cells : (long long)c->frames;
    double rate = c->cells ? -c->cell_rate : c->fps;
    cb_json_int(j, "frame_count", c->loops ? frames : -frames); /* < 0: one-shot, clamps */
    cb_json_float32(j, "rate", (float)rate); /* the clip's fps, written alike */
    cb_json_number(j, "rate_per_speed", sync->speed ? rate / state_speed(t, c) : 0);
    cb_json_string(j, "phase", c->loops ? "golden_ratio" : "zero");
    cb_json_end(j);
    if (t->animal->bake.formats & CB_FORMAT_BABYLON) roster_json_babylon_play(j, t, (uint32_t)t->state_clip[s]);
    cb_json_end(j);
}

/* Footsteps: each striding foot's landings and lifts, in landing order over the cycle. */
static void write_contacts(cb_json *j, const cb_stride *st)
{
    const cb_foot *order[CB_MAX_FEET * CB_MAX_STANCES];
    const cb_stance *stance[CB_MAX_FEET * CB_MAX_STANCES];
    uint32_t n = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k)
        for (uint32_t s = 0; st->feet[k].strides && s < st->feet[k].stance_count; ++s) {
            uint32_t at = n++;
            for (; at > 0 && stance[at - 1]->land > st->feet[k].stances[s].land; --at)
                order[at] = order[at - 1], stance[at] = stance[at - 1];
            order[at] = &st->feet[k], stance[at] = &st->feet[k].stances[s];
        }
    cb_json_array(j, "contacts");
    for (uint32_t i = 0; i < n; ++i) {
        cb_json_object(j, NULL);
        cb_json_string(j, "foot", order[i]->name);
        cb_json_int(j, "bone", order[i]->joint);
        cb_json_number(j, "time", stance[i]->land);
        cb_json_number(j, "lift", stance[i]->lift);
        cb_json_end(j);
    }
    cb_json_end(j);
}

void cb_roster_json_sockets(cb_json *j, const cb_socket *sockets, uint32_t count)
{
    cb_json_array(j, "sockets");
    for (uint32_t i = 0; i < count; ++i) {
        cb_json_object(j, NULL);
        cb_json_string(j, "name", sockets[i].name);
        cb_json_int(j, "bone", sockets[i].bone);
        cb_json_inline_array(j, "bind_transform"); /* the prop's world: instance x bone matrix x this */
        for (int e = 0; e < 16; ++e) cb_json_number(j, NULL, sockets[i].bind_transform[e]);
        cb_json_end(j);
        cb_json_end(j);
    }
    cb_json_end(j);
}

void cb_roster_json_plant(cb_json *j, const cb_plant_clip *c)
{
    cb_json_bool(j, "planted", c->planted);
    cb_json_string(j, "why", c->why);
    cb_json_number(j, "ground_speed", c->speed);
    cb_json_int(j, "feet", c->feet);
    cb_json_number(j, "slide_before", c->slide_before);
    cb_json_number(j, "slide_worst_before", c->slide_worst_before);
    cb_json_number(j, "slide_after", c->planted ? c->slide_after : c->slide_before);
    cb_json_number(j, "slide_worst_after", c->planted ? c->slide_worst_after : c->slide_worst_before);
    cb_json_number(j, "max_rotation_deg", c->max_rotation_deg);
    cb_json_number(j, "max_shortfall", c->max_shortfall);
}

void cb_roster_json_stride(cb_json *j, const cb_stride *st)
{
    cb_json_bool(j, "stride", st->stride);
    cb_json_string(j, "stride_reason", st->why);
    if (!st->stride) return;
    cb_json_object(j, "foot_slide");
    cb_json_number(j, "mean", st->slide_mean);
    cb_json_number(j, "worst", st->slide_worst);
    cb_json_number(j, "mean_with_per_row_travel", st->slide_mean_varying); /* stride.h's estimate; row_travel says what ships */
    cb_json_array(j, "feet");
    for (uint32_t k = 0; k < st->foot_count; ++k) {
        const cb_foot *f = &st->feet[k];
        if (!f->strides) continue;
        cb_json_object(j, NULL);
        cb_json_string(j, "foot", f->name);
        cb_json_int(j, "bone", f->joint);
        cb_json_number(j, "stance", f->stance);
        cb_json_number(j, "step_speed", f->step_speed);
        cb_json_number(j, "mean", f->slide_mean);
        cb_json_number(j, "worst", f->slide_worst);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_json_end(j);
    write_contacts(j, st);
}

void cb_roster_json_row_travel(cb_json *j, const cb_row_travel *t)
{
    cb_json_object(j, "row_travel");
    cb_json_bool(j, "applied", t->applied); /* the .pal carries the clip's offsets (version 5) */
    cb_json_string(j, "reason", t->why);
    if (t->slide_mean > 0) { /* measured: a striding loop in place */
        cb_json_number(j, "slide_mean", t->slide_mean);
        cb_json_number(j, "slide_mean_with_offsets", t->slide_with);
    }
    if (t->applied) {
        cb_json_inline_array(j, "heading");
        for (int k = 0; k < 3; ++k) cb_json_number(j, NULL, t->heading[k]);
        cb_json_end(j);
    }
    cb_json_end(j);
}

/* `p` as an absolute path without "." or ".." steps or repeated slashes, worked out from the
 * text and the current directory alone: symbolic links are not followed, so where a build
 * engine's sandbox links its inputs from changes nothing the manifest says. */
static void lexical_absolute(const char *p, char *out, size_t size)
{
    char joined[8192] = "";
    if (p[0] != '/' && !getcwd(joined, sizeof joined)) joined[0] = '\0';
    size_t n = strlen(joined);
    snprintf(joined + n, sizeof joined - n, "/%s", p);
    size_t len = 0;
    out[0] = '\0';
    for (char *save = NULL, *step = strtok_r(joined, "/", &save); step; step = strtok_r(NULL, "/", &save)) {
        if (strcmp(step, ".") == 0) continue;
        if (strcmp(step, "..") == 0) {
            char *slash = strrchr(out, '/');
            len = slash ? (size_t)(slash - out) : 0;
            out[len] = '\0';
            continue;
        }
        int k = snprintf(out + len, size - len, "/%s", step);
        if (k > 0 && (size_t)k < size - len) len += (size_t)k;
    }
    if (!len) snprintf(out, size, "/");
}

/* `path` relative to directory `dir` (both as the catalog resolved them, or absolute), so a
 * game resolves palette paths against the manifest's own directory. */
static void relative_path(const char *dir, const char *path, char *out, size_t size)
{
    char a[4096], b[4096];
    lexical_absolute(dir, a, sizeof a);
    lexical_absolute(path, b, sizeof b);
    if (strcmp(a, "/") == 0) a[0] = '\0'; /* the root: every path is below it */
    size_t common = 0, i = 0;
    for (; a[i] && a[i] == b[i]; ++i)
        if (a[i] == '/') common = i;
    if (!a[i] && b[i] == '/') common = i; /* dir is a prefix of path */
    out[0] = '\0';
    for (const char *p = a + common; *p; ++p)
        if (*p == '/') strncat(out, "../", size - strlen(out) - 1);
    strncat(out, b + common + 1, size - strlen(out) - 1);
}

/* What the bake did with a clip's root travel, and why: the catalog's or the command line's
 * root_motion; else, where a loop of the type travels, the loops in place (their velocity
 * recorded for the game to move the instance) and the one-shots keeping theirs; else nothing
 * taken out (cb_bake_job_plan decides it so). */
static void root_motion_reason(const cb_roster_type *t, const cb_roster_clip *c, char *why, size_t size)
{
    const cb_bake_settings *b = &t->animal->bake;
    double travel = c->speed.root * c->duration;
    cb_clip_info info = {.duration = c->duration, .loops = c->loops, .ground_speed = c->speed.root};
    bool travels = cb_clip_travels(&info, t->model_height), decided = false;
    for (uint32_t i = 0; i < t->clip_count; ++i) decided |= t->clips[i].in_place;
    if (b->from.root_motion != CB_FROM_DEFAULT)
        snprintf(why, size, "root_motion = \"%s\" (%s)", cb_root_motion_name(b->root_motion), cb_setting_from_name(b->from.root_motion));
    else if (decided && c->in_place && !travels)
        snprintf(why, size, "in place with the type's loops that travel (its own root moves %.3g units a loop, under 1%% of "
                 "the model's height) (root_motion = \"keep\" overrides)", travel);
    else if (decided && c->in_place)
        snprintf(why, size, "a loop travelling %.3g units a loop, which its wrap would pull back: in place, its velocity "
                 "%.3g units/s recorded for the game to move the instance (root_motion = \"keep\" overrides)", travel, c->speed.root);
    else if (decided)
        snprintf(why, size, "a one-shot keeps its travel (%.3g units), ending where it moved (root_motion = \"in-place\" "
                 "overrides)", travel);
    else
        snprintf(why, size, "no loop of the type travels%s, so nothing is taken out (root_motion overrides)",
                 travels ? "" : " and neither does this clip");
}

/* "animation_lod": what a far instance's fewer influences cost, for every runtime's LOD thresholds
 * (docs/roster.md). */
static void write_lod_error(cb_json *j, const cb_lod_error *e)
{
    cb_json_object(j, "animation_lod");
    cb_json_number(j, "two_influences_error", e->two);
    cb_json_number(j, "one_influence_error", e->one);
    cb_json_int(j, "frames", e->frames);
    cb_json_end(j);
}

static void write_type(cb_json *j, const cb_roster *r, const cb_roster_type *t, const char *manifest_dir)
{
    const cb_roster_type *owner = &r->types[t->owner];
    const cb_catalog_animal *an = t->animal;
    char rel[4096];
    cb_json_object(j, an->name);
    relative_path(manifest_dir, an->model, rel, sizeof rel);
    cb_json_string(j, "model", rel);
    for (uint32_t k = 0; k < cb_output_format_count(); ++k) { /* each file under its format's key */
        const cb_output_format *f = cb_output_format_at(k);
        if (!(owner->animal->bake.formats & f->format)) continue;
        relative_path(manifest_dir, owner->paths[k], rel, sizeof rel);
        cb_json_string(j, f->manifest_key, rel);
    }
    if (t->owner != (uint32_t)(t - r->types)) cb_json_string(j, "shares_palette_of", owner->animal->name);
    cb_json_string(j, "layout", cb_layout_name(owner->layout));
    cb_json_string(j, "precision", cb_precision_name(owner->precision));
    char why[600];
    bool local = roster_local_rows(owner);
    cb_bake_bone_space_why(&owner->animal->bake, CB_FORMAT_PAL, local ? CB_BONE_SPACE_LOCAL : CB_BONE_SPACE_GLOBAL,
                           NULL, why, sizeof why);
    cb_json_string(j, "bone_space", local ? "local" : "global"); /* of the .pal: other formats hold global rows */
    cb_json_string(j, "bone_space_why", why);
    cb_json_int(j, "bones", t->bones);
    cb_json_int(j, "texels_per_bone", cb_layout_texels_per_bone(owner->layout));
    cb_json_int(j, "rows", owner->rows);
    cb_json_int(j, "width", owner->width);
    cb_json_int(j, "height", owner->height);
    cb_json_int(j, "blocks", owner->blocks);
    /* Errors in mm per metre of model height: the encoding's at the baked rows, and what a player
     * sees (the runtime's blend of two rows). */
    double per_m = t->model_height > 0 ? 1000 / t->model_height : 0;
    cb_json_number(j, "encoding_error_mm_per_m", owner->max_error * per_m);
    cb_json_number(j, "visible_error_mm_per_m", owner->visible_error * per_m);
    cb_json_number(j, "speed_reference", t->speed_reference);
    cb_json_string(j, "speed_reference_from", t->speed_reference_from);
    cb_json_string(j, "default_state", an->default_state ? an->default_state : "");
    cb_json_string(j, "default_state_from", an->default_state_from ? an->default_state_from : "no states");
    cb_json_array(j, "clips");
    for (uint32_t c = 0; c < t->clip_count; ++c) {
        const cb_roster_clip *cl = &t->clips[c];
        cb_json_object(j, NULL);
        cb_json_string(j, "name", cl->name);
        cb_json_int(j, "first_row", cl->first_row);
        cb_json_int(j, "frame_count", cl->frames);
        cb_json_float32(j, "fps", (float)cl->fps); /* as the files record it, without float32 noise */
        cb_json_number(j, "duration", cl->duration);
        cb_json_bool(j, "loops", cl->loops);
        cb_json_string(j, "loop_reason", cl->loop_reason);
        char why[512];
        root_motion_reason(t, cl, why, sizeof why);
        cb_json_string(j, "root_motion", cl->in_place ? "in-place" : "keep");
        cb_json_string(j, "root_motion_reason", why);
        if (cl->visible_error_mm >= 0) cb_json_number(j, "visible_error_mm_per_m", cl->visible_error_mm);
        cb_json_string(j, "rate_reason", cl->rate_reason);
        if (cl->step) cb_json_bool(j, "step_rows", true); /* held, not blended: .pal clip flag bit 2 */
        if (cl->cells) { /* timed rows (.pal clip flag bit 3): the map's cells, rate and rows before first_row */
            cb_json_object(j, "timed_rows");
            cb_json_int(j, "cells", cl->cells);
            cb_json_number(j, "cell_rate", cl->cell_rate);
            cb_json_int(j, "map_rows", cl->map_rows);
            cb_json_end(j);
        }
        cb_json_number(j, "ground_speed", cl->speed.speed);
        cb_json_number(j, "root_speed", cl->speed.root);
        cb_json_number(j, "feet_speed", cl->speed.feet);
        cb_json_string(j, "speed_method", cl->speed.method);
        cb_roster_json_stride(j, &cl->speed.stride);
        if (cl->plant.planted) { /* plant_feet: the slide above is after; what it was, and what changed */
            cb_json_object(j, "plant_feet");
            cb_roster_json_plant(j, &cl->plant);
            cb_json_end(j);
        }
        cb_roster_json_row_travel(j, &cl->travel);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_json_object(j, "states");
    for (uint32_t s = 0; s < an->state_count; ++s) write_state(j, t, s);
    cb_json_end(j);
    cb_json_array(j, "lods");
    for (uint32_t l = 0; l < t->lod_count; ++l) {
        cb_json_object(j, NULL);
        relative_path(manifest_dir, t->lods[l].path, rel, sizeof rel);
        cb_json_string(j, "model", rel);
        cb_json_inline_array(j, "joint_remap");
        for (uint32_t k = 0; k < t->lods[l].joint_count; ++k) cb_json_int(j, NULL, t->lods[l].remap[k]);
        cb_json_end(j);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_roster_json_sockets(j, t->sockets, t->socket_count);
    write_lod_error(j, &t->lod_error);
    cb_json_end(j);
}

/* Writes `data` to path unless the file already holds exactly it (mtimes stay put). */
cb_status roster_write_if_changed(const char *path, const char *data, size_t size, bool *written, cb_error *err)
{
    *written = false;
    FILE *f = fopen(path, "rb");
    if (f) {
        char *old = malloc(size + 1);
        size_t got = old ? fread(old, 1, size + 1, f) : 0;
        fclose(f);
        bool same = old && got == size && memcmp(old, data, size) == 0;
        free(old);
        if (same) return CB_OK;
    }
    cb_atomic_file af;
    if (cb_atomic_open(&af, path, err)) return err->status;
    if (cb_atomic_write(&af, data, size, err)) {
        cb_atomic_abort(&af);
        return err->status;
    }
    if (cb_atomic_commit(&af, err)) return err->status;
    *written = true;
    return CB_OK;
}

void roster_write_record(const char *path, const unsigned char *data, size_t size)
{
    cb_error ignored = {0};
    bool written;
    roster_write_if_changed(path, (const char *)data, size, &written, &ignored);
}

cb_status roster_write_manifest(const cb_catalog *cat, cb_roster *r, const char *path, cb_error *err)
{
    char *buf = NULL;
    size_t size = 0;
    FILE *mem = open_memstream(&buf, &size);
    if (!mem) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash) *slash = '\0';
    else snprintf(dir, sizeof dir, ".");
    cb_json j;
    cb_json_init(&j, mem);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "schema", "crowdbake-roster/1");
    cb_json_string(&j, "generator", "crowdbake " CROWDBAKE_VERSION);
    char rel[4096];
    relative_path(dir, cat->path, rel, sizeof rel);
    cb_json_string(&j, "catalog", rel);
    cb_json_object(&j, "types");
    for (uint32_t i = 0; i < r->type_count; ++i)
        if (r->types[i].outcome != CB_TYPE_FAILED) write_type(&j, r, &r->types[i], dir);
    cb_json_end(&j);
    /* Failed types are named, not dropped: a loader sees that the roster is incomplete. */
    if (r->failed) {
        cb_json_object(&j, "failed");
        for (uint32_t i = 0; i < r->type_count; ++i) {
            const cb_roster_type *t = &r->types[i];
            if (t->outcome != CB_TYPE_FAILED) continue;
            cb_json_object(&j, t->animal->name);
            relative_path(dir, t->animal->model, rel, sizeof rel);
            cb_json_string(&j, "model", rel);
            cb_json_string(&j, "error", t->error.message);
            cb_json_end(&j);
        }
        cb_json_end(&j);
    }
    cb_json_end(&j);
    fclose(mem);
    cb_status rc = roster_write_if_changed(path, buf, size, &r->manifest_written, err);
    free(buf);
    return rc;
}

static void depfile_path(FILE *f, const char *p)
{
    for (; *p; ++p) {
        if (*p == ' ' || *p == '#' || *p == '\\') fputc('\\', f);
        if (*p == '$') fputc('$', f);
        fputc(*p, f);
    }
}

static void depfile_input(FILE *f, const char *path) { fputs(" \\\n  ", f), depfile_path(f, path); }

static void depfile_inputs(FILE *f, const cb_roster_type *t)
{
    for (uint32_t i = 0; i < t->input_count; ++i) depfile_input(f, t->inputs[i]);
}

/* Whether input k of type i was already listed by an earlier input or type. */
static bool listed_before(const cb_roster *r, uint32_t i, uint32_t k)
{
    for (uint32_t a = 0; a <= i; ++a)
        for (uint32_t b = 0; b < (a == i ? k : r->types[a].input_count); ++b)
            if (strcmp(r->types[a].inputs[b], r->types[i].inputs[k]) == 0) return true;
    return false;
}

/* A rule's target and what every rule depends on: the catalog, and the executable (an upgrade
 * re-runs the bake, which rebakes what the new version would bake differently: its version is
 * in every type's key). */
static void depfile_rule(FILE *f, const char *target, const cb_catalog *cat, const char *tool)
{
    depfile_path(f, target);
    fputs(":", f);
    fputc(' ', f), depfile_path(f, cat->path);
    if (tool && tool[0]) depfile_input(f, tool);
}

/* One rule per output: Make and Ninja both read it. */
cb_status roster_write_depfile(const cb_catalog *cat, const cb_roster *r, const cb_roster_options *opt, cb_error *err)
{
    char *buf = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&buf, &size);
    if (!f) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t i = 0; i < r->type_count && !opt->depfile_manifest_only; ++i) {
        const cb_roster_type *t = &r->types[i];
        if (t->owner != i) continue; /* failed types too: their inputs keep the build out of date */
        for (uint32_t k = 0; k < cb_output_format_count(); ++k) {
            if (!(t->animal->bake.formats & cb_output_format_at(k)->format)) continue;
            depfile_rule(f, t->paths[k], cat, opt->tool);
            for (uint32_t k = 0; k < r->type_count; ++k) /* every type sharing this palette */
                if (r->types[k].owner == i) depfile_inputs(f, &r->types[k]);
            fputc('\n', f);
        }
    }
    depfile_rule(f, r->manifest_path, cat, opt->tool);
    for (uint32_t i = 0; i < r->type_count; ++i) depfile_inputs(f, &r->types[i]);
    fputc('\n', f);
    /* An empty rule per input (as gcc -MP writes): a deleted or renamed model makes Make run the
     * bake, which names the problem, instead of stopping at "no rule to make target". */
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].input_count; ++k)
            if (!listed_before(r, i, k)) fputc('\n', f), depfile_path(f, r->types[i].inputs[k]), fputs(":\n", f);
    if (opt->tool && opt->tool[0]) fputc('\n', f), depfile_path(f, opt->tool), fputs(":\n", f);
    fclose(f);
    bool written;
    cb_status rc = roster_write_if_changed(opt->depfile, buf, size, &written, err);
    free(buf);
    return rc;
}

cb_status roster_make_parent_directories(const char *file, cb_error *err)
{
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", file);
    char *slash = strrchr(dir, '/');
    if (!slash) return CB_OK;
    *slash = '\0';
    return dir[0] ? roster_make_directories(dir, err) : CB_OK;
}

static bool newer_than(const struct stat *a, const struct stat *b)
{
    return a->st_mtim.tv_sec > b->st_mtim.tv_sec ||
           (a->st_mtim.tv_sec == b->st_mtim.tv_sec && a->st_mtim.tv_nsec > b->st_mtim.tv_nsec);
}

/* Make and Ninja decide from modification times, so the manifest's must tell the truth. After
 * a failure it is set to the epoch (as are a failed type's old palettes): older than every
 * input, so the next build runs the bake again, however often it is run, until the inputs are
 * fixed. After a success it is never older than an input, even when its contents did not
 * change (else Make would run the bake on every build). */
void roster_settle_times(const cb_roster *r, const char *tool)
{
    static const struct timespec epoch[2] = {{0, 0}, {0, 0}};
    if (r->failed) {
        utimensat(AT_FDCWD, r->manifest_path, epoch, 0);
        for (uint32_t i = 0; i < r->type_count; ++i)
            if (r->types[i].outcome == CB_TYPE_FAILED && r->types[i].owner == i) {
                struct stat st;
                /* only regular files: a bake refuses to replace anything else, and so does this */
                for (uint32_t k = 0; k < cb_output_format_count(); ++k) {
                    const char *path = r->types[i].paths[k];
                    if (path[0] && stat(path, &st) == 0 && S_ISREG(st.st_mode)) utimensat(AT_FDCWD, path, epoch, 0);
                }
            }
        return;
    }
    struct stat manifest, in;
    if (stat(r->manifest_path, &manifest) != 0) return;
    bool stale = (stat(r->catalog->path, &in) == 0 && newer_than(&in, &manifest)) ||
                 (tool && tool[0] && stat(tool, &in) == 0 && newer_than(&in, &manifest));
    for (uint32_t i = 0; i < r->type_count && !stale; ++i)
        for (uint32_t k = 0; k < r->types[i].input_count && !stale; ++k)
            stale = stat(r->types[i].inputs[k], &in) == 0 && newer_than(&in, &manifest);
    if (stale) utimensat(AT_FDCWD, r->manifest_path, NULL, 0);
}

