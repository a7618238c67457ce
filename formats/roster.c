/* roster.c - see roster.h. Three passes: prepare every type (load, plan clips, match states,
 * measure speeds, check LODs, hash the rig and clips) in parallel; let types with equal hashes
 * share one palette; bake the owners that are out of date in parallel. Then the manifest and
 * the depfile. Nothing that is written depends on the thread count or on timing. */
#define _GNU_SOURCE /* open_memstream, strcasecmp */
#include "roster.h"

#include <errno.h>
#include <fcntl.h> /* AT_FDCWD */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <threads.h>
#include <time.h>

#include "atomic_file.h"
#include "crowdbake_pal.h"
#include "exr_io.h"
#include "gltf_load.h"
#include "json_writer.h"
#include "pal_write.h"
#include "roster_cache.h"
#include "../src/runtime.h"
#include "../src/vat.h"

typedef struct type_work {
    cb_model *model;
    int32_t skin;
    cb_clip_plan *plan;
    cb_model **lod_models;
    unsigned char *record; /* what preparing found, for the type's record (roster_cache.h) */
    size_t record_size;
} type_work;

typedef struct roster_run {
    const cb_catalog *cat;
    const cb_roster_options *opt;
    cb_roster *r;
    type_work *work;
    atomic_uint next;
    mtx_t log_lock;
    double start;
    uint32_t threads_per_bake;
} roster_run;

static double now_seconds(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static const char *at(const cb_catalog *cat, cb_source_pos pos, char *buf, size_t size)
{
    snprintf(buf, size, "%s:%u:%u", cat->path, pos.line, pos.column);
    return buf;
}

/* ---- the content hash: rig, planned clips and settings ---- */

static void hash_str(cbpal_xxh64_state *h, const char *s) { cbpal_xxh64_update(h, s, strlen(s) + 1); }

static uint64_t content_key(const cb_model *m, int32_t skin, const cb_clip_plan *plan, uint32_t n, const cb_bake_settings *b)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    hash_str(&h, "crowdbake " CROWDBAKE_VERSION);
    double settings[8] = {b->fps, b->layout + 10.0 * b->layout_set, b->precision + 10.0 * b->precision_set,
                          b->max_texture_size, b->root_motion, b->formats, b->zstd, b->exr_compression};
    cbpal_xxh64_update(&h, settings, sizeof settings);
    if (b->fit_rows) hash_str(&h, "fit_rows"); /* (only then: other palettes stay up to date) */
    for (uint32_t i = 0; i < m->node_count; ++i) {
        const cb_node *node = &m->nodes[i];
        hash_str(&h, node->name);
        cbpal_xxh64_update(&h, &node->parent, sizeof node->parent);
        cbpal_xxh64_update(&h, node->translation, sizeof node->translation);
        cbpal_xxh64_update(&h, node->rotation, sizeof node->rotation);
        cbpal_xxh64_update(&h, node->scale, sizeof node->scale);
        if (node->has_matrix) cbpal_xxh64_update(&h, node->matrix, sizeof node->matrix);
    }
    const cb_skin *sk = &m->skins[skin];
    cbpal_xxh64_update(&h, sk->joints, sk->joint_count * sizeof(int32_t));
    cbpal_xxh64_update(&h, sk->inverse_bind, sk->joint_count * 16 * sizeof(double));
    for (uint32_t i = 0; i < n; ++i) {
        hash_str(&h, plan[i].name);
        cbpal_xxh64_update(&h, &plan[i].loop, sizeof plan[i].loop);
        cbpal_xxh64_update(&h, &plan[i].fps, sizeof plan[i].fps);
        const cb_animation *a = &m->animations[plan[i].animation];
        for (uint32_t c = 0; c < a->channel_count; ++c) {
            const cb_channel *ch = &a->channels[c];
            int per_key = (ch->path == CB_PATH_ROTATION ? 4 : 3) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
            int32_t head[4] = {ch->node, (int32_t)ch->path, (int32_t)ch->interp, (int32_t)ch->key_count};
            cbpal_xxh64_update(&h, head, sizeof head);
            cbpal_xxh64_update(&h, ch->times, ch->key_count * sizeof(float));
            cbpal_xxh64_update(&h, ch->values, (size_t)ch->key_count * per_key * sizeof(float));
        }
    }
    return cbpal_xxh64_digest(&h);
}

/* Appends a model's files to the type's inputs (for the depfile): its path even when it failed
 * to load (m NULL), so that fixing it makes the build out of date; its external files when it
 * loaded. */
static cb_status add_inputs(cb_roster_type *t, const char *path, const cb_model *m, cb_error *err)
{
    uint32_t externals = m ? m->external_file_count : 0;
    char **grown = realloc(t->inputs, (t->input_count + 1 + externals) * sizeof *grown);
    if (!grown) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    t->inputs = grown;
    for (uint32_t i = 0; i <= externals; ++i) {
        if (!(t->inputs[t->input_count] = strdup(i ? m->external_files[i - 1] : path)))
            return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        ++t->input_count;
    }
    return CB_OK;
}

/* What the files record: everything that produced them, so any change re-bakes. The loader
 * hashed the model and LOD bytes as it read them. */
static uint64_t input_hash(const cb_catalog_animal *an, const type_work *w, uint64_t key)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    cbpal_xxh64_update(&h, &key, sizeof key);
    hash_str(&h, an->canonical);
    cbpal_xxh64_update(&h, &w->model->source_hash, sizeof w->model->source_hash);
    for (uint32_t i = 0; i < an->lod_count; ++i)
        cbpal_xxh64_update(&h, &w->lod_models[i]->source_hash, sizeof w->lod_models[i]->source_hash);
    return cbpal_xxh64_digest(&h);
}

static cb_status write_if_changed(const char *path, const char *data, size_t size, bool *written, cb_error *err);

/* ---- pass 1: prepare a type ---- */

static int pick_skin(const cb_model *m)
{
    for (uint32_t s = 0; s < m->skin_count; ++s)
        if (cb_model_skin_vertex_count(m, (int32_t)s) > 0) return (int)s;
    return m->skin_count ? 0 : -1;
}

static cb_status plan_clips(const cb_catalog *cat, const cb_catalog_animal *an, type_work *w, cb_roster_type *t,
                            cb_error *err)
{
    const cb_model *m = w->model;
    uint32_t n = an->clips ? an->clip_count : m->animation_count;
    w->plan = calloc(n ? n : 1, sizeof *w->plan);
    t->clips = calloc(n ? n : 1, sizeof *t->clips);
    if (!w->plan || !t->clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    char where[1100];
    for (uint32_t i = 0; i < n; ++i) {
        cb_clip_plan *p = &w->plan[i];
        if (!an->clips) {
            *p = (cb_clip_plan){(int32_t)i, m->animations[i].name, -1, 0};
            continue;
        }
        const cb_catalog_clip *c = &an->clips[i];
        int32_t a = cb_model_find_animation(m, c->source);
        const struct cb_skipped_clip *skip = a < 0 ? cb_model_find_skipped_clip(m, c->source) : NULL;
        if (skip) /* asked for by name: an error, not a warning */
            return cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] %s", at(cat, c->pos, where, sizeof where), an->name,
                           skip->reason);
        if (a < 0) {
            char list[512] = "";
            for (uint32_t k = 0; k < m->animation_count; ++k)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", k ? ", " : "", m->animations[k].name);
            return cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] %s has no clip '%s'; its clips are: %s",
                           at(cat, c->pos, where, sizeof where), an->name, m->source, c->source, list);
        }
        *p = (cb_clip_plan){a, c->name, c->loop, c->fps};
    }
    t->clip_count = n;
    return CB_OK;
}

static cb_status analyze_clips(const cb_catalog_animal *an, const cb_limits *limits, type_work *w, cb_roster_type *t,
                               cb_error *err)
{
    cb_sampler *s = cb_sampler_create(w->model, w->skin, err);
    if (!s) return err->status;
    uint32_t row = 0;
    for (uint32_t i = 0; i < t->clip_count && !err->status; ++i) {
        cb_clip_info info;
        double fps = w->plan[i].fps > 0 ? w->plan[i].fps : an->bake.fps;
        if (cb_clip_analyze(s, w->plan[i].animation, fps, w->plan[i].loop, limits, &info, err)) break;
        cb_roster_clip *c = &t->clips[i];
        snprintf(c->name, sizeof c->name, "%s", w->plan[i].name);
        c->first_row = row;
        c->frames = info.frames;
        c->fps = info.effective_fps;
        c->duration = info.duration;
        c->loops = info.loops;
        cb_measure_ground_speed(s, &info, &c->speed);
        row += info.frames;
    }
    t->rows = row;
    double lo[3], hi[3];
    if (!err->status) t->model_height = cb_skin_rest_bounds(s, lo, hi);
    cb_sampler_free(s);
    return err->status;
}

static cb_status match_states(const cb_catalog *cat, const cb_catalog_animal *an, cb_roster_type *t, cb_error *err)
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
        if (t->state_clip[s] >= 0) continue;
        char list[512] = "", words[256] = "", where[1100];
        for (uint32_t i = 0; i < t->clip_count; ++i)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", names[i]);
        for (uint32_t k = 0; k < st->keyword_count; ++k)
            snprintf(words + strlen(words), sizeof words - strlen(words), "%s\"%s\"", k ? ", " : "", st->keywords[k]);
        cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] state '%s' matches no clip (keywords %s); the clips are: %s",
                at(cat, st->pos, where, sizeof where), an->name, st->name, words, list);
    }
    free(names);
    return err->status;
}

/* Locomotion: a looping clip that moves. Only these are synced to the animal's speed. */
static bool is_locomotion(const cb_roster_clip *c) { return c->loops && c->speed.speed > 0; }

/* The speed at which locomotion plays at rate 1: given, or measured on a locomotion loop: the
 * default state's clip if it is one, else the state the catalog names, else the slowest
 * locomotion state. t->speed_reference_from says which. */
static void speed_reference(const cb_catalog_animal *an, cb_roster_type *t)
{
    t->speed_reference = an->speed_reference;
    snprintf(t->speed_reference_from, sizeof t->speed_reference_from, "the catalog");
    if (!an->speed_auto) return;
    t->speed_reference = 0;
    snprintf(t->speed_reference_from, sizeof t->speed_reference_from, "none: no state plays a looping clip that moves");
    int pick = -1;
    const char *rule = "";
    for (uint32_t s = 0; s < an->state_count && pick < 0; ++s)
        if (strcmp(an->states[s].name, an->default_state) == 0 && is_locomotion(&t->clips[t->state_clip[s]]))
            pick = (int)s, rule = "the default state";
    for (uint32_t s = 0; s < an->state_count && pick < 0 && an->speed_state; ++s)
        if (strcmp(an->states[s].name, an->speed_state) == 0 && is_locomotion(&t->clips[t->state_clip[s]]))
            pick = (int)s, rule = "the catalog's speed_reference state";
    for (uint32_t s = 0; s < an->state_count && !(pick >= 0 && *rule); ++s) {
        const cb_roster_clip *c = &t->clips[t->state_clip[s]];
        if (is_locomotion(c) && (pick < 0 || c->speed.speed < t->clips[t->state_clip[pick]].speed.speed)) pick = (int)s;
    }
    if (pick < 0) return;
    const cb_roster_clip *c = &t->clips[t->state_clip[pick]];
    t->speed_reference = c->speed.speed;
    snprintf(t->speed_reference_from, sizeof t->speed_reference_from, "%s '%s' (clip '%s', %s)",
             *rule ? rule : "the slowest locomotion state", an->states[pick].name, c->name, c->speed.method);
}

static cb_status check_lods(const roster_run *run, const cb_catalog_animal *an, type_work *w, cb_roster_type *t,
                            cb_error *err)
{
    t->lod_count = an->lod_count;
    t->lods = calloc(an->lod_count ? an->lod_count : 1, sizeof *t->lods);
    w->lod_models = calloc(an->lod_count ? an->lod_count : 1, sizeof *w->lod_models);
    if (!t->lods || !w->lod_models) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    char where[1100];
    for (uint32_t i = 0; i < an->lod_count; ++i) {
        cb_error inner = {0};
        cb_model *lod = w->lod_models[i] = cb_gltf_load(an->lods[i], run->opt->limits, &inner);
        if (add_inputs(t, an->lods[i], lod, err)) return err->status;
        int skin = lod ? pick_skin(lod) : -1;
        if (lod && skin < 0) cb_fail(&inner, CB_ERR_INPUT, "%s: has no skin", an->lods[i]);
        cb_roster_lod *l = &t->lods[i];
        if (!inner.status) {
            l->path = an->lods[i];
            l->joint_count = lod->skins[skin].joint_count;
            l->remap = calloc(l->joint_count, sizeof *l->remap);
            l->vertices = cb_model_skin_vertex_count(lod, skin);
            for (uint32_t p = 0; p < lod->primitive_count; ++p) l->indices += lod->primitives[p].index_count;
            if (!l->remap) cb_fail(&inner, CB_ERR_INTERNAL, "out of memory");
            else cb_lod_remap(w->model, w->skin, lod, skin, l->remap, &inner);
        }
        if (inner.status)
            return cb_fail(err, inner.status, "%s: [animal.%s] LOD %u: %s", at(run->cat, an->lod_pos[i], where, sizeof where),
                           an->name, i, inner.message);
    }
    return CB_OK;
}

/* The bake options a type's settings give. */
static cb_bake_options bake_options(const cb_catalog_animal *an, const cb_limits *limits)
{
    cb_bake_options o = cb_default_bake_options();
    if (limits) o.limits = *limits;
    o.fps = an->bake.fps;
    o.layout = an->bake.layout;
    o.precision = an->bake.precision;
    if (!an->bake.precision_set && (an->bake.formats & CB_FORMAT_EXR)) o.precision = CB_PRECISION_FLOAT;
    o.max_texture_size = an->bake.max_texture_size;
    o.root_motion = an->bake.root_motion;
    o.affine_fallback = !an->bake.layout_set;
    o.fit = an->bake.fit_rows;
    return o;
}

/* fps = "auto" (the animal's or a clip's): each such clip's rate, chosen by its visible error. */
static cb_status choose_rates(const cb_catalog_animal *an, const cb_limits *limits, uint32_t threads, type_work *w,
                              uint32_t n, cb_error *err)
{
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    if (!goals) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    bool any = false;
    for (uint32_t i = 0; i < n; ++i) {
        const cb_catalog_clip *c = an->clips ? &an->clips[i] : NULL;
        if (!(c && c->fps_auto >= 0 ? c->fps_auto == 1 : an->bake.fps_auto)) continue;
        goals[i] = (cb_rate_goal){c && c->max_error_mm > 0 ? c->max_error_mm : an->bake.max_error_mm, an->bake.max_fps};
        any = true;
    }
    cb_sampler *s = any ? cb_sampler_create(w->model, w->skin, err) : NULL;
    cb_bake_options o = bake_options(an, limits);
    o.threads = threads; /* clips searched at once */
    if (s) cb_choose_rates(s, &o, w->plan, n, goals, NULL, err);
    cb_sampler_free(s);
    free(goals);
    return err->status;
}

/* The error a VAT of the same frames would have: half-float positions against exact skinning. */
static void measure_vat(const cb_catalog_animal *an, const cb_limits *limits, type_work *w, cb_roster_type *t)
{
    cb_bake_options o = bake_options(an, limits);
    o.max_texture_size = 1u << 30; /* only measured: no texture is made */
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(w->model, w->skin, &err);
    cb_vat vat = {0};
    if (s && !cb_vat_bake(s, &o, w->plan, t->clip_count, false, &vat, &err)) t->vat_error = vat.max_error;
    cb_vat_free(&vat);
    cb_sampler_free(s);
}

static void output_paths(const cb_catalog_animal *an, cb_roster_type *t)
{
    snprintf(t->pal_path, sizeof t->pal_path, "%s/%s.pal", an->bake.out_dir, an->name);
    snprintf(t->exr_path, sizeof t->exr_path, "%s/%s.exr", an->bake.out_dir, an->name);
}

/* A type that failed before its LODs were loaded still lists them: they are its inputs. */
static void list_unloaded_lods(const cb_catalog_animal *an, const type_work *w, cb_roster_type *t)
{
    for (uint32_t l = 0; !w->lod_models && l < an->lod_count; ++l)
        if (add_inputs(t, an->lods[l], NULL, &t->error)) break;
}

/* Preparing from the model: load, plan, sample what the manifest states, hash. */
static void prepare_from_model(roster_run *run, uint32_t i)
{
    const cb_catalog_animal *an = &run->cat->animals[i];
    cb_roster_type *t = &run->r->types[i];
    type_work *w = &run->work[i];
    cb_error *err = &t->error;
    char where[1100];
    cb_error inner = {0};
    w->model = cb_gltf_load(an->model, run->opt->limits, &inner);
    if (add_inputs(t, an->model, w->model, err)) return;
    if (!w->model) {
        cb_fail(err, inner.status, "%s: [animal.%s] %s", at(run->cat, an->model_pos, where, sizeof where), an->name,
                inner.message);
        list_unloaded_lods(an, w, t);
        return;
    }
    w->skin = pick_skin(w->model);
    if (w->skin < 0) {
        cb_fail(err, CB_ERR_INPUT, "%s: [animal.%s] %s has no skin to bake", at(run->cat, an->model_pos, where, sizeof where),
                an->name, an->model);
        list_unloaded_lods(an, w, t);
        return;
    }
    cb_model_warnings(w->model, !an->clips, &t->warnings);
    t->bones = w->model->skins[w->skin].joint_count;
    t->vertices = cb_model_skin_vertex_count(w->model, w->skin);
    t->mesh_bytes = cb_model_skin_mesh_bytes(w->model, w->skin);
    for (uint32_t p = 0; p < w->model->primitive_count; ++p)
        if (w->model->primitives[p].skin == w->skin) t->indices += w->model->primitives[p].index_count;
    if (plan_clips(run->cat, an, w, t, err) || choose_rates(an, run->opt->limits, run->threads_per_bake, w, t->clip_count, err) ||
        analyze_clips(an, run->opt->limits, w, t, err) || match_states(run->cat, an, t, err) ||
        check_lods(run, an, w, t, err)) {
        list_unloaded_lods(an, w, t);
        return;
    }
    speed_reference(an, t);
    t->key = content_key(w->model, w->skin, w->plan, t->clip_count, &an->bake);
    t->input_hash = input_hash(an, w, t->key);
    if (run->opt->measure_vat) measure_vat(an, run->opt->limits, w, t);
    uint64_t key;
    if (cb_prep_key(an, run->opt->limits, t->inputs, t->input_count, &key))
        cb_prep_record_encode(t, key, &w->record, &w->record_size);
}

/* A type's record, when it matches its files, stands in for loading and sampling: an
 * up-to-date type then costs the hashing of its files and the check of its palette. */
static void prepare_type(roster_run *run, uint32_t i)
{
    const cb_catalog_animal *an = &run->cat->animals[i];
    cb_roster_type *t = &run->r->types[i];
    t->animal = an;
    t->owner = i;
    output_paths(an, t);
    char path[4096];
    if (!run->opt->force && !run->opt->measure_vat && cb_prep_record_path(an, path, sizeof path) &&
        cb_prep_record_load(path, an, run->opt->limits, t))
        t->prepared_from_record = true;
    else
        prepare_from_model(run, i);
}

/* ---- pass 3: bake an owner ---- */

static uint64_t file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
}

/* True when every output exists and records this key; fills the geometry from the .pal. */
static bool up_to_date(cb_roster_type *t, unsigned formats)
{
    char msg[256];
    if (formats & CB_FORMAT_PAL) {
        cbpal_file f;
        /* Verified (memory speed): a file torn by a power loss is baked again, not trusted. */
        if (cbpal_open(t->pal_path, CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg) != 0) return false;
        bool same = f.header.input_hash == t->input_hash && f.header.rows == t->rows;
        if (same) {
            t->width = f.header.width, t->height = f.header.height, t->blocks = f.header.blocks;
            t->layout = (cb_layout)f.header.layout, t->precision = (cb_precision)f.header.precision;
            t->max_error = f.header.max_error;
            t->visible_error = f.header.visible_error;
            t->palette_bytes = f.header.payload_raw_size;
        }
        cbpal_close(&f);
        if (!same) return false;
    }
    if (formats & CB_FORMAT_EXR) {
        cb_exr_image img;
        cb_error e = {0};
        if (cb_exr_read(t->exr_path, &img, &e)) return false;
        bool same = img.input_hash == t->input_hash && (uint32_t)img.rows == t->rows;
        if (same && !(formats & CB_FORMAT_PAL)) {
            t->width = img.width, t->height = img.height, t->blocks = (uint32_t)img.blocks;
            cb_layout_parse(img.layout, &t->layout);
            t->precision = img.precision;
            t->palette_bytes = img.texel_bytes;
            t->max_error = img.max_error, t->visible_error = img.visible_error;
        }
        cb_exr_image_free(&img);
        if (!same) return false;
    }
    return true;
}

/* mkdir -p: the output directory and any missing parents. */
static cb_status make_directories(const char *dir, cb_error *err)
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

static cb_status bake_files(roster_run *run, const cb_catalog_animal *an, type_work *w, cb_roster_type *t, cb_error *err)
{
    cb_bake_options o = bake_options(an, run->opt->limits);
    o.threads = run->threads_per_bake;
    cb_sampler *s = cb_sampler_create(w->model, w->skin, err);
    if (!s) return err->status;
    cb_palette p;
    cb_status rc = cb_palette_bake(s, &o, w->plan, t->clip_count, &p, err);
    cb_sampler_free(s);
    if (rc) return rc;
    make_directories(an->bake.out_dir, err);
    if (!err->status && (an->bake.formats & CB_FORMAT_PAL)) {
        cb_pal_write_options po = {an->bake.zstd, 0, t->input_hash, (float)t->speed_reference, o.root_motion == CB_ROOT_MOTION_IN_PLACE};
        cb_pal_write(t->pal_path, &p, w->model, w->skin, &po, err);
    }
    if (!err->status && (an->bake.formats & CB_FORMAT_EXR))
        cb_exr_write(t->exr_path, &p, w->model, w->skin, an->bake.exr_compression, t->input_hash, (float)t->speed_reference, err);
    t->width = p.width, t->height = p.height, t->blocks = p.blocks;
    t->layout = p.layout, t->precision = p.precision;
    t->max_error = (float)p.max_error;
    t->visible_error = (float)p.visible_error;
    t->palette_bytes = p.texel_bytes;
    if (p.fallback_note[0]) cb_warn(&t->warnings, "note", "%s", p.fallback_note);
    cb_palette_free(&p);
    return err->status;
}

static void log_type(roster_run *run, const cb_roster_type *t)
{
    if (!run->opt->log) return;
    mtx_lock(&run->log_lock);
    FILE *f = run->opt->log;
    const char *clear = run->opt->tty ? "\r\033[K" : "";
    const cb_roster_type *owner = &run->r->types[t->owner];
    switch (t->outcome) {
    case CB_TYPE_BAKED:
        fprintf(f, "%s  %-16s baked    %s (%.1f KiB, %ux%u, %s/%s, encoding error %.3g mm/m, visible %.3g mm/m) in %.0f ms\n",
                clear, t->animal->name, (t->animal->bake.formats & CB_FORMAT_PAL) ? t->pal_path : t->exr_path,
                t->palette_bytes / 1024.0, t->width, t->height, cb_layout_name(t->layout), cb_precision_name(t->precision),
                cb_mm_per_m(t->max_error, t->model_height),
                cb_mm_per_m(t->visible_error, t->model_height), t->seconds * 1000);
        break;
    case CB_TYPE_UP_TO_DATE: fprintf(f, "%s  %-16s up to date\n", clear, t->animal->name); break;
    case CB_TYPE_SHARED:
        fprintf(f, "%s  %-16s shares %s's palette (same rig, bind pose and clips)\n", clear, t->animal->name,
                owner->animal->name);
        break;
    case CB_TYPE_FAILED: fprintf(f, "%s  %-16s FAILED: %s\n", clear, t->animal->name, t->error.message); break;
    }
    for (uint32_t i = 0; i < t->warnings.count; ++i)
        fprintf(f, "  %-16s %s: %s\n", "", t->warnings.items[i].kind, t->warnings.items[i].message);
    if (run->opt->tty)
        fprintf(f, "  [%u/%u done, %.1f s]", run->r->baked + run->r->up_to_date + run->r->shared + run->r->failed,
                run->r->type_count, now_seconds() - run->start);
    fflush(f);
    mtx_unlock(&run->log_lock);
}

/* Saves the record of a type prepared from its model (unless the file holds it already); a
 * record that cannot be written only costs the next run the preparation. */
static void write_record(roster_run *run, uint32_t i)
{
    type_work *w = &run->work[i];
    if (!w->record) return;
    char path[4096];
    cb_error ignored = {0};
    bool written;
    if (cb_prep_record_path(run->r->types[i].animal, path, sizeof path))
        write_if_changed(path, (const char *)w->record, w->record_size, &written, &ignored);
}

static void bake_type(roster_run *run, uint32_t i)
{
    cb_roster_type *t = &run->r->types[i];
    const cb_catalog_animal *an = t->animal;
    double t0 = now_seconds();
    if (t->error.status) {
        t->outcome = CB_TYPE_FAILED;
    } else if (t->owner != i) {
        return; /* shared types are settled once their owner is */
    } else {
        if (!run->opt->force && up_to_date(t, an->bake.formats)) {
            t->outcome = CB_TYPE_UP_TO_DATE;
        } else {
            if (t->prepared_from_record) { /* the palette is not: bake it from the model */
                cb_prep_clear(t);
                t->prepared_from_record = false;
                prepare_from_model(run, i);
            }
            t->outcome = t->error.status || bake_files(run, an, &run->work[i], t, &t->error) ? CB_TYPE_FAILED : CB_TYPE_BAKED;
        }
        if (t->outcome != CB_TYPE_FAILED) write_record(run, i);
        t->pal_file_bytes = file_size(t->pal_path);
        t->exr_file_bytes = file_size(t->exr_path);
    }
    t->seconds = now_seconds() - t0;
    mtx_lock(&run->log_lock);
    if (t->outcome == CB_TYPE_BAKED) run->r->baked++;
    else if (t->outcome == CB_TYPE_UP_TO_DATE) run->r->up_to_date++;
    else run->r->failed++;
    mtx_unlock(&run->log_lock);
    log_type(run, t);
}

/* ---- parallel passes ---- */

typedef struct pass {
    roster_run *run;
    void (*fn)(roster_run *, uint32_t);
} pass;

static int pass_main(void *arg)
{
    pass *p = arg;
    for (;;) {
        uint32_t i = atomic_fetch_add(&p->run->next, 1);
        if (i >= p->run->r->type_count) return 0;
        p->fn(p->run, i);
    }
}

static void run_pass(roster_run *run, void (*fn)(roster_run *, uint32_t))
{
    atomic_store(&run->next, 0);
    pass p = {run, fn};
    uint32_t threads = run->opt->jobs ? run->opt->jobs : 1;
    if (threads > run->r->type_count) threads = run->r->type_count ? run->r->type_count : 1;
    if (threads > 64) threads = 64;
    thrd_t ids[64];
    uint32_t started = 0;
    for (uint32_t t = 1; t < threads; ++t)
        if (thrd_create(&ids[started], pass_main, &p) == thrd_success) ++started;
    pass_main(&p);
    for (uint32_t t = 0; t < started; ++t) thrd_join(ids[t], NULL);
}

/* ---- the manifest and the depfile ---- */

static void write_state(cb_json *j, const cb_roster_type *t, const cb_catalog_state *st, int clip)
{
    const cb_roster_clip *c = &t->clips[clip];
    /* Only locomotion loops are synced to speed; one-shots and clips that stand still play at
     * their own rate (a dying animal at speed 0 still dies). */
    bool synced = is_locomotion(c);
    double speed = t->animal->speed_auto ? c->speed.speed : t->speed_reference;
    cb_json_object(j, st->name);
    cb_json_string(j, "clip", c->name);
    cb_json_inline_array(j, "keywords");
    for (uint32_t k = 0; k < st->keyword_count; ++k) cb_json_string(j, NULL, st->keywords[k]);
    cb_json_end(j);
    /* The four numbers of the per-instance data, exactly as the shader wants them. */
    cb_json_object(j, "instance");
    cb_json_int(j, "first_row", c->first_row);
    cb_json_int(j, "frame_count", c->loops ? (long long)c->frames : -(long long)c->frames); /* < 0: one-shot, clamps */
    cb_json_number(j, "rate", c->fps);
    cb_json_number(j, "rate_per_speed", synced && speed > 0 ? c->fps / speed : 0);
    cb_json_string(j, "phase", c->loops ? "golden_ratio" : "zero");
    cb_json_end(j);
    cb_json_end(j);
}

/* `path` relative to directory `dir` (both as the catalog resolved them, or absolute), so a
 * game resolves palette paths against the manifest's own directory. */
static void relative_path(const char *dir, const char *path, char *out, size_t size)
{
    char a[4096], b[4096];
    if (!realpath(dir, a) || !realpath(path, b)) {
        snprintf(out, size, "%s", path);
        return;
    }
    size_t common = 0, i = 0;
    for (; a[i] && a[i] == b[i]; ++i)
        if (a[i] == '/') common = i;
    if (!a[i] && b[i] == '/') common = i; /* dir is a prefix of path */
    out[0] = '\0';
    for (const char *p = a + common; *p; ++p)
        if (*p == '/') strncat(out, "../", size - strlen(out) - 1);
    strncat(out, b + common + 1, size - strlen(out) - 1);
}

static void write_type(cb_json *j, const cb_roster *r, const cb_roster_type *t, const char *manifest_dir)
{
    const cb_roster_type *owner = &r->types[t->owner];
    const cb_catalog_animal *an = t->animal;
    char rel[4096];
    cb_json_object(j, an->name);
    relative_path(manifest_dir, an->model, rel, sizeof rel);
    cb_json_string(j, "model", rel);
    if (owner->animal->bake.formats & CB_FORMAT_PAL) {
        relative_path(manifest_dir, owner->pal_path, rel, sizeof rel);
        cb_json_string(j, "palette", rel);
    }
    if (owner->animal->bake.formats & CB_FORMAT_EXR) {
        relative_path(manifest_dir, owner->exr_path, rel, sizeof rel);
        cb_json_string(j, "palette_exr", rel);
    }
    if (t->owner != (uint32_t)(t - r->types)) cb_json_string(j, "shares_palette_of", owner->animal->name);
    cb_json_string(j, "layout", cb_layout_name(owner->layout));
    cb_json_string(j, "precision", cb_precision_name(owner->precision));
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
    cb_json_array(j, "clips");
    for (uint32_t c = 0; c < t->clip_count; ++c) {
        const cb_roster_clip *cl = &t->clips[c];
        cb_json_object(j, NULL);
        cb_json_string(j, "name", cl->name);
        cb_json_int(j, "first_row", cl->first_row);
        cb_json_int(j, "frame_count", cl->frames);
        cb_json_number(j, "fps", cl->fps);
        cb_json_number(j, "duration", cl->duration);
        cb_json_bool(j, "loops", cl->loops);
        cb_json_number(j, "ground_speed", cl->speed.speed);
        cb_json_number(j, "root_speed", cl->speed.root);
        cb_json_number(j, "feet_speed", cl->speed.feet);
        cb_json_string(j, "speed_method", cl->speed.method);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_json_object(j, "states");
    for (uint32_t s = 0; s < an->state_count; ++s) write_state(j, t, &an->states[s], t->state_clip[s]);
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
    cb_json_end(j);
}

/* Writes `data` to path unless the file already holds exactly it (mtimes stay put). */
static cb_status write_if_changed(const char *path, const char *data, size_t size, bool *written, cb_error *err)
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

static cb_status write_manifest(const cb_catalog *cat, cb_roster *r, const char *path, cb_error *err)
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
    cb_status rc = write_if_changed(path, buf, size, &r->manifest_written, err);
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

static void depfile_inputs(FILE *f, const cb_roster_type *t)
{
    for (uint32_t i = 0; i < t->input_count; ++i) fputs(" \\\n  ", f), depfile_path(f, t->inputs[i]);
}

/* Whether input k of type i was already listed by an earlier input or type. */
static bool listed_before(const cb_roster *r, uint32_t i, uint32_t k)
{
    for (uint32_t a = 0; a <= i; ++a)
        for (uint32_t b = 0; b < (a == i ? k : r->types[a].input_count); ++b)
            if (strcmp(r->types[a].inputs[b], r->types[i].inputs[k]) == 0) return true;
    return false;
}

/* One rule per output: Make and Ninja both read it. */
static cb_status write_depfile(const cb_catalog *cat, const cb_roster *r, const char *path, cb_error *err)
{
    char *buf = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&buf, &size);
    if (!f) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_roster_type *t = &r->types[i];
        if (t->owner != i) continue; /* failed types too: their inputs keep the build out of date */
        for (int fmt = 0; fmt < 2; ++fmt) {
            if (!(t->animal->bake.formats & (fmt ? CB_FORMAT_EXR : CB_FORMAT_PAL))) continue;
            depfile_path(f, fmt ? t->exr_path : t->pal_path);
            fputs(":", f);
            fputc(' ', f), depfile_path(f, cat->path);
            for (uint32_t k = 0; k < r->type_count; ++k) /* every type sharing this palette */
                if (r->types[k].owner == i) depfile_inputs(f, &r->types[k]);
            fputc('\n', f);
        }
    }
    depfile_path(f, r->manifest_path);
    fputs(":", f);
    fputc(' ', f), depfile_path(f, cat->path);
    for (uint32_t i = 0; i < r->type_count; ++i) depfile_inputs(f, &r->types[i]);
    fputc('\n', f);
    /* An empty rule per input (as gcc -MP writes): a deleted or renamed model makes Make run the
     * bake, which names the problem, instead of stopping at "no rule to make target". */
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].input_count; ++k)
            if (!listed_before(r, i, k)) fputc('\n', f), depfile_path(f, r->types[i].inputs[k]), fputs(":\n", f);
    fclose(f);
    bool written;
    cb_status rc = write_if_changed(path, buf, size, &written, err);
    free(buf);
    return rc;
}

static cb_status make_parent_directories(const char *file, cb_error *err)
{
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", file);
    char *slash = strrchr(dir, '/');
    if (!slash) return CB_OK;
    *slash = '\0';
    return dir[0] ? make_directories(dir, err) : CB_OK;
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
static void settle_times(const cb_roster *r)
{
    static const struct timespec epoch[2] = {{0, 0}, {0, 0}};
    if (r->failed) {
        utimensat(AT_FDCWD, r->manifest_path, epoch, 0);
        for (uint32_t i = 0; i < r->type_count; ++i)
            if (r->types[i].outcome == CB_TYPE_FAILED && r->types[i].owner == i) {
                struct stat st;
                /* only regular files: a bake refuses to replace anything else, and so does this */
                if (stat(r->types[i].pal_path, &st) == 0 && S_ISREG(st.st_mode)) utimensat(AT_FDCWD, r->types[i].pal_path, epoch, 0);
                if (stat(r->types[i].exr_path, &st) == 0 && S_ISREG(st.st_mode)) utimensat(AT_FDCWD, r->types[i].exr_path, epoch, 0);
            }
        return;
    }
    struct stat manifest, in;
    if (stat(r->manifest_path, &manifest) != 0) return;
    bool stale = stat(r->catalog->path, &in) == 0 && newer_than(&in, &manifest);
    for (uint32_t i = 0; i < r->type_count && !stale; ++i)
        for (uint32_t k = 0; k < r->types[i].input_count && !stale; ++k)
            stale = stat(r->types[i].inputs[k], &in) == 0 && newer_than(&in, &manifest);
    if (stale) utimensat(AT_FDCWD, r->manifest_path, NULL, 0);
}

/* ---- the whole bake ---- */

cb_status cb_roster_bake(const cb_catalog *cat, const cb_roster_options *opt, cb_roster *r, cb_error *err)
{
    memset(r, 0, sizeof *r);
    r->catalog = cat;
    r->type_count = cat->animal_count;
    r->types = calloc(cat->animal_count ? cat->animal_count : 1, sizeof *r->types);
    roster_run run;
    memset(&run, 0, sizeof run);
    run.cat = cat, run.opt = opt, run.r = r, run.start = now_seconds();
    run.work = calloc(cat->animal_count ? cat->animal_count : 1, sizeof(type_work));
    if (!r->types || !run.work || mtx_init(&run.log_lock, mtx_plain) != thrd_success) {
        free(run.work);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    /* Types are the unit of parallel work; a lone type spreads its clips instead. */
    run.threads_per_bake = cat->animal_count == 1 && opt->jobs ? opt->jobs : 1;
    run_pass(&run, prepare_type);
    /* Equal keys share: the first type (by name) owns the palette. */
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
    run_pass(&run, bake_type);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        cb_roster_type *t = &r->types[i];
        if (t->owner == i || t->error.status) continue;
        const cb_roster_type *o = &r->types[t->owner];
        if (o->outcome == CB_TYPE_FAILED) {
            t->outcome = CB_TYPE_FAILED;
            cb_fail(&t->error, o->error.status, "its palette is %s's, which failed", o->animal->name);
            r->failed++;
        } else {
            memcpy(t->pal_path, o->pal_path, sizeof t->pal_path);
            memcpy(t->exr_path, o->exr_path, sizeof t->exr_path);
            t->layout = o->layout, t->precision = o->precision, t->palette_bytes = o->palette_bytes;
            t->width = o->width, t->height = o->height, t->blocks = o->blocks, t->max_error = o->max_error;
            t->visible_error = o->visible_error;
            write_record(&run, i);
            r->shared++;
        }
        log_type(&run, t);
    }
    if (opt->log && opt->tty) fputs("\r\033[K", opt->log);
    if (opt->manifest) snprintf(r->manifest_path, sizeof r->manifest_path, "%s", opt->manifest);
    else snprintf(r->manifest_path, sizeof r->manifest_path, "%s/roster.json", cat->defaults.out_dir);
    cb_status rc = make_parent_directories(r->manifest_path, err);
    if (!rc) rc = write_manifest(cat, r, r->manifest_path, err);
    if (!rc && opt->depfile && !(rc = make_parent_directories(opt->depfile, err))) rc = write_depfile(cat, r, opt->depfile, err);
    if (!rc) settle_times(r);
    for (uint32_t i = 0; i < r->type_count && !rc; ++i)
        if (r->types[i].outcome == CB_TYPE_FAILED) rc = cb_fail(err, r->types[i].error.status, "%s", r->types[i].error.message);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        free(run.work[i].plan);
        cb_model_free(run.work[i].model);
        for (uint32_t l = 0; l < cat->animals[i].lod_count && run.work[i].lod_models; ++l) cb_model_free(run.work[i].lod_models[l]);
        free(run.work[i].lod_models);
        free(run.work[i].record);
    }
    free(run.work);
    mtx_destroy(&run.log_lock);
    return rc;
}

void cb_roster_free(cb_roster *r)
{
    for (uint32_t i = 0; i < r->type_count; ++i) {
        free(r->types[i].clips);
        free(r->types[i].state_clip);
        for (uint32_t l = 0; l < r->types[i].lod_count; ++l) free(r->types[i].lods[l].remap);
        free(r->types[i].lods);
        for (uint32_t k = 0; k < r->types[i].input_count; ++k) free(r->types[i].inputs[k]);
        free(r->types[i].inputs);
        cb_warnings_free(&r->types[i].warnings);
    }
    free(r->types);
    memset(r, 0, sizeof *r);
}
