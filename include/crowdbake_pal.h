/* crowdbake_pal.h - reader for crowdbake .pal bone-matrix palettes. Public domain / MIT-0.
 *
 * One C99 header and its part crowdbake_pal_runtime.h (a bone's matrix at a time, as the shaders
 * blend rows; keep the two side by side), no dependencies (define CBPAL_WITH_ZSTD and link
 * libzstd to read files baked with --zstd). In exactly one C file:
 *
 *     #define CROWDBAKE_PAL_IMPLEMENTATION
 *     #include "crowdbake_pal.h"
 *
 * Then:
 *
 *     cbpal_file pal;
 *     char err[256];
 *     if (cbpal_open("goat.pal", 0, &pal, err, sizeof err) != 0) { puts(err); ... }
 *     upload(pal.texels, pal.header.width, pal.header.height);   // straight from the page cache
 *     cbpal_close(&pal);
 *
 * The file is mapped with mmap (read() where that fails); every size and offset is checked
 * against the file length before use; uncompressed texels are returned without a copy.
 * The format is specified in docs/pal-format.md. Little-endian hosts only (the texels are
 * little-endian and handed over as they are).
 */
#ifndef CROWDBAKE_PAL_H
#define CROWDBAKE_PAL_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CBPAL_VERSION 7 /* newest known; writers write the oldest version that holds what a file says (pal-format.md) */
#define CBPAL_HEADER_SIZE 256
#define CBPAL_CLIP_SIZE 80
#define CBPAL_BONE_SIZE 32
#define CBPAL_PAYLOAD_ALIGN 4096
#define CBPAL_CHECKSUM_OFFSET 176

enum { CBPAL_LAYOUT_MAT4 = 0, CBPAL_LAYOUT_AFFINE = 1, CBPAL_LAYOUT_QPOS = 2 };
enum { CBPAL_PRECISION_FLOAT = 0, CBPAL_PRECISION_HALF = 1, CBPAL_PRECISION_U16 = 2 };
/* CBPAL_FLAG_POSITIONS_RELATIVE (versions 2 and 3): qpos position texels hold the joint's position
 * less its bone's position offset (cbpal_bone.position_offset: version 3 files store it in their
 * offset table, version 2 files used the bind position); add it back (CB_POSITIONS_RELATIVE in
 * the shipped GLSL). */
/* CBPAL_FLAG_FITTED_ROWS: every clip's rows were fitted to the linear blend between them rather
 * than sampled; CBPAL_CLIP_FITTED: this clip's were (a palette may mix fitted and sampled clips;
 * files written before the clip flag set only the header's, and cbpal_get_clip then sets the
 * clip's). Read and blend them as always. */
/* CBPAL_FLAG_ROW_TRAVEL (version 5): the file holds a per-row travel offset table (header offset
 * 192, one f32 per row): a runtime that moves an instance at a clip's ground speed adds
 * cbpal_travel_offset to its position (rotated and scaled as the instance is), so the planted
 * feet stay still. Files without it read every offset as 0. */
/* CBPAL_FLAG_LOCAL_ROWS (version 6): rows hold each bone in its parent's frame, with a bone range table
 * (header offset 200): blend each bone's rows, then compose down the skeleton (pal-format.md "Local rows"). */
/* CBPAL_FLAG_TIMED_ROWS (version 7): some clip is timed (CBPAL_CLIP_TIMED), with a timed clip table
 * (header offset 208, 16 bytes a clip): its rows lie on cells of a grid and map rows just before
 * its first row say which two rows each cell blends (pal-format.md "Timed rows"). */
enum { CBPAL_FLAG_ZSTD = 1u, CBPAL_FLAG_IN_PLACE = 2u, CBPAL_FLAG_POSITIONS_RELATIVE = 4u, CBPAL_FLAG_FITTED_ROWS = 8u,
       CBPAL_FLAG_ROW_TRAVEL = 16u, CBPAL_FLAG_LOCAL_ROWS = 32u, CBPAL_FLAG_TIMED_ROWS = 64u };
#define CBPAL_RANGE_SIZE 32 /* a bone range table entry */
#define CBPAL_TIMED_SIZE 16 /* a timed clip table entry: u32 cells, f32 cell_rate, u32 map_rows, u32 reserved */
/* CBPAL_CLIP_STEP (version 4): the clip's rows are held, not blended - at clip time t the runtime
 * shows row floor(t * fps) alone (a STEP-keyed clip, baked at its key times: exact). */
/* CBPAL_CLIP_TIMED (version 7): the clip's rows are timed (cbpal_clip.cells, cell_rate, map_rows);
 * cbpal_bone_matrix and cbpal_travel_offset follow its map. */
enum { CBPAL_CLIP_LOOPS = 1u, CBPAL_CLIP_FITTED = 2u, CBPAL_CLIP_STEP = 4u, CBPAL_CLIP_TIMED = 8u };
/* cbpal_open flags */
enum { CBPAL_VERIFY_CHECKSUM = 1u };

typedef struct cbpal_header {
    uint32_t version, flags, header_size;
    uint32_t layout, precision, texels_per_bone, bone_count, row_texels;
    uint32_t rows, width, height, blocks, texel_bytes, clip_count;
    float fps, speed_reference, linear_range, bounds_min[3], bounds_max[3], max_error, model_height;
    float visible_error; /* max_error is at the baked rows; this includes blending two rows (0: not recorded) */
    uint64_t input_hash, clip_table_offset, bone_table_offset, strings_offset, strings_size;
    uint64_t payload_offset, payload_size, payload_raw_size, checksum;
    uint64_t offset_table_offset; /* version 3 with relative positions: bone_count x 3 f32 position offsets */
    uint64_t travel_table_offset; /* version 5 with CBPAL_FLAG_ROW_TRAVEL: rows x f32 travel offsets; else 0 */
    uint64_t range_table_offset;  /* version 6 with CBPAL_FLAG_LOCAL_ROWS: bone_count x 32-byte bone ranges; else 0 */
    uint64_t timed_table_offset;  /* version 7 with CBPAL_FLAG_TIMED_ROWS: clip_count x 16-byte timed entries; else 0 */
} cbpal_header;

typedef struct cbpal_clip {
    const char *name; /* NUL-terminated, inside the file */
    uint32_t first_row, frames, flags;
    float fps, duration, start, root_velocity[3], bounds_min[3], bounds_max[3];
    float travel_heading[3]; /* version 5: the direction its rows' travel offsets lie along (0 where it has none) */
    /* version 7, CBPAL_CLIP_TIMED (else 0): the grid's steps over the clip, cells per second of clip
     * time, and the map's rows (ceil(cells / row_texels), just before first_row). frames counts
     * its rows, not the map's. Its instance numbers: (first_row, +-cells, -cell_rate x rate, phase). */
    uint32_t cells, map_rows;
    float cell_rate;
} cbpal_clip;

typedef struct cbpal_bone {
    const char *name;
    int32_t parent;           /* the nearest ancestor bone, -1 for a root (local rows compose onto it) */
    float bind_position[3];
    float position_offset[3]; /* with CBPAL_FLAG_POSITIONS_RELATIVE: added to the position texel; else 0 */
    float pos_min[3], pos_max[3], scale_max; /* CBPAL_FLAG_LOCAL_ROWS: its range table entry (u16 decodes with it); else 0 */
} cbpal_bone;

typedef struct cbpal_file {
    cbpal_header header;
    const unsigned char *data; /* the whole file */
    size_t size;
    const void *texels;        /* width * height * texel_bytes */
    size_t texels_size;
    void *owned_;              /* read() fallback buffer or decompressed texels */
    void *map_;
    size_t map_size_;
} cbpal_file;

/* 0 on success; otherwise non-zero and a one-line message in err. */
int cbpal_open(const char *path, unsigned flags, cbpal_file *out, char *err, size_t err_size);
/* Same over bytes the caller keeps alive. */
int cbpal_open_memory(const void *data, size_t size, unsigned flags, cbpal_file *out, char *err, size_t err_size);
void cbpal_close(cbpal_file *file);
int cbpal_get_clip(const cbpal_file *file, uint32_t index, cbpal_clip *out);
int cbpal_get_bone(const cbpal_file *file, uint32_t index, cbpal_bone *out);
/* Texel coordinates of a bone's first texel in a baked row (rows wrap into column blocks). */
void cbpal_texel_xy(const cbpal_header *h, uint32_t row, uint32_t bone, uint32_t *x, uint32_t *y);
/* Cell `cell` of a timed clip's map: the rows it blends relative to first_row (r0, r1) and the
 * weights at the cell's start and end (f0, f1). Non-zero for an untimed clip or a cell >= cells. */
int cbpal_timed_map(const cbpal_file *file, uint32_t clip, uint32_t cell, float out[4]);
/* The two rows a clip shows `time` seconds into it and the weight of the second, as every runtime
 * picks them (loops wrap, one-shots clamp; held rows not blended; a timed clip through its map).
 * Non-zero for a clip that does not exist or a time that is not finite. */
int cbpal_clip_frame(const cbpal_file *file, uint32_t clip, double time, uint32_t *row0, uint32_t *row1, float *fr);
/* The bone's skinning matrix (column-major 4x4: the glTF joint matrix, bind space to the posed
 * model) `time` seconds into the clip (loops wrap, one-shots clamp), the two rows blended as the
 * shipped GLSL blends them (a CBPAL_CLIP_STEP clip's row held, not blended). Attach a prop by composing it with the prop's bind-space transform.
 * Non-zero for a clip or bone that does not exist or a time that is not finite. Uses <math.h>. */
int cbpal_bone_matrix(const cbpal_file *file, uint32_t clip, double time, uint32_t bone, float out[16]);
/* A row's travel offset along its clip's heading, model units (0 in files without the table). */
float cbpal_row_travel(const cbpal_file *file, uint32_t row);
/* The body's travel offset `time` seconds into the clip, model units in the model's frame: the
 * rows' offsets blended as the shaders blend the rows, times the clip's heading. An instance
 * moving at the clip's ground speed is drawn at its position plus this (rotated and scaled as
 * the instance), and its planted feet stay still. Zero for clips and files without it. Non-zero
 * return for a clip that does not exist or a time that is not finite. */
int cbpal_travel_offset(const cbpal_file *file, uint32_t clip, double time, float out[3]);

/* XXH64 (seed 0), streaming: the checksum and input-hash function of the format. */
typedef struct cbpal_xxh64 {
    uint64_t v[4], total;
    unsigned char buf[32];
    size_t buffered;
} cbpal_xxh64_state;
void cbpal_xxh64_init(cbpal_xxh64_state *s);
void cbpal_xxh64_update(cbpal_xxh64_state *s, const void *data, size_t size);
uint64_t cbpal_xxh64_digest(const cbpal_xxh64_state *s);
uint64_t cbpal_xxh64(const void *data, size_t size);

#ifdef __cplusplus
}
#endif
#endif /* CROWDBAKE_PAL_H */

#ifdef CROWDBAKE_PAL_IMPLEMENTATION
#ifndef CROWDBAKE_PAL_IMPLEMENTED
#define CROWDBAKE_PAL_IMPLEMENTED

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#define CBPAL_HAVE_MMAP 1
#endif
#ifdef CBPAL_WITH_ZSTD
#include <zstd.h>
#endif

/* ---- XXH64, from the algorithm's specification ---- */

#define CBPAL_P1 0x9E3779B185EBCA87ull
#define CBPAL_P2 0xC2B2AE3D27D4EB4Full
#define CBPAL_P3 0x165667B19E3779F9ull
#define CBPAL_P4 0x85EBCA77C2B2AE63ull
#define CBPAL_P5 0x27D4EB2F165667C5ull

static uint64_t cbpal__rotl(uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }
static uint64_t cbpal__u64(const unsigned char *p)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    uint64_t v; /* one unaligned load on little-endian hosts */
    memcpy(&v, p, 8);
    return v;
#else
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
#endif
}
static uint32_t cbpal__u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static float cbpal__f32(const unsigned char *p)
{
    uint32_t v = cbpal__u32(p);
    float f;
    memcpy(&f, &v, 4);
    return f;
}
static uint64_t cbpal__round(uint64_t acc, uint64_t input)
{
    acc += input * CBPAL_P2;
    return cbpal__rotl(acc, 31) * CBPAL_P1;
}
static uint64_t cbpal__merge(uint64_t acc, uint64_t v)
{
    acc ^= cbpal__round(0, v);
    return acc * CBPAL_P1 + CBPAL_P4;
}

void cbpal_xxh64_init(cbpal_xxh64_state *s)
{
    memset(s, 0, sizeof *s);
    s->v[0] = CBPAL_P1 + CBPAL_P2;
    s->v[1] = CBPAL_P2;
    s->v[2] = 0;
    s->v[3] = (uint64_t)0 - CBPAL_P1;
}

/* Asks for the bytes 2 KB ahead while a stripe is hashed: a large palette or model file is read
 * from memory, not cache, and the hardware's prefetcher alone leaves the hash waiting on it (29 MB
 * hashed in 4.4 ms without, 3.2 ms with, on an EPYC VM). A hint: it never faults, past the end
 * either (an address computed as an integer, not a pointer past the buffer), and does not change
 * a bit of the hash. */
#if defined(__GNUC__) || defined(__clang__)
#define CBPAL__PREFETCH(p, ahead) __builtin_prefetch((const void *)((uintptr_t)(p) + (ahead)))
#else
#define CBPAL__PREFETCH(p, ahead) ((void)0)
#endif

static void cbpal__stripe(uint64_t v[4], const unsigned char *p)
{
    v[0] = cbpal__round(v[0], cbpal__u64(p));
    v[1] = cbpal__round(v[1], cbpal__u64(p + 8));
    v[2] = cbpal__round(v[2], cbpal__u64(p + 16));
    v[3] = cbpal__round(v[3], cbpal__u64(p + 24));
}

void cbpal_xxh64_update(cbpal_xxh64_state *s, const void *data, size_t size)
{
    const unsigned char *p = (const unsigned char *)data;
    s->total += size;
    if (s->buffered) {
        size_t take = 32 - s->buffered < size ? 32 - s->buffered : size;
        memcpy(s->buf + s->buffered, p, take);
        s->buffered += take, p += take, size -= take;
        if (s->buffered < 32) return;
        cbpal__stripe(s->v, s->buf);
        s->buffered = 0;
    }
    uint64_t v[4] = {s->v[0], s->v[1], s->v[2], s->v[3]};
    for (; size >= 32; p += 32, size -= 32) {
        CBPAL__PREFETCH(p, 2048);
        cbpal__stripe(v, p);
    }
    memcpy(s->v, v, sizeof v);
    memcpy(s->buf, p, size);
    s->buffered = size;
}

uint64_t cbpal_xxh64_digest(const cbpal_xxh64_state *s)
{
    uint64_t h;
    if (s->total >= 32) {
        h = cbpal__rotl(s->v[0], 1) + cbpal__rotl(s->v[1], 7) + cbpal__rotl(s->v[2], 12) + cbpal__rotl(s->v[3], 18);
        for (int i = 0; i < 4; ++i) h = cbpal__merge(h, s->v[i]);
    } else {
        h = CBPAL_P5;
    }
    h += s->total;
    const unsigned char *p = s->buf;
    size_t n = s->buffered;
    for (; n >= 8; p += 8, n -= 8) h = cbpal__rotl(h ^ cbpal__round(0, cbpal__u64(p)), 27) * CBPAL_P1 + CBPAL_P4;
    if (n >= 4) h = cbpal__rotl(h ^ ((uint64_t)cbpal__u32(p) * CBPAL_P1), 23) * CBPAL_P2 + CBPAL_P3, p += 4, n -= 4;
    for (; n; ++p, --n) h = cbpal__rotl(h ^ (*p * CBPAL_P5), 11) * CBPAL_P1;
    h ^= h >> 33, h *= CBPAL_P2, h ^= h >> 29, h *= CBPAL_P3, h ^= h >> 32;
    return h;
}

uint64_t cbpal_xxh64(const void *data, size_t size)
{
    cbpal_xxh64_state s;
    cbpal_xxh64_init(&s);
    cbpal_xxh64_update(&s, data, size);
    return cbpal_xxh64_digest(&s);
}

/* ---- validation ---- */

static int cbpal__fail(char *err, size_t err_size, const char *fmt, ...)
{
    if (err && err_size) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, err_size, fmt, ap);
        va_end(ap);
    }
    return -1;
}

/* begin + count * size <= limit, without overflow. */
static int cbpal__fits(uint64_t begin, uint64_t count, uint64_t size, uint64_t limit)
{
    if (begin > limit) return 0;
    if (size && count > (limit - begin) / size) return 0;
    return 1;
}

static void cbpal__parse_header(const unsigned char *d, cbpal_header *h)
{
    uint32_t *u[] = {&h->version, &h->flags, &h->header_size, &h->layout, &h->precision, &h->texels_per_bone,
                     &h->bone_count, &h->row_texels, &h->rows, &h->width, &h->height, &h->blocks, &h->texel_bytes,
                     &h->clip_count};
    for (int i = 0; i < 14; ++i) *u[i] = cbpal__u32(d + 8 + 4 * i);
    h->fps = cbpal__f32(d + 64);
    h->speed_reference = cbpal__f32(d + 68);
    h->linear_range = cbpal__f32(d + 72);
    for (int k = 0; k < 3; ++k) h->bounds_min[k] = cbpal__f32(d + 76 + 4 * k), h->bounds_max[k] = cbpal__f32(d + 88 + 4 * k);
    h->max_error = cbpal__f32(d + 100);
    h->model_height = cbpal__f32(d + 104);
    h->visible_error = cbpal__f32(d + 108);
    uint64_t *w[] = {&h->input_hash, &h->clip_table_offset, &h->bone_table_offset, &h->strings_offset, &h->strings_size,
                     &h->payload_offset, &h->payload_size, &h->payload_raw_size, &h->checksum};
    for (int i = 0; i < 9; ++i) *w[i] = cbpal__u64(d + 112 + 8 * i);
    h->offset_table_offset = h->version >= 3 ? cbpal__u64(d + 184) : 0;
    h->travel_table_offset = h->version >= 5 && (h->flags & CBPAL_FLAG_ROW_TRAVEL) ? cbpal__u64(d + 192) : 0;
    h->range_table_offset = h->version >= 6 && (h->flags & CBPAL_FLAG_LOCAL_ROWS) ? cbpal__u64(d + 200) : 0;
    h->timed_table_offset = h->version >= 7 && (h->flags & CBPAL_FLAG_TIMED_ROWS) ? cbpal__u64(d + 208) : 0;
}

static int cbpal__check_string(const cbpal_header *h, const unsigned char *d, uint32_t off, uint32_t len)
{
    return (uint64_t)off + len < h->strings_size && d[h->strings_offset + off + len] == 0;
}

/* Local rows (flag bit 5): version 6, qpos with u16 or float, no relative positions, and a bone
 * range table inside the file whose every entry is finite, min <= max, scale_max > 0, reserved 0. */
static int cbpal__validate_local(const unsigned char *d, size_t size, const cbpal_header *h, char *err, size_t es)
{
    if (!(h->flags & CBPAL_FLAG_LOCAL_ROWS)) return 0;
    if (h->version < 6) return cbpal__fail(err, es, "flag bit 5 (local rows) in a version %u file; local rows are v6", h->version);
    if (h->layout != CBPAL_LAYOUT_QPOS || h->precision == CBPAL_PRECISION_HALF || (h->flags & CBPAL_FLAG_POSITIONS_RELATIVE))
        return cbpal__fail(err, es, "local rows need qpos and u16 or float (layout %u, precision %u, flags 0x%x)", h->layout,
                           h->precision, h->flags);
    uint64_t at = h->range_table_offset;
    if (!cbpal__fits(at, h->bone_count, CBPAL_RANGE_SIZE, size) || at < CBPAL_HEADER_SIZE || at % 4)
        return cbpal__fail(err, es, "bone range table (offset %llu, %u bones) lies outside the file", (unsigned long long)at,
                           h->bone_count);
    for (uint32_t i = 0; i < h->bone_count; ++i, at += CBPAL_RANGE_SIZE) {
        int ok = cbpal__u32(d + at + 28) == 0 && cbpal__f32(d + at + 12) > 0;
        for (int k = 0; k < 7; ++k) /* finite, and pos_min <= pos_max */
            ok = ok && isfinite(cbpal__f32(d + at + 4 * k)) && (k > 2 || cbpal__f32(d + at + 4 * k) <= cbpal__f32(d + at + 16 + 4 * k));
        if (!ok) return cbpal__fail(err, es, "bone %u's range (at %llu): not finite, min > max, scale_max <= 0 or reserved not 0",
                                    i, (unsigned long long)at);
    }
    return 0;
}

/* Timed rows (flag bit 6): version 7 and a timed clip table inside the file. */
static int cbpal__validate_timed_table(size_t size, const cbpal_header *h, char *err, size_t es)
{
    if (!(h->flags & CBPAL_FLAG_TIMED_ROWS)) return 0;
    if (h->version < 7) return cbpal__fail(err, es, "flag bit 6 (timed rows) in a version %u file; timed rows are v7", h->version);
    uint64_t at = h->timed_table_offset;
    if (!cbpal__fits(at, h->clip_count, CBPAL_TIMED_SIZE, size) || at < CBPAL_HEADER_SIZE || at % 4)
        return cbpal__fail(err, es, "timed clip table (offset %llu, %u clips) lies outside the file; the file is truncated "
                           "or corrupt: re-bake it", (unsigned long long)at, h->clip_count);
    return 0;
}

/* Every clip: clip flag bit 3 if and only if a timed table entry is nonzero; a timed one's cells
 * >= 1, cell_rate > 0 and finite, map_rows = ceil(cells / row_texels) <= first_row, reserved 0.
 * Its map's texels are checked once the texels are at hand (cbpal__validate_maps). Called after
 * the table's place and the clips' names were checked. */
static int cbpal__validate_timed(const unsigned char *d, const cbpal_header *h, char *err, size_t es)
{
    for (uint32_t i = 0; !(h->flags & CBPAL_FLAG_TIMED_ROWS) && i < h->clip_count; ++i) {
        const unsigned char *c = d + h->clip_table_offset + (uint64_t)i * CBPAL_CLIP_SIZE;
        if (cbpal__u32(c + 28) & CBPAL_CLIP_TIMED)
            return cbpal__fail(err, es, "clip %u (%s) is marked timed (clip flag bit 3) in a file without timed rows "
                               "(header flag bit 6); the file is corrupt: re-bake it", i, (const char *)d + h->strings_offset + cbpal__u32(c));
    }
    if (!(h->flags & CBPAL_FLAG_TIMED_ROWS)) return 0;
    uint64_t at = h->timed_table_offset;
    for (uint32_t i = 0; i < h->clip_count; ++i, at += CBPAL_TIMED_SIZE) {
        const unsigned char *c = d + h->clip_table_offset + (uint64_t)i * CBPAL_CLIP_SIZE, *e = d + at;
        const char *name = (const char *)d + h->strings_offset + cbpal__u32(c);
        uint32_t cells = cbpal__u32(e), map_rows = cbpal__u32(e + 8), first = cbpal__u32(c + 8);
        float rate = cbpal__f32(e + 4);
        int timed = (cbpal__u32(c + 28) & CBPAL_CLIP_TIMED) != 0;
        int entry = cells || cbpal__u32(e + 4) || map_rows || cbpal__u32(e + 12);
        uint64_t want = ((uint64_t)cells + h->row_texels - 1) / h->row_texels;
        if (timed != entry)
            return cbpal__fail(err, es, "clip %u (%s): clip flag bit 3 (timed) is %s but its timed table entry is %s; the file "
                               "is corrupt: re-bake it", i, name, timed ? "set" : "clear", entry ? "not 0" : "0");
        if (timed && (cells == 0 || !(rate > 0) || !isfinite(rate) || cbpal__u32(e + 12) != 0 || map_rows != want ||
                      map_rows > first))
            return cbpal__fail(err, es, "clip %u (%s): bad timed entry (cells %u, cell_rate %g, map_rows %u for ceil(cells / "
                               "%u) = %llu, first row %u); the file is corrupt: re-bake it", i, name, cells, (double)rate,
                               map_rows, h->row_texels, (unsigned long long)want, first);
    }
    return 0;
}

/* 1 + a bone on a cycle of parents, or 0: each chain walked at most bone_count steps. */
static uint32_t cbpal__parent_cycle(const unsigned char *d, const cbpal_header *h)
{
    for (uint32_t i = 0; i < h->bone_count; ++i)
        for (uint32_t a = i, steps = 0; a != 0xffffffffu; a = cbpal__u32(d + h->bone_table_offset + (uint64_t)a * CBPAL_BONE_SIZE + 8))
            if (steps++ > h->bone_count) return i + 1;
    return 0;
}

static int cbpal__validate(const unsigned char *d, size_t size, cbpal_header *h, char *err, size_t es)
{
    static const unsigned char magic[8] = {'C', 'B', 'P', 'A', 'L', '\r', '\n', 0x1a};
    if (size < 8 || memcmp(d, magic, 8) != 0) return cbpal__fail(err, es, "not a crowdbake palette (wrong magic)");
    if (size < 12) return cbpal__fail(err, es, "truncated: %zu bytes, shorter than the header", size);
    uint32_t version = cbpal__u32(d + 8);
    if (version > CBPAL_VERSION)
        return cbpal__fail(err, es, "palette format version %u is newer than this reader (version %u); update the reader",
                           version, CBPAL_VERSION);
    if (version < 1) return cbpal__fail(err, es, "unknown palette format version %u", version);
    if (size < CBPAL_HEADER_SIZE) return cbpal__fail(err, es, "truncated: %zu bytes, shorter than the header", size);
    cbpal__parse_header(d, h);
    if (h->header_size != CBPAL_HEADER_SIZE) return cbpal__fail(err, es, "bad header size %u", h->header_size);
    if (h->layout > 2 || h->precision > 2) return cbpal__fail(err, es, "unknown layout %u or precision %u", h->layout, h->precision);
    static const uint32_t tpb[3] = {4, 3, 2}, tbytes[3] = {16, 8, 8};
    if (h->texels_per_bone != tpb[h->layout] || h->texel_bytes != tbytes[h->precision])
        return cbpal__fail(err, es, "texels per bone or bytes per texel do not match the layout and precision");
    if (h->bone_count == 0 || (uint64_t)h->bone_count * h->texels_per_bone != h->row_texels || h->blocks == 0 ||
        (uint64_t)h->blocks * h->row_texels != h->width || h->height == 0 || (uint64_t)h->height * h->blocks < h->rows ||
        (uint64_t)(h->blocks - 1) * h->height >= h->rows || (uint64_t)h->width * h->height * h->texel_bytes != h->payload_raw_size)
        return cbpal__fail(err, es, "inconsistent texture geometry (%u bones, %u rows, %ux%u in %u blocks)", h->bone_count,
                           h->rows, h->width, h->height, h->blocks);
    if (!cbpal__fits(h->clip_table_offset, h->clip_count, CBPAL_CLIP_SIZE, size) || h->clip_table_offset < CBPAL_HEADER_SIZE)
        return cbpal__fail(err, es, "clip table (offset %llu, %u clips) lies outside the file",
                           (unsigned long long)h->clip_table_offset, h->clip_count);
    if (!cbpal__fits(h->bone_table_offset, h->bone_count, CBPAL_BONE_SIZE, size) || h->bone_table_offset < CBPAL_HEADER_SIZE)
        return cbpal__fail(err, es, "bone table (offset %llu, %u bones) lies outside the file",
                           (unsigned long long)h->bone_table_offset, h->bone_count);
    if (h->version >= 3 && (h->flags & CBPAL_FLAG_POSITIONS_RELATIVE) &&
        (!cbpal__fits(h->offset_table_offset, h->bone_count, 12, size) || h->offset_table_offset < CBPAL_HEADER_SIZE))
        return cbpal__fail(err, es, "position offset table (offset %llu, %u bones) lies outside the file",
                           (unsigned long long)h->offset_table_offset, h->bone_count);
    if (h->version >= 5 && (h->flags & CBPAL_FLAG_ROW_TRAVEL) &&
        (!cbpal__fits(h->travel_table_offset, h->rows, 4, size) || h->travel_table_offset < CBPAL_HEADER_SIZE))
        return cbpal__fail(err, es, "travel offset table (offset %llu, %u rows) lies outside the file",
                           (unsigned long long)h->travel_table_offset, h->rows);
    if (cbpal__validate_local(d, size, h, err, es) || cbpal__validate_timed_table(size, h, err, es)) return -1;
    if (!cbpal__fits(h->strings_offset, h->strings_size, 1, size) || h->strings_offset < CBPAL_HEADER_SIZE)
        return cbpal__fail(err, es, "string table lies outside the file");
    if (h->payload_offset % CBPAL_PAYLOAD_ALIGN || !cbpal__fits(h->payload_offset, h->payload_size, 1, size) ||
        h->payload_offset < CBPAL_HEADER_SIZE)
        return cbpal__fail(err, es, "truncated or bad payload: offset %llu + %llu bytes, file has %zu",
                           (unsigned long long)h->payload_offset, (unsigned long long)h->payload_size, size);
    if (!(h->flags & CBPAL_FLAG_ZSTD) && h->payload_size != h->payload_raw_size)
        return cbpal__fail(err, es, "payload is %llu bytes, the texture needs %llu", (unsigned long long)h->payload_size,
                           (unsigned long long)h->payload_raw_size);
    for (uint32_t i = 0; i < h->clip_count; ++i) {
        const unsigned char *c = d + h->clip_table_offset + (uint64_t)i * CBPAL_CLIP_SIZE;
        uint32_t first = cbpal__u32(c + 8), frames = cbpal__u32(c + 12);
        if (!cbpal__check_string(h, d, cbpal__u32(c), cbpal__u32(c + 4)) || frames == 0 || first > h->rows ||
            frames > h->rows - first)
            return cbpal__fail(err, es, "clip %u has a bad name or rows %u..%u outside the %u rows", i, first,
                               first + frames, h->rows);
    }
    for (uint32_t i = 0; i < h->bone_count; ++i) {
        const unsigned char *b = d + h->bone_table_offset + (uint64_t)i * CBPAL_BONE_SIZE;
        int32_t parent = (int32_t)cbpal__u32(b + 8);
        if (!cbpal__check_string(h, d, cbpal__u32(b), cbpal__u32(b + 4)) || parent < -1 || parent >= (int32_t)h->bone_count)
            return cbpal__fail(err, es, "bone %u has a bad name or parent", i);
    }
    if (cbpal__validate_timed(d, h, err, es)) return -1;
    if ((h->flags & CBPAL_FLAG_LOCAL_ROWS) && cbpal__parent_cycle(d, h))
        return cbpal__fail(err, es, "local rows: bone %u is its own ancestor (the bone table's parents form a cycle)",
                           cbpal__parent_cycle(d, h) - 1);
    return 0;
}

static uint64_t cbpal__checksum(const unsigned char *d, uint64_t end)
{
    static const unsigned char zero[8] = {0};
    cbpal_xxh64_state s;
    cbpal_xxh64_init(&s);
    cbpal_xxh64_update(&s, d, CBPAL_CHECKSUM_OFFSET);
    cbpal_xxh64_update(&s, zero, 8);
    cbpal_xxh64_update(&s, d + CBPAL_CHECKSUM_OFFSET + 8, (size_t)(end - CBPAL_CHECKSUM_OFFSET - 8));
    return cbpal_xxh64_digest(&s);
}

static float cbpal__half(uint16_t h); /* crowdbake_pal_runtime.h */

/* Texel `cell` of a timed clip's map (rows first_row - map_rows on), decoded: (r0, r1, f0, f1). */
static void cbpal__map_texel(const cbpal_file *f, uint32_t first_row, uint32_t map_rows, uint32_t cell, float v[4])
{
    const cbpal_header *h = &f->header;
    uint32_t x, y, k = cell % h->row_texels;
    cbpal_texel_xy(h, first_row - map_rows + cell / h->row_texels, 0, &x, &y);
    const unsigned char *t = (const unsigned char *)f->texels + ((size_t)y * h->width + x + k) * h->texel_bytes;
    for (int i = 0; i < 4; ++i) {
        uint16_t u = (uint16_t)(t[2 * i] | t[2 * i + 1] << 8);
        if (h->precision == CBPAL_PRECISION_FLOAT) v[i] = cbpal__f32(t + 4 * i);
        else v[i] = h->precision == CBPAL_PRECISION_HALF ? cbpal__half(u) : i < 2 ? (float)u : (float)u / 65535.0f;
    }
}

/* Every timed clip's map: each cell's rows whole numbers below the clip's frames, its weights
 * within [0, 1] with f0 <= f1. Needs the texels (decompressed). */
static int cbpal__validate_maps(const cbpal_file *f, char *err, size_t es)
{
    for (uint32_t i = 0; f->header.timed_table_offset && i < f->header.clip_count; ++i) {
        cbpal_clip c;
        cbpal_get_clip(f, i, &c);
        for (uint32_t cell = 0; c.cells && cell < c.cells; ++cell) {
            float v[4];
            cbpal__map_texel(f, c.first_row, c.map_rows, cell, v);
            int ok = v[0] >= 0 && v[0] < (float)c.frames && v[0] == floorf(v[0]) && v[1] >= 0 && v[1] < (float)c.frames &&
                     v[1] == floorf(v[1]) && v[2] >= 0 && v[2] <= v[3] && v[3] <= 1;
            if (!ok)
                return cbpal__fail(err, es, "clip %u (%s): its map's cell %u reads rows %g, %g and weights %g, %g (rows must be "
                                   "whole and below its %u frames, weights 0 <= f0 <= f1 <= 1); the file is corrupt: re-bake it",
                                   i, c.name, cell, (double)v[0], (double)v[1], (double)v[2], (double)v[3], c.frames);
        }
    }
    return 0;
}

static int cbpal__attach(cbpal_file *f, unsigned flags, char *err, size_t es)
{
    cbpal_header *h = &f->header;
    if (cbpal__validate(f->data, f->size, h, err, es)) return -1;
    if ((flags & CBPAL_VERIFY_CHECKSUM) && cbpal__checksum(f->data, h->payload_offset + h->payload_size) != h->checksum)
        return cbpal__fail(err, es, "checksum mismatch: the file is corrupted");
    const unsigned char *payload = f->data + h->payload_offset;
    f->texels_size = (size_t)h->payload_raw_size;
    if (!(h->flags & CBPAL_FLAG_ZSTD)) {
        f->texels = payload;
        return cbpal__validate_maps(f, err, es);
    }
#ifdef CBPAL_WITH_ZSTD
    void *out = malloc(f->texels_size ? f->texels_size : 1);
    if (!out) return cbpal__fail(err, es, "out of memory for %zu decompressed bytes", f->texels_size);
    size_t got = ZSTD_decompress(out, f->texels_size, payload, (size_t)h->payload_size);
    if (ZSTD_isError(got) || got != f->texels_size) {
        free(out);
        return cbpal__fail(err, es, "compressed payload does not decompress to %zu bytes", f->texels_size);
    }
    f->owned_ = out; /* replaces nothing: read() buffers are freed through map_ below */
    f->texels = out;
    return cbpal__validate_maps(f, err, es);
#else
    return cbpal__fail(err, es, "payload is zstd-compressed; build the reader with CBPAL_WITH_ZSTD and -lzstd");
#endif
}

int cbpal_open_memory(const void *data, size_t size, unsigned flags, cbpal_file *out, char *err, size_t err_size)
{
    memset(out, 0, sizeof *out);
    out->data = (const unsigned char *)data;
    out->size = size;
    if (cbpal__attach(out, flags, err, err_size)) {
        cbpal_close(out);
        return -1;
    }
    return 0;
}

int cbpal_open(const char *path, unsigned flags, cbpal_file *out, char *err, size_t err_size)
{
    memset(out, 0, sizeof *out);
#ifdef CBPAL_HAVE_MMAP
    int fd = open(path, O_RDONLY);
    if (fd < 0) return cbpal__fail(err, err_size, "%s: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return cbpal__fail(err, err_size, "%s: not a regular file", path);
    }
    size_t size = (size_t)st.st_size;
    void *map = size ? mmap(NULL, size, PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
    if (map != MAP_FAILED) {
        close(fd);
        out->map_ = map;
        out->map_size_ = size;
        out->data = (const unsigned char *)map;
        out->size = size;
    } else { /* read() fallback */
        unsigned char *buf = (unsigned char *)malloc(size ? size : 1);
        size_t got = 0;
        while (buf && got < size) {
            ssize_t n = read(fd, buf + got, size - got);
            if (n <= 0) break;
            got += (size_t)n;
        }
        close(fd);
        if (!buf || got != size) {
            free(buf);
            return cbpal__fail(err, err_size, "%s: read failed", path);
        }
        out->map_ = buf;
        out->data = buf;
        out->size = size;
    }
#else
    FILE *fp = fopen(path, "rb");
    if (!fp) return cbpal__fail(err, err_size, "%s: %s", path, strerror(errno));
    fseek(fp, 0, SEEK_END);
    long len = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    unsigned char *buf = (unsigned char *)malloc(len > 0 ? (size_t)len : 1);
    size_t size = buf && len > 0 ? fread(buf, 1, (size_t)len, fp) : 0;
    fclose(fp);
    out->map_ = buf;
    out->data = buf;
    out->size = size;
#endif
    char inner[256];
    if (cbpal__attach(out, flags, inner, sizeof inner)) {
        cbpal_close(out);
        return cbpal__fail(err, err_size, "%s: %s", path, inner);
    }
    return 0;
}

void cbpal_close(cbpal_file *f)
{
    free(f->owned_);
#ifdef CBPAL_HAVE_MMAP
    if (f->map_ && f->map_size_) munmap(f->map_, f->map_size_);
    else
#endif
        free(f->map_);
    memset(f, 0, sizeof *f);
}

int cbpal_get_clip(const cbpal_file *f, uint32_t i, cbpal_clip *out)
{
    if (i >= f->header.clip_count) return -1;
    const unsigned char *c = f->data + f->header.clip_table_offset + (uint64_t)i * CBPAL_CLIP_SIZE;
    out->name = (const char *)f->data + f->header.strings_offset + cbpal__u32(c);
    out->first_row = cbpal__u32(c + 8);
    out->frames = cbpal__u32(c + 12);
    out->fps = cbpal__f32(c + 16);
    out->duration = cbpal__f32(c + 20);
    out->start = cbpal__f32(c + 24);
    out->flags = cbpal__u32(c + 28) | (f->header.flags & CBPAL_FLAG_FITTED_ROWS ? (uint32_t)CBPAL_CLIP_FITTED : 0u);
    for (int k = 0; k < 3; ++k) {
        out->root_velocity[k] = cbpal__f32(c + 32 + 4 * k);
        out->bounds_min[k] = cbpal__f32(c + 44 + 4 * k);
        out->bounds_max[k] = cbpal__f32(c + 56 + 4 * k);
        out->travel_heading[k] = f->header.travel_table_offset ? cbpal__f32(c + 68 + 4 * k) : 0.0f;
    }
    const unsigned char *e = f->header.timed_table_offset ? f->data + f->header.timed_table_offset + (uint64_t)i * CBPAL_TIMED_SIZE : NULL;
    out->cells = e ? cbpal__u32(e) : 0;
    out->cell_rate = e ? cbpal__f32(e + 4) : 0.0f;
    out->map_rows = e ? cbpal__u32(e + 8) : 0;
    return 0;
}

int cbpal_get_bone(const cbpal_file *f, uint32_t i, cbpal_bone *out)
{
    if (i >= f->header.bone_count) return -1;
    const unsigned char *b = f->data + f->header.bone_table_offset + (uint64_t)i * CBPAL_BONE_SIZE;
    out->name = (const char *)f->data + f->header.strings_offset + cbpal__u32(b);
    out->parent = (int32_t)cbpal__u32(b + 8);
    const cbpal_header *h = &f->header;
    int relative = (h->flags & CBPAL_FLAG_POSITIONS_RELATIVE) != 0; /* else the offset table's offset is unchecked */
    const unsigned char *o = relative && h->version >= 3 ? f->data + h->offset_table_offset + (uint64_t)i * 12 : NULL;
    const unsigned char *e = h->range_table_offset ? f->data + h->range_table_offset + (uint64_t)i * CBPAL_RANGE_SIZE : NULL;
    for (int k = 0; k < 3; ++k) {
        out->bind_position[k] = cbpal__f32(b + 16 + 4 * k);
        out->position_offset[k] = !relative ? 0.0f : o ? cbpal__f32(o + 4 * k) : out->bind_position[k];
        out->pos_min[k] = e ? cbpal__f32(e + 4 * k) : 0.0f;
        out->pos_max[k] = e ? cbpal__f32(e + 16 + 4 * k) : 0.0f;
    }
    out->scale_max = e ? cbpal__f32(e + 12) : 0.0f;
    return 0;
}

void cbpal_texel_xy(const cbpal_header *h, uint32_t row, uint32_t bone, uint32_t *x, uint32_t *y)
{
    *x = (row / h->height) * h->row_texels + bone * h->texels_per_bone;
    *y = row % h->height;
}

/* A bone's matrix at a time, as the shipped shaders compute it: its own file. */
#include "crowdbake_pal_runtime.h"

#endif /* CROWDBAKE_PAL_IMPLEMENTED */
#endif /* CROWDBAKE_PAL_IMPLEMENTATION */
