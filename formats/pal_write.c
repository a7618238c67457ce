/* pal_write.c - see pal_write.h and docs/pal-format.md. */
#include "crowdbake/pal_write.h"

#include <stdlib.h>
#include <string.h>
#define ZSTD_STATIC_LINKING_ONLY /* ZSTD_c_stableInBuffer */
#include <zstd.h>

#include "internal/atomic_file.h"
#include "crowdbake_pal.h"
#include "internal/pal_mapping.h"

static void put32(unsigned char *d, uint32_t v)
{
    for (int i = 0; i < 4; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

static void put64(unsigned char *d, uint64_t v)
{
    for (int i = 0; i < 8; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

static void putf(unsigned char *d, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put32(d, v);
}

/* Index in the skin of the nearest ancestor that is also a joint, or -1. */
static int32_t joint_parent(const cb_model *m, const cb_skin *skin, uint32_t j)
{
    for (int32_t n = m->nodes[skin->joints[j]].parent; n >= 0; n = m->nodes[n].parent)
        for (uint32_t k = 0; k < skin->joint_count; ++k)
            if (skin->joints[k] == n) return (int32_t)k;
    return -1;
}

typedef struct layout_plan {
    uint64_t clips, bones, offsets, travel, ranges, timed, strings, strings_size, payload, payload_size;
} layout_plan;

static size_t strings_size(const cb_palette *p, const cb_model *m, const cb_skin *skin)
{
    size_t n = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) n += strlen(p->clips[c].name) + 1;
    for (uint32_t j = 0; j < skin->joint_count; ++j) n += strlen(m->nodes[skin->joints[j]].name) + 1;
    return n;
}

static bool local(const cb_palette *p) { return p->bone_space == CB_BONE_SPACE_LOCAL; }

static bool timed(const cb_palette *p) { return cb_palette_timed_clip(p) != NULL; }

static void write_header(unsigned char *d, const cb_palette *p, const cb_pal_write_options *opt, const layout_plan *lp)
{
    static const unsigned char magic[8] = {'C', 'B', 'P', 'A', 'L', '\r', '\n', 0x1a};
    memcpy(d, magic, 8);
    uint32_t flags = (opt->zstd ? CBPAL_FLAG_ZSTD : 0) | (opt->in_place ? CBPAL_FLAG_IN_PLACE : 0) |
                     (p->positions_relative ? CBPAL_FLAG_POSITIONS_RELATIVE : 0) |
                     (p->fitted ? CBPAL_FLAG_FITTED_ROWS : 0) | (p->row_travel ? CBPAL_FLAG_ROW_TRAVEL : 0) |
                     (local(p) ? CBPAL_FLAG_LOCAL_ROWS : 0) | (timed(p) ? CBPAL_FLAG_TIMED_ROWS : 0);
    /* A version only where its meaning differs from the one before: readers of version 1 keep
     * reading the rest. Version 4: held rows (a clip's step flag), which an older reader would
     * blend, so it must refuse them (docs/pal-format.md). Version 5: a per-row travel table,
     * which an older reader would leave out, sliding the feet it plants. Version 6: local rows,
     * which an older reader would draw uncomposed. Version 7: timed rows, whose map an older reader
     * would draw as rows and whose rows it would play at a uniform rate. */
    bool held = false;
    for (uint32_t c = 0; c < p->clip_count; ++c) held = held || p->clips[c].step;
    uint32_t version = timed(p) ? 7 : local(p) ? 6 : p->row_travel ? 5 : held ? 4 : p->positions_relative ? 3 : 1;
    uint32_t u[14] = {version, flags, CBPAL_HEADER_SIZE, (uint32_t)p->layout, (uint32_t)p->precision,
                      p->texels_per_bone, p->bone_count, p->row_texels, p->rows, p->width, p->height, p->blocks,
                      cb_precision_texel_bytes(p->precision), p->clip_count};
    for (int i = 0; i < 14; ++i) put32(d + 8 + 4 * i, u[i]);
    putf(d + 64, (float)p->fps);
    putf(d + 68, opt->speed_reference);
    putf(d + 72, p->linear_range);
    for (int k = 0; k < 3; ++k) putf(d + 76 + 4 * k, p->bounds_min[k]), putf(d + 88 + 4 * k, p->bounds_max[k]);
    putf(d + 100, (float)p->max_error);
    putf(d + 104, (float)p->model_height);
    putf(d + 108, (float)p->visible_error);
    uint64_t w[9] = {opt->input_hash, lp->clips, lp->bones, lp->strings, lp->strings_size, lp->payload, lp->payload_size,
                     (uint64_t)p->texel_bytes, 0 /* checksum, filled last */};
    for (int i = 0; i < 9; ++i) put64(d + 112 + 8 * i, w[i]);
    if (p->positions_relative) put64(d + 184, lp->offsets);
    if (p->row_travel) put64(d + 192, lp->travel);
    if (local(p)) put64(d + 200, lp->ranges);
    if (timed(p)) put64(d + 208, lp->timed);
}

static void write_tables(unsigned char *d, const cb_palette *p, const cb_model *m, const cb_skin *skin, const layout_plan *lp)
{
    uint32_t s = 0;
    char *strings = (char *)d + lp->strings;
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *clip = &p->clips[c];
        unsigned char *e = d + lp->clips + (uint64_t)c * CBPAL_CLIP_SIZE;
        uint32_t len = (uint32_t)strlen(clip->name);
        memcpy(strings + s, clip->name, len + 1);
        put32(e, s), put32(e + 4, len);
        s += len + 1;
        put32(e + 8, clip->first_row), put32(e + 12, clip->frames);
        putf(e + 16, (float)clip->fps), putf(e + 20, (float)clip->duration), putf(e + 24, (float)clip->start);
        put32(e + 28, (clip->loops ? CBPAL_CLIP_LOOPS : 0) | (clip->fitted ? CBPAL_CLIP_FITTED : 0) |
                          (clip->step ? CBPAL_CLIP_STEP : 0) | (clip->timed ? CBPAL_CLIP_TIMED : 0));
        if (timed(p) && clip->timed) { /* an untimed clip's entry stays 0 */
            unsigned char *t = d + lp->timed + (uint64_t)c * CBPAL_TIMED_SIZE;
            put32(t, clip->cells), putf(t + 4, (float)clip->cell_rate), put32(t + 8, clip->map_rows);
        }
        for (int k = 0; k < 3; ++k) {
            putf(e + 32 + 4 * k, clip->root_velocity[k]);
            putf(e + 44 + 4 * k, clip->bounds_min[k]);
            putf(e + 56 + 4 * k, clip->bounds_max[k]);
            if (p->row_travel && clip->travel.applied) putf(e + 68 + 4 * k, clip->travel.heading[k]);
        }
    }
    for (uint32_t r = 0; p->row_travel && r < p->rows; ++r) putf(d + lp->travel + 4 * (uint64_t)r, p->row_travel[r]);
    for (uint32_t i = 0; local(p) && i < p->bone_count * 8; ++i) /* the bone range table; its reserved word 0.0f is 0 */
        putf(d + lp->ranges + 4 * (uint64_t)i, p->bone_ranges[i]);
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        unsigned char *e = d + lp->bones + (uint64_t)j * CBPAL_BONE_SIZE;
        const char *name = m->nodes[skin->joints[j]].name;
        uint32_t len = (uint32_t)strlen(name);
        memcpy(strings + s, name, len + 1);
        put32(e, s), put32(e + 4, len);
        s += len + 1;
        put32(e + 8, (uint32_t)joint_parent(m, skin, j));
        for (int k = 0; k < 3; ++k) putf(e + 16 + 4 * k, p->bind_positions[j * 3 + k]);
        for (int k = 0; p->positions_relative && k < 3; ++k) putf(d + lp->offsets + j * 12 + 4 * k, p->position_offsets[j * 3 + k]);
    }
}

/* Header and tables, zero-padded to the payload offset, for a payload of payload_size bytes;
 * the checksum field still 0. */
/* Where the header's tables, strings and payload lie: from the clips, the bones and their names. */
static layout_plan plan_layout(const cb_palette *p, const cb_model *m, const cb_skin *skin, uint64_t payload_size)
{
    layout_plan lp;
    lp.clips = CBPAL_HEADER_SIZE;
    lp.bones = lp.clips + (uint64_t)p->clip_count * CBPAL_CLIP_SIZE;
    lp.offsets = lp.bones + (uint64_t)p->bone_count * CBPAL_BONE_SIZE;
    lp.travel = lp.offsets + (p->positions_relative ? (uint64_t)p->bone_count * 12 : 0);
    lp.ranges = lp.travel + (p->row_travel ? (uint64_t)p->rows * 4 : 0);
    lp.timed = lp.ranges + (local(p) ? (uint64_t)p->bone_count * 32 : 0);
    lp.strings = lp.timed + (timed(p) ? (uint64_t)p->clip_count * CBPAL_TIMED_SIZE : 0);
    lp.strings_size = strings_size(p, m, skin);
    lp.payload = (lp.strings + lp.strings_size + CBPAL_PAYLOAD_ALIGN - 1) / CBPAL_PAYLOAD_ALIGN * CBPAL_PAYLOAD_ALIGN;
    lp.payload_size = payload_size;
    return lp;
}

static unsigned char *build_meta(const cb_palette *p, const cb_model *m, int32_t skin_index, const cb_pal_write_options *opt,
                                 uint64_t payload_size, size_t *meta_size)
{
    const cb_skin *skin = &m->skins[skin_index];
    layout_plan lp = plan_layout(p, m, skin, payload_size);
    unsigned char *d = calloc((size_t)lp.payload, 1);
    if (!d) return NULL;
    write_header(d, p, opt, &lp);
    write_tables(d, p, m, skin, &lp);
    *meta_size = (size_t)lp.payload;
    return d;
}

enum { ZSTD_CHUNK = 64 << 10 }; /* small enough that most palettes take several */

/* Compresses the texels into the file a chunk at a time (the compressed copy of a large
 * palette is nearly its size again). The input is stable and its size pledged, which gives the
 * bytes one-shot ZSTD_compress gives. *size gets the compressed size. */
static cb_status write_compressed(cb_atomic_file *f, const cb_palette *p, int level, uint64_t *size, cb_error *err)
{
    ZSTD_CCtx *cc = ZSTD_createCCtx();
    unsigned char *chunk = malloc(ZSTD_CHUNK);
    cb_status rc = cc && chunk ? CB_OK : cb_fail(err, CB_ERR_INTERNAL, "out of memory compressing a %zu-byte palette", p->texel_bytes);
    size_t r = 0;
    if (!rc && (ZSTD_isError(r = ZSTD_CCtx_setParameter(cc, ZSTD_c_compressionLevel, level)) ||
                ZSTD_isError(r = ZSTD_CCtx_setParameter(cc, ZSTD_c_stableInBuffer, 1)) ||
                ZSTD_isError(r = ZSTD_CCtx_setPledgedSrcSize(cc, p->texel_bytes))))
        rc = cb_fail(err, CB_ERR_INTERNAL, "zstd compression failed: %s", ZSTD_getErrorName(r));
    ZSTD_inBuffer in = {p->texels, p->texel_bytes, 0};
    *size = 0;
    for (bool done = false; !rc && !done;) {
        ZSTD_outBuffer out = {chunk, ZSTD_CHUNK, 0};
        r = ZSTD_compressStream2(cc, &out, &in, ZSTD_e_end);
        if (ZSTD_isError(r)) rc = cb_fail(err, CB_ERR_INTERNAL, "zstd compression failed: %s", ZSTD_getErrorName(r));
        else rc = cb_atomic_write(f, chunk, out.pos, err);
        *size += out.pos;
        done = r == 0;
    }
    ZSTD_freeCCtx(cc);
    free(chunk);
    return rc;
}

/* The checksum over the header and tables (its own field 0) and the payload, which the file
 * holds from payload_at on when it was compressed into it, or the palette's texels. */
static cb_status checksum(cb_atomic_file *f, const cb_palette *p, const unsigned char *meta, size_t meta_size, uint64_t payload_size,
                          bool in_file, uint64_t *out, cb_error *err)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    cbpal_xxh64_update(&h, meta, meta_size);
    if (!in_file) {
        cbpal_xxh64_update(&h, p->texels, p->texel_bytes);
        *out = cbpal_xxh64_digest(&h);
        return CB_OK;
    }
    unsigned char *chunk = malloc(ZSTD_CHUNK);
    if (!chunk) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    cb_status rc = CB_OK;
    for (uint64_t at = 0; !rc && at < payload_size; at += ZSTD_CHUNK) {
        size_t n = payload_size - at < ZSTD_CHUNK ? (size_t)(payload_size - at) : ZSTD_CHUNK;
        if (!(rc = cb_atomic_read_back(f, chunk, n, meta_size + at, err))) cbpal_xxh64_update(&h, chunk, n);
    }
    free(chunk);
    *out = cbpal_xxh64_digest(&h);
    return rc;
}

/* A timed clip as a reader accepts it (docs/pal-format.md "Timed rows"): its map rows before its
 * first row, cells and a rate, and in half floats rows its map can name exactly (integers to
 * 2048); the map's texels are the bake's (timed_map_fill). */
static cb_status check_timed(const char *path, const cb_palette *p, cb_error *err)
{
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *clip = &p->clips[c];
        if (clip->timed && p->precision == CB_PRECISION_HALF && clip->frames > 2048)
            return cb_fail(err, CB_ERR_INTERNAL, "%s: clip %s has %u timed rows, more than a half float map can name (2048): "
                           "a bug in what built the palette", path, clip->name, clip->frames);
        if (clip->timed && (clip->cells == 0 || !(clip->cell_rate > 0) || clip->map_rows > clip->first_row ||
                            clip->map_rows != cb_timed_map_rows(clip->cells, p->row_texels)))
            return cb_fail(err, CB_ERR_INTERNAL, "%s: clip %s's timed rows are inconsistent (cells %u, cell rate %g, %u map "
                           "rows before row %u): a bug in what built the palette", path, clip->name, clip->cells,
                           clip->cell_rate, clip->map_rows, clip->first_row);
    }
    return CB_OK;
}

cb_status cb_pal_write(const char *path, const cb_palette *p, const cb_model *m, int32_t skin,
                       const cb_pal_write_options *opt, cb_error *err)
{
    cb_status bad = check_timed(path, p, err);
    if (bad) return bad;
    size_t meta_size = 0;
    uint64_t payload_size = p->texel_bytes, sum = 0;
    unsigned char *meta = build_meta(p, m, skin, opt, payload_size, &meta_size);
    if (!meta) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    cb_atomic_file f;
    cb_status rc = cb_atomic_open(&f, path, err);
    if (rc) {
        free(meta);
        return rc;
    }
    /* Uncompressed: header, tables and checksum first, then the texels from where they are.
     * Compressed: the header waits for the payload's size, and is written over its place. */
    if (!opt->zstd && !(rc = checksum(&f, p, meta, meta_size, payload_size, false, &sum, err))) {
        put64(meta + CBPAL_CHECKSUM_OFFSET, sum);
        if (!(rc = cb_atomic_write(&f, meta, meta_size, err))) rc = cb_atomic_write(&f, p->texels, p->texel_bytes, err);
    } else if (opt->zstd && !(rc = cb_atomic_write(&f, meta, meta_size, err)) &&
               !(rc = write_compressed(&f, p, opt->zstd_level ? opt->zstd_level : 9, &payload_size, err))) {
        free(meta);
        if (!(meta = build_meta(p, m, skin, opt, payload_size, &meta_size))) rc = cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        if (!rc && !(rc = checksum(&f, p, meta, meta_size, payload_size, true, &sum, err))) {
            put64(meta + CBPAL_CHECKSUM_OFFSET, sum);
            rc = cb_atomic_rewrite(&f, meta, meta_size, 0, err);
        }
    }
    if (!rc) rc = cb_atomic_commit(&f, err);
    else cb_atomic_abort(&f);
    free(meta);
    return rc;
}

/* ---- written where it is baked ---- */

void cb_pal_mapping_init(cb_pal_mapping *mp, const char *path, const cb_model *m, int32_t skin)
{
    memset(mp, 0, sizeof *mp);
    mp->path = path, mp->model = m, mp->skin = skin;
    mp->file.fd = -1, mp->file.slot = -1;
}

void cb_pal_mapping_abort(cb_pal_mapping *mp)
{
    if (mp->open) cb_atomic_abort(&mp->file);
    mp->open = false, mp->base = NULL, mp->meta_size = 0;
}

void *cb_pal_map_texels(void *ctx, const cb_palette *p)
{
    cb_pal_mapping *mp = ctx;
    cb_pal_mapping_abort(mp); /* asked again (qpos fell back to affine): a file of the new size */
    size_t meta_size = (size_t)plan_layout(p, mp->model, &mp->model->skins[mp->skin], p->texel_bytes).payload;
    cb_error ignored = {0}; /* where mapping fails, cb_pal_write says what is wrong */
    void *base = NULL;
    if (cb_atomic_open(&mp->file, mp->path, &ignored)) return NULL;
    mp->open = true;
    if (cb_atomic_map(&mp->file, meta_size + p->texel_bytes, &base, &ignored)) {
        cb_pal_mapping_abort(mp);
        return NULL;
    }
    mp->base = base, mp->meta_size = meta_size;
    return mp->base + meta_size;
}

bool cb_pal_mapping_holds(const cb_pal_mapping *mp, const cb_palette *p)
{
    /* Mapped before its rows were baked: a travel table measured after them makes the tables
     * longer than the file planned, and such a palette is written the ordinary way. */
    if (!mp->open || !mp->base || p->texels != mp->base + mp->meta_size) return false;
    return plan_layout(p, mp->model, &mp->model->skins[mp->skin], p->texel_bytes).payload == mp->meta_size;
}

cb_status cb_pal_write_mapped(cb_pal_mapping *mp, const cb_palette *p, const cb_pal_write_options *opt, cb_error *err)
{
    cb_status bad = check_timed(mp->path, p, err);
    if (bad) {
        cb_pal_mapping_abort(mp);
        return bad;
    }
    size_t meta_size = 0;
    uint64_t sum = 0;
    unsigned char *meta = build_meta(p, mp->model, mp->skin, opt, p->texel_bytes, &meta_size);
    cb_status rc = !meta ? cb_fail(err, CB_ERR_INTERNAL, "out of memory")
                   : meta_size != mp->meta_size || opt->zstd
                       ? cb_fail(err, CB_ERR_INTERNAL, "%s: the palette does not fit the file mapped for it", mp->path)
                       : checksum(&mp->file, p, meta, meta_size, p->texel_bytes, false, &sum, err);
    if (!rc) {
        put64(meta + CBPAL_CHECKSUM_OFFSET, sum);
        rc = cb_atomic_write(&mp->file, meta, meta_size, err); /* at offset 0, before the payload */
    }
    if (!rc) rc = cb_atomic_commit(&mp->file, err);
    else cb_atomic_abort(&mp->file);
    mp->open = false, mp->base = NULL;
    free(meta);
    return rc;
}
