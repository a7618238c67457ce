/* roster_fragment.c - one type's part of the manifest, for builds that bake each type as its own
 * action (`bake CATALOG --type NAME`, one per type on as many machines as a build engine has),
 * and the merge that writes the manifest from them (`roster merge`).
 *
 * A fragment is "CBFRAG1" and a NUL, then in this machine's byte order: the catalog's path (as
 * given), the run's --sync and --default-state, the type's name and formats, its outcome and
 * error, its output paths and palette facts, then its prep record (roster_cache.h), which holds
 * everything else the manifest says of it. Strings are a u32 length and their bytes. Paths are
 * as the command line and catalog gave them: relative in, relative out. */
#define _GNU_SOURCE /* open_memstream */
#include "roster_cache.h"
#include "roster_files.h"

#include <stdlib.h>
#include <string.h>

#include "catalog/catalog_toml.h"

static const char fragment_magic[8] = "CBFRAG1";

static void put_str(FILE *f, const char *s)
{
    uint32_t n = s ? (uint32_t)strlen(s) : 0;
    fwrite(&n, sizeof n, 1, f);
    fwrite(s ? s : "", 1, n, f);
}

static void put_u32(FILE *f, uint32_t v) { fwrite(&v, sizeof v, 1, f); }
static void put_u64(FILE *f, uint64_t v) { fwrite(&v, sizeof v, 1, f); }
static void put_f32(FILE *f, float v) { fwrite(&v, sizeof v, 1, f); }

static void put_type(FILE *f, const cb_roster_type *t)
{
    put_str(f, t->animal->name);
    put_u32(f, t->animal->bake.formats);
    put_u32(f, t->outcome == CB_TYPE_FAILED);
    put_u32(f, (uint32_t)t->error.status), put_u32(f, (uint32_t)t->error.setting);
    put_str(f, t->error.message);
    put_str(f, t->pal_path), put_str(f, t->exr_path), put_str(f, t->babylon_path);
    put_u32(f, t->layout), put_u32(f, t->precision);
    put_u32(f, t->width), put_u32(f, t->height), put_u32(f, t->blocks);
    put_f32(f, t->max_error), put_f32(f, t->visible_error);
    put_u64(f, t->palette_bytes), put_u64(f, t->pal_file_bytes), put_u64(f, t->exr_file_bytes);
}

cb_status roster_write_fragment(const cb_roster *r, const cb_roster_fragment *fragment, cb_error *err)
{
    if (r->type_count != 1) return cb_fail(err, CB_ERR_INTERNAL, "a fragment holds one type, not %u", r->type_count);
    const cb_roster_type *t = &r->types[0];
    unsigned char *record = NULL;
    size_t record_size = 0;
    if (t->outcome != CB_TYPE_FAILED && !cb_prep_record_encode(t, 0, &record, &record_size))
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    char *buf = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&buf, &size);
    if (!f) return free(record), cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    fwrite(fragment_magic, 1, sizeof fragment_magic, f);
    put_str(f, r->catalog->path);
    put_str(f, fragment->syncs), put_str(f, fragment->default_state);
    put_type(f, t);
    put_u64(f, record_size);
    fwrite(record ? (const void *)record : "", 1, record_size, f);
    bool failed = ferror(f);
    fclose(f);
    free(record);
    bool written;
    cb_status rc = failed ? cb_fail(err, CB_ERR_INTERNAL, "out of memory")
                          : roster_write_if_changed(fragment->path, buf, size, &written, err);
    free(buf);
    return rc;
}

/* ---- reading ---- */

typedef struct frag_reader {
    const unsigned char *p, *end;
    bool failed;
} frag_reader;

static void get(frag_reader *r, void *out, size_t n)
{
    if (r->failed || (size_t)(r->end - r->p) < n) {
        r->failed = true;
        memset(out, 0, n);
        return;
    }
    memcpy(out, r->p, n);
    r->p += n;
}

static uint32_t get_u32(frag_reader *r) { uint32_t v; get(r, &v, sizeof v); return v; }
static uint64_t get_u64(frag_reader *r) { uint64_t v; get(r, &v, sizeof v); return v; }
static float get_f32(frag_reader *r) { float v; get(r, &v, sizeof v); return v; }

/* A string into buf (size bytes, NUL-terminated); too long for it reads as damage. */
static void get_str(frag_reader *r, char *buf, size_t size)
{
    uint32_t n = get_u32(r);
    if (r->failed || n >= size || (size_t)(r->end - r->p) < n) {
        r->failed = true;
        buf[0] = '\0';
        return;
    }
    memcpy(buf, r->p, n);
    buf[n] = '\0';
    r->p += n;
}

typedef struct fragment {
    char path[4096];         /* the file, for messages */
    unsigned char *data;
    size_t size;
    char catalog[4096], syncs[1024], default_state[256], name[256];
    frag_reader rest;        /* past the header: the type's facts and record */
} fragment;

static cb_status read_fragment(const char *path, fragment *fr, cb_error *err)
{
    snprintf(fr->path, sizeof fr->path, "%s", path);
    FILE *f = fopen(path, "rb");
    if (!f) return cb_fail(err, CB_ERR_IO, "%s: cannot open the fragment (bake CATALOG --type NAME writes it)", path);
    long end = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (end > 0 && end < (1L << 28) && fseek(f, 0, SEEK_SET) == 0 && (fr->data = malloc((size_t)end)) &&
        fread(fr->data, 1, (size_t)end, f) == (size_t)end)
        fr->size = (size_t)end;
    fclose(f);
    frag_reader r = {fr->data, fr->data + fr->size, fr->size == 0};
    char head[8];
    get(&r, head, sizeof head);
    get_str(&r, fr->catalog, sizeof fr->catalog);
    get_str(&r, fr->syncs, sizeof fr->syncs);
    get_str(&r, fr->default_state, sizeof fr->default_state);
    get_str(&r, fr->name, sizeof fr->name);
    if (r.failed || memcmp(head, fragment_magic, sizeof head) != 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: not a crowdbake %s manifest fragment, or damaged; bake its type again "
                       "(crowdbake bake CATALOG --type NAME)", path, CROWDBAKE_VERSION);
    fr->rest = r;
    return CB_OK;
}

/* The type's facts and record, into t (t->animal set). */
static cb_status read_type(fragment *fr, const cb_catalog *cat, cb_catalog_animal *an, cb_roster_type *t, cb_error *err)
{
    frag_reader *r = &fr->rest;
    /* The formats it was baked in (--format may have replaced the catalog's). */
    an->bake.formats = get_u32(r) & (CB_FORMAT_PAL | CB_FORMAT_EXR | CB_FORMAT_BABYLON);
    bool failed = get_u32(r);
    t->error.status = (cb_status)get_u32(r), t->error.setting = (cb_setting)get_u32(r);
    get_str(r, t->error.message, sizeof t->error.message);
    get_str(r, t->pal_path, sizeof t->pal_path), get_str(r, t->exr_path, sizeof t->exr_path);
    get_str(r, t->babylon_path, sizeof t->babylon_path);
    t->layout = (cb_layout)get_u32(r), t->precision = (cb_precision)get_u32(r);
    t->width = get_u32(r), t->height = get_u32(r), t->blocks = get_u32(r);
    t->max_error = get_f32(r), t->visible_error = get_f32(r);
    t->palette_bytes = get_u64(r), t->pal_file_bytes = get_u64(r), t->exr_file_bytes = get_u64(r);
    uint64_t record_size = get_u64(r), key;
    bool intact = !r->failed && record_size == (uint64_t)(r->end - r->p) && (failed || record_size > 0);
    if (intact && !failed) intact = cb_prep_record_decode(r->p, record_size, t->animal, t, &key);
    if (!intact)
        return cb_fail(err, CB_ERR_INPUT, "%s: type %s's fragment is damaged, or its catalog %s changed since; bake "
                       "it again (crowdbake bake %s --type %s)", fr->path, fr->name, cat->path, cat->path, fr->name);
    t->outcome = failed ? CB_TYPE_FAILED : CB_TYPE_BAKED;
    if (failed) {
        if (!t->error.status) t->error.status = CB_ERR_INPUT;
        return CB_OK;
    }
    cb_error states = {0};
    if (roster_decide_states(cat, t->animal, t, &states)) t->outcome = CB_TYPE_FAILED, t->error = states;
    return CB_OK;
}

static int32_t find_type(const cb_catalog *cat, const char *name)
{
    for (uint32_t i = 0; i < cat->animal_count; ++i)
        if (strcmp(cat->animals[i].name, name) == 0) return (int32_t)i;
    return -1;
}

/* The catalog every fragment names, with the state options they were baked with. */
static cb_status load_catalog(const fragment *frags, uint32_t count, cb_catalog *cat, cb_error *err)
{
    for (uint32_t i = 1; i < count; ++i)
        if (strcmp(frags[i].catalog, frags[0].catalog) || strcmp(frags[i].syncs, frags[0].syncs) ||
            strcmp(frags[i].default_state, frags[0].default_state))
            return cb_fail(err, CB_ERR_INPUT, "%s: baked from %s, %s from %s (or with other --sync or --default-state): "
                           "merge the fragments of one catalog baked with the same options", frags[i].path,
                           frags[i].catalog, frags[0].path, frags[0].catalog);
    if (cb_catalog_load_checking(frags[0].catalog, "", cat, err)) return err->status; /* reads no model */
    const char *syncs = frags[0].syncs[0] ? frags[0].syncs : NULL;
    const char *state = frags[0].default_state[0] ? frags[0].default_state : NULL;
    if (cb_catalog_override_states(cat, syncs, state, err)) return cb_catalog_free(cat), err->status;
    return CB_OK;
}

static cb_status place_fragments(fragment *frags, uint32_t count, cb_catalog *cat, cb_roster *r, cb_error *err)
{
    for (uint32_t f = 0; f < count; ++f) {
        int32_t i = find_type(cat, frags[f].name);
        if (i < 0)
            return cb_fail(err, CB_ERR_INPUT, "%s: type %s is not in %s; bake the catalog's types again", frags[f].path,
                           frags[f].name, cat->path);
        cb_roster_type *t = &r->types[i];
        if (t->animal)
            return cb_fail(err, CB_ERR_INPUT, "%s: type %s has two fragments; pass one", frags[f].path, frags[f].name);
        t->animal = &cat->animals[i];
        t->owner = (uint32_t)i;
        if (read_type(&frags[f], cat, &cat->animals[i], t, err)) return err->status;
    }
    for (uint32_t i = 0; i < r->type_count; ++i)
        if (!r->types[i].animal)
            return cb_fail(err, CB_ERR_INPUT, "%s: no fragment for type %s; add the one `crowdbake bake %s --type %s` "
                           "writes", cat->path, cat->animals[i].name, cat->path, cat->animals[i].name);
    return CB_OK;
}

/* As cb_roster_bake settles its types once they are baked. */
static void settle(cb_roster *r)
{
    roster_assign_owners(r);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        cb_roster_type *t = &r->types[i];
        if (t->outcome == CB_TYPE_FAILED) r->failed++;
        else if (t->owner == i) r->baked++;
        else roster_settle_shared(r, i);
    }
}

cb_status cb_roster_merge(char *const *paths, uint32_t count, const char *manifest, cb_catalog *cat, cb_roster *r,
                          cb_error *err)
{
    memset(r, 0, sizeof *r);
    memset(cat, 0, sizeof *cat);
    if (count == 0) return cb_fail(err, CB_ERR_SETTINGS, "roster merge needs the fragments of every type");
    fragment *frags = calloc(count, sizeof *frags);
    if (!frags) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    cb_status rc = CB_OK;
    for (uint32_t i = 0; i < count && !rc; ++i) rc = read_fragment(paths[i], &frags[i], err);
    if (!rc) rc = load_catalog(frags, count, cat, err);
    if (!rc) {
        r->catalog = cat;
        r->type_count = cat->animal_count;
        r->types = calloc(cat->animal_count ? cat->animal_count : 1, sizeof *r->types);
        rc = r->types ? place_fragments(frags, count, cat, r, err) : cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    if (!rc) {
        settle(r);
        snprintf(r->manifest_path, sizeof r->manifest_path, "%s", manifest);
        rc = roster_make_parent_directories(manifest, err);
        if (!rc) rc = roster_write_manifest(cat, r, manifest, err);
    }
    for (uint32_t i = 0; i < r->type_count && !rc; ++i)
        if (r->types[i].outcome == CB_TYPE_FAILED) *err = r->types[i].error, rc = err->status;
    for (uint32_t i = 0; i < count; ++i) free(frags[i].data);
    free(frags);
    return rc;
}
