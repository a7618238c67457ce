/* roster_fragment.c - one type's part of the manifest, for builds that bake each type as its own
 * action (`bake CATALOG --type NAME`, one per type on as many machines as a build engine has),
 * and the merge that writes the manifest from them (`roster merge`).
 *
 * A fragment is "CBFRAG1" and a NUL, then in this machine's byte order: the catalog's path (as
 * given), the run's --sync and --default-state, the type's name and formats, its outcome and
 * error, its output paths and palette facts, then its prep record (roster_cache.h), which holds
 * everything else the manifest says of it. Strings are a u32 length and their bytes. Paths are
 * as the command line and catalog gave them: relative in, relative out. */
#include "roster_cache.h"
#include "roster_files.h"
#include "record_io.h"

#include <stdlib.h>
#include <string.h>

#include "catalog/catalog_toml.h"

static const char fragment_magic[8] = "CBFRAG1";

static void put_type(record_writer *w, const cb_roster_type *t)
{
    rec_put_str(w, t->animal->name);
    rec_put_u32(w, t->animal->bake.formats);
    rec_put_u32(w, t->outcome == CB_TYPE_FAILED);
    rec_put_u32(w, (uint32_t)t->error.status), rec_put_u32(w, (uint32_t)t->error.setting);
    rec_put_str(w, t->error.message);
    rec_put_u32(w, cb_output_format_count()); /* a path per row of the table of formats (outputs.h) */
    for (uint32_t k = 0; k < cb_output_format_count(); ++k) rec_put_str(w, t->paths[k]);
    rec_put_u32(w, t->layout), rec_put_u32(w, t->precision);
    rec_put_u32(w, t->width), rec_put_u32(w, t->height), rec_put_u32(w, t->blocks);
    rec_put_f32(w, t->max_error), rec_put_f32(w, t->visible_error);
    rec_put_u64(w, t->palette_bytes), rec_put_u64(w, t->file_bytes);
}

cb_status roster_write_fragment(const cb_roster *r, const cb_roster_fragment *fragment, cb_error *err)
{
    if (r->type_count != 1) return cb_fail(err, CB_ERR_INTERNAL, "a fragment holds one type, not %u", r->type_count);
    const cb_roster_type *t = &r->types[0];
    unsigned char *record = NULL;
    size_t record_size = 0;
    if (t->outcome != CB_TYPE_FAILED && !cb_prep_record_encode(t, 0, &record, &record_size))
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    record_writer w = {0};
    rec_put(&w, fragment_magic, sizeof fragment_magic);
    rec_put_str(&w, r->catalog->path);
    rec_put_str(&w, fragment->syncs), rec_put_str(&w, fragment->default_state);
    put_type(&w, t);
    rec_put_u64(&w, record_size);
    rec_put(&w, record, record_size);
    free(record);
    bool written;
    cb_status rc = w.failed ? cb_fail(err, CB_ERR_INTERNAL, "out of memory")
                            : roster_write_if_changed(fragment->path, (const char *)w.data, w.size, &written, err);
    free(w.data);
    return rc;
}

/* ---- reading ---- */

typedef struct fragment {
    char path[4096];         /* the file, for messages */
    unsigned char *data;
    size_t size;
    char catalog[4096], syncs[1024], default_state[256], name[256];
    record_reader rest;        /* past the header: the type's facts and record */
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
    record_reader r = {fr->data, fr->data + fr->size, fr->size == 0};
    char head[8];
    rec_get(&r, head, sizeof head);
    rec_get_str(&r, fr->catalog, sizeof fr->catalog);
    rec_get_str(&r, fr->syncs, sizeof fr->syncs);
    rec_get_str(&r, fr->default_state, sizeof fr->default_state);
    rec_get_str(&r, fr->name, sizeof fr->name);
    if (r.failed || memcmp(head, fragment_magic, sizeof head) != 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: not a crowdbake %s manifest fragment, or damaged; bake its type again "
                       "(crowdbake bake CATALOG --type NAME)", path, CROWDBAKE_VERSION);
    fr->rest = r;
    return CB_OK;
}

/* The type's facts and record, into t (t->animal set). */
static cb_status read_type(fragment *fr, const cb_catalog *cat, cb_catalog_animal *an, cb_roster_type *t, cb_error *err)
{
    record_reader *r = &fr->rest;
    /* The formats it was baked in (--format may have replaced the catalog's). */
    an->bake.formats = rec_get_u32(r);
    bool failed = rec_get_u32(r);
    t->error.status = (cb_status)rec_get_u32(r), t->error.setting = (cb_setting)rec_get_u32(r);
    rec_get_str(r, t->error.message, sizeof t->error.message);
    if (rec_get_u32(r) != cb_output_format_count()) r->failed = true; /* another crowdbake's table */
    for (uint32_t k = 0; k < cb_output_format_count(); ++k) rec_get_str(r, t->paths[k], sizeof t->paths[k]);
    t->layout = (cb_layout)rec_get_u32(r), t->precision = (cb_precision)rec_get_u32(r);
    t->width = rec_get_u32(r), t->height = rec_get_u32(r), t->blocks = rec_get_u32(r);
    t->max_error = rec_get_f32(r), t->visible_error = rec_get_f32(r);
    t->palette_bytes = rec_get_u64(r), t->file_bytes = rec_get_u64(r);
    uint64_t record_size = rec_get_u64(r), key;
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
