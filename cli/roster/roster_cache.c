/* roster_cache.c - see roster_cache.h. A record is "CBPREP1" and a NUL, the key, the length
 * and xxh64 of the body, then the body: fixed-size numbers in this machine's byte order and
 * strings as a u32 length and their bytes. Doubles are stored bit for bit, so a manifest
 * written from a record is byte-identical to one written after loading the model. */
#include "roster_cache.h"
#include "record_io.h"

#include <stdlib.h>
#include <string.h>

#include "crowdbake_pal.h"

static const char magic[8] = "CBPREP9"; /* 2: each clip's stride; 3: its feet's stances, the sockets; 4: feet tracked by
                                        * their soles; 5: the VAT error; 6: each clip's root motion (flag bit 2), loop reason and error;
                                        * 7: each clip's row travel; 8: the LOD's error; 9: each clip's rate reason */

bool cb_prep_record_path(const cb_catalog_animal *an, char *out, size_t size)
{
    int n = snprintf(out, size, "%s/.%s.prep", an->bake.out_dir, an->name);
    return n > 0 && (size_t)n < size;
}

/* ---- the key ---- */

static void hash_str(cbpal_xxh64_state *h, const char *s) { cbpal_xxh64_update(h, s ? s : "", (s ? strlen(s) : 0) + 1); }

static bool hash_file(cbpal_xxh64_state *h, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    unsigned char buf[1 << 16];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) cbpal_xxh64_update(h, buf, n);
    bool ok = !ferror(f);
    fclose(f);
    return ok;
}

bool cb_prep_key(const cb_catalog_animal *an, const cb_limits *limits, char *const *inputs, uint32_t input_count,
                 uint64_t *key)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    hash_str(&h, "crowdbake prepare " CROWDBAKE_VERSION);
    hash_str(&h, an->name);
    hash_str(&h, an->canonical);
    /* The settings a run's options may override (the canonical entry is the catalog's text). */
    const cb_bake_settings *b = &an->bake;
    double settings[15] = {b->fps, b->fps_auto, b->max_error_mm, b->max_fps, b->layout, b->layout_set, b->precision,
                           b->precision_set, b->formats, b->max_texture_size, b->root_motion, b->zstd,
                           b->exr_compression, an->speed_reference, b->fit_rows};
    cbpal_xxh64_update(&h, settings, sizeof settings);
    if (b->measure_all) hash_str(&h, "measure_all"); /* only then: records made before it stay valid */
    if (b->plant_feet) hash_str(&h, "plant_feet");   /* (likewise) */
    if (b->row_travel_off) hash_str(&h, "row_travel_off"); /* likewise */
    if (b->timed_rows != CB_TIMED_ROWS_AUTO) hash_str(&h, cb_timed_rows_name(b->timed_rows)); /* likewise */
    if (b->max_error_given && b->from.max_error == CB_FROM_COMMAND_LINE) hash_str(&h, "max_error from the command line");
    hash_str(&h, b->out_dir);
    cb_limits l = limits ? *limits : cb_default_limits();
    uint64_t lim[5] = {l.max_joints, l.max_frames, l.max_accessor_count, l.max_file_bytes, l.max_palette_bytes};
    cbpal_xxh64_update(&h, lim, sizeof lim);
    for (uint32_t i = 0; i < input_count; ++i) {
        hash_str(&h, inputs[i]);
        if (!hash_file(&h, inputs[i])) return false;
    }
    *key = cbpal_xxh64_digest(&h);
    return true;
}

/* ---- writing ---- */

bool cb_prep_record_encode(const cb_roster_type *t, uint64_t key, unsigned char **data, size_t *size)
{
    record_writer w = {0};
    rec_put(&w, magic, sizeof magic);
    rec_put_u64(&w, key);
    rec_put_u64(&w, 0), rec_put_u64(&w, 0); /* body length and hash, filled in below */
    size_t body = w.size;
    rec_put_u64(&w, t->key), rec_put_u64(&w, t->input_hash);
    rec_put_u32(&w, t->bones), rec_put_u32(&w, t->rows);
    rec_put_u64(&w, t->vertices), rec_put_u64(&w, t->indices), rec_put_u64(&w, t->mesh_bytes);
    rec_put_f64(&w, t->model_height), rec_put_f64(&w, t->speed_reference);
    rec_put_str(&w, t->speed_reference_from);
    rec_put_u32(&w, t->vat_measured), rec_put_f64(&w, t->vat_error);
    rec_put_u32(&w, t->clip_count);
    for (uint32_t i = 0; i < t->clip_count; ++i) {
        const cb_roster_clip *c = &t->clips[i];
        rec_put_str(&w, c->name);
        rec_put_u32(&w, c->first_row), rec_put_u32(&w, c->frames);
        rec_put_u32(&w, (c->loops ? 1u : 0u) | (c->step ? 2u : 0u) | (c->in_place ? 4u : 0u) | (c->plant.planted ? 8u : 0u) |
                            (c->cells ? 16u : 0u));
        rec_put_f64(&w, c->fps), rec_put_f64(&w, c->duration);
        rec_put_str(&w, c->loop_reason);
        rec_put_f64(&w, c->visible_error_mm);
        rec_put_str(&w, c->rate_reason);
        rec_put_f64(&w, c->speed.speed), rec_put_f64(&w, c->speed.root), rec_put_f64(&w, c->speed.feet);
        rec_put_str(&w, c->speed.method);
        rec_put(&w, &c->speed.stride, sizeof c->speed.stride); /* plain numbers and zero-filled strings */
        if (c->plant.planted) rec_put(&w, &c->plant, sizeof c->plant); /* (likewise; only then: older records read) */
        rec_put(&w, &c->travel, sizeof c->travel);             /* likewise */
        if (c->cells) rec_put_u32(&w, c->cells), rec_put_u32(&w, c->map_rows), rec_put_f64(&w, c->cell_rate); /* timed */
    }
    rec_put_u32(&w, t->animal->state_count);
    for (uint32_t s = 0; s < t->animal->state_count; ++s) rec_put_u32(&w, (uint32_t)t->state_clip[s]);
    rec_put_u32(&w, t->lod_count);
    for (uint32_t l = 0; l < t->lod_count; ++l) {
        const cb_roster_lod *lod = &t->lods[l];
        rec_put_u32(&w, lod->joint_count);
        rec_put(&w, lod->remap, (size_t)lod->joint_count * sizeof *lod->remap);
        rec_put_u64(&w, lod->vertices), rec_put_u64(&w, lod->indices);
    }
    rec_put_u32(&w, t->socket_count);
    rec_put(&w, t->sockets, (size_t)t->socket_count * sizeof *t->sockets); /* plain numbers and zero-filled names */
    rec_put(&w, &t->lod_error, sizeof t->lod_error);                        /* plain numbers */
    rec_put_u32(&w, t->input_count);
    for (uint32_t i = 0; i < t->input_count; ++i) rec_put_str(&w, t->inputs[i]);
    rec_put_u32(&w, t->warnings.count);
    for (uint32_t i = 0; i < t->warnings.count; ++i) {
        rec_put_str(&w, t->warnings.items[i].kind);
        rec_put_str(&w, t->warnings.items[i].message);
    }
    if (w.failed) {
        free(w.data);
        return false;
    }
    uint64_t length = w.size - body, hash = cbpal_xxh64(w.data + body, length);
    memcpy(w.data + body - 16, &length, 8);
    memcpy(w.data + body - 8, &hash, 8);
    *data = w.data, *size = w.size;
    return true;
}

/* ---- reading ---- */

/* Counts are checked against what is left of the record before anything is allocated. */
static bool plausible(record_reader *r, uint64_t count, size_t min_bytes_each)
{
    if (r->failed || count > (uint64_t)(r->end - r->p) / (min_bytes_each ? min_bytes_each : 1)) r->failed = true;
    return !r->failed;
}

/* The speed methods are the measurement's own literals (catalog.h). */
static const char *known_method(const char *text)
{
    static const char *const methods[] = {"none", "root motion", "planted feet"};
    for (size_t i = 0; i < sizeof methods / sizeof methods[0]; ++i)
        if (strcmp(text, methods[i]) == 0) return methods[i];
    return NULL;
}

/* A stride as cb_stride_measure leaves it: feet within bounds, strings terminated. */
static bool stride_plausible(const cb_stride *s)
{
    bool ok = s->foot_count <= CB_MAX_FEET && memchr(s->why, 0, sizeof s->why);
    for (uint32_t k = 0; ok && k < s->foot_count; ++k)
        ok = memchr(s->feet[k].name, 0, sizeof s->feet[k].name) != NULL && s->feet[k].stance_count <= CB_MAX_STANCES;
    return ok;
}

static void read_clips(record_reader *r, cb_roster_type *t)
{
    uint32_t n = rec_get_u32(r);
    if (!plausible(r, n, 64) || !(t->clips = calloc(n ? n : 1, sizeof *t->clips))) {
        r->failed = true;
        return;
    }
    t->clip_count = n;
    for (uint32_t i = 0; i < n && !r->failed; ++i) {
        cb_roster_clip *c = &t->clips[i];
        char method[64];
        rec_get_str(r, c->name, sizeof c->name);
        c->first_row = rec_get_u32(r), c->frames = rec_get_u32(r);
        uint32_t flags = rec_get_u32(r); /* bit 0 loops, bit 1 held rows, bit 2 in place, bit 3 a planting follows */
        c->loops = (flags & 1u) != 0, c->step = (flags & 2u) != 0, c->in_place = (flags & 4u) != 0;
        c->fps = rec_get_f64(r), c->duration = rec_get_f64(r);
        rec_get_str(r, c->loop_reason, sizeof c->loop_reason);
        c->visible_error_mm = rec_get_f64(r);
        rec_get_str(r, c->rate_reason, sizeof c->rate_reason);
        c->speed.speed = rec_get_f64(r), c->speed.root = rec_get_f64(r), c->speed.feet = rec_get_f64(r);
        if (rec_get_str(r, method, sizeof method) && !(c->speed.method = known_method(method))) r->failed = true;
        rec_get(r, &c->speed.stride, sizeof c->speed.stride);
        if (!stride_plausible(&c->speed.stride)) r->failed = true;
        if (flags & 8u) rec_get(r, &c->plant, sizeof c->plant);
        if ((flags & 8u) && (!c->plant.planted || !memchr(c->plant.why, 0, sizeof c->plant.why))) r->failed = true;
        rec_get(r, &c->travel, sizeof c->travel);
        if (!memchr(c->travel.why, 0, sizeof c->travel.why)) r->failed = true;
        if (flags & 16u) c->cells = rec_get_u32(r), c->map_rows = rec_get_u32(r), c->cell_rate = rec_get_f64(r); /* timed */
    }
}

/* Sockets as written: names terminated, bones inside the rig. */
static void read_sockets(record_reader *r, cb_roster_type *t)
{
    uint32_t n = rec_get_u32(r);
    if (r->failed || !plausible(r, n, sizeof *t->sockets) || (n && !(t->sockets = calloc(n, sizeof *t->sockets)))) {
        r->failed = true;
        return;
    }
    t->socket_count = n;
    rec_get(r, t->sockets, (size_t)n * sizeof *t->sockets);
    for (uint32_t i = 0; i < n && !r->failed; ++i)
        r->failed = !memchr(t->sockets[i].name, 0, sizeof t->sockets[i].name) || t->sockets[i].bone >= t->bones;
}

static void read_states_and_lods(record_reader *r, const cb_catalog_animal *an, cb_roster_type *t)
{
    uint32_t states = rec_get_u32(r);
    if (r->failed || states != an->state_count || !(t->state_clip = calloc(states ? states : 1, sizeof *t->state_clip))) {
        r->failed = true;
        return;
    }
    for (uint32_t s = 0; s < states; ++s) {
        t->state_clip[s] = (int)rec_get_u32(r);
        if (t->state_clip[s] < 0 || (uint32_t)t->state_clip[s] >= t->clip_count) r->failed = true;
    }
    uint32_t lods = rec_get_u32(r);
    if (r->failed || lods != an->lod_count || !(t->lods = calloc(lods ? lods : 1, sizeof *t->lods))) {
        r->failed = true;
        return;
    }
    t->lod_count = lods;
    for (uint32_t l = 0; l < lods && !r->failed; ++l) {
        cb_roster_lod *lod = &t->lods[l];
        lod->path = an->lods[l];
        uint32_t joints = rec_get_u32(r);
        if (!plausible(r, joints, sizeof *lod->remap) || !(lod->remap = malloc((joints ? joints : 1) * sizeof *lod->remap))) {
            r->failed = true;
            return;
        }
        lod->joint_count = joints;
        rec_get(r, lod->remap, (size_t)joints * sizeof *lod->remap);
        for (uint32_t k = 0; k < joints; ++k)
            if (lod->remap[k] >= t->bones) r->failed = true;
        lod->vertices = rec_get_u64(r), lod->indices = rec_get_u64(r);
    }
}

static void read_inputs_and_warnings(record_reader *r, cb_roster_type *t)
{
    uint32_t n = rec_get_u32(r);
    if (!plausible(r, n, 4) || !(t->inputs = calloc(n ? n : 1, sizeof *t->inputs))) {
        r->failed = true;
        return;
    }
    for (uint32_t i = 0; i < n && !r->failed; ++i)
        if ((t->inputs[i] = rec_get_str(r, NULL, 0))) t->input_count = i + 1;
    uint32_t warnings = rec_get_u32(r);
    if (!plausible(r, warnings, 8)) return;
    for (uint32_t i = 0; i < warnings && !r->failed; ++i) {
        char kind[16];
        char *message = rec_get_str(r, kind, sizeof kind) ? rec_get_str(r, NULL, 0) : NULL;
        if (message) cb_warn(&t->warnings, strcmp(kind, "warning") == 0 ? "warning" : "note", "%s", message);
        free(message);
    }
}

bool cb_prep_record_decode(const unsigned char *data, size_t size, const cb_catalog_animal *an, cb_roster_type *t,
                           uint64_t *key)
{
    record_reader r = {data, data + size, false};
    char head[8];
    rec_get(&r, head, sizeof head);
    uint64_t record_key = rec_get_u64(&r), length = rec_get_u64(&r), hash = rec_get_u64(&r);
    if (r.failed || memcmp(head, magic, sizeof magic) != 0 || length != (uint64_t)(r.end - r.p) ||
        cbpal_xxh64(r.p, length) != hash)
        return false;
    t->key = rec_get_u64(&r), t->input_hash = rec_get_u64(&r);
    t->bones = rec_get_u32(&r), t->rows = rec_get_u32(&r);
    t->vertices = rec_get_u64(&r), t->indices = rec_get_u64(&r), t->mesh_bytes = rec_get_u64(&r);
    t->model_height = rec_get_f64(&r), t->speed_reference = rec_get_f64(&r);
    rec_get_str(&r, t->speed_reference_from, sizeof t->speed_reference_from);
    t->vat_measured = rec_get_u32(&r) != 0, t->vat_error = rec_get_f64(&r);
    read_clips(&r, t);
    read_states_and_lods(&r, an, t);
    read_sockets(&r, t);
    rec_get(&r, &t->lod_error, sizeof t->lod_error);
    read_inputs_and_warnings(&r, t);
    *key = record_key;
    return !r.failed && r.p == r.end && t->input_count > 0;
}

static bool decode(const unsigned char *data, size_t size, const cb_catalog_animal *an, const cb_limits *limits,
                   cb_roster_type *t)
{
    uint64_t key, now;
    return cb_prep_record_decode(data, size, an, t, &key) && cb_prep_key(an, limits, t->inputs, t->input_count, &now) &&
           now == key;
}

bool cb_prep_record_load(const char *path, const cb_catalog_animal *an, const cb_limits *limits, cb_roster_type *t)
{
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    unsigned char *data = NULL;
    size_t size = 0;
    if (fseek(f, 0, SEEK_END) == 0) {
        long end = ftell(f);
        if (end > 0 && end < (1L << 26) && fseek(f, 0, SEEK_SET) == 0 && (data = malloc((size_t)end)) &&
            fread(data, 1, (size_t)end, f) == (size_t)end)
            size = (size_t)end;
    }
    fclose(f);
    bool ok = size > 0 && decode(data, size, an, limits, t);
    free(data);
    if (!ok) cb_prep_clear(t);
    return ok;
}

void cb_prep_clear(cb_roster_type *t)
{
    free(t->clips);
    free(t->state_clip);
    free(t->state_sync);
    for (uint32_t l = 0; t->lods && l < t->lod_count; ++l) free(t->lods[l].remap);
    free(t->lods);
    free(t->sockets);
    for (uint32_t i = 0; i < t->input_count; ++i) free(t->inputs[i]);
    free(t->inputs);
    cb_warnings_free(&t->warnings);
    t->clips = NULL, t->state_clip = NULL, t->state_sync = NULL, t->lods = NULL, t->inputs = NULL, t->sockets = NULL;
    t->clip_count = t->lod_count = t->input_count = t->socket_count = 0;
    t->key = t->input_hash = 0;
    t->bones = t->rows = 0;
    t->vertices = t->indices = t->mesh_bytes = 0;
    t->model_height = t->speed_reference = 0;
    t->vat_measured = false, t->vat_error = 0;
    t->speed_reference_from[0] = '\0';
}
