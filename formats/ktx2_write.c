/* ktx2_write.c - see include/crowdbake/ktx2.h. Written from the KTX 2.0 specification (file layout,
 * section 3) and the Khronos Data Format Specification (basic descriptor block). */
#include "crowdbake/ktx2.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "internal/atomic_file.h"
#include "internal/json.h"

enum { VK_FORMAT_R16G16B16A16_SFLOAT = 97, VK_FORMAT_R32G32B32A32_SFLOAT = 109 };

static void put32(unsigned char *d, uint32_t v)
{
    for (int i = 0; i < 4; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

static void put64(unsigned char *d, uint64_t v)
{
    for (int i = 0; i < 8; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

/* The data format descriptor: dfdTotalSize, then one basic block of 24 bytes and a sample per
 * channel (R, G, B, A), each a signed float of `bits` bits, as KTX-Software writes them. */
#define DFD_BYTES (4 + 24 + 4 * 16)
static void write_dfd(unsigned char *d, uint32_t bits, bool supercompressed)
{
    memset(d, 0, DFD_BYTES);
    put32(d, DFD_BYTES);
    put32(d + 4, 0);                                /* vendorId Khronos (0), descriptorType basic (0) */
    put32(d + 8, 2u | (uint32_t)(DFD_BYTES - 4) << 16); /* versionNumber 2, descriptorBlockSize */
    d[12] = 1;                                      /* colorModel KHR_DF_MODEL_RGBSDA */
    d[13] = 1;                                      /* colorPrimaries BT709 */
    d[14] = 1;                                      /* transferFunction LINEAR: the texels are numbers, not colours */
    d[15] = 0;                                      /* flags: alpha straight */
    /* texelBlockDimension0..3 = 0 (1x1x1x1), bytesPlane0 = the texel's bytes */
    d[20] = supercompressed ? 0 : (unsigned char)(bits / 2); /* the specification: 0 under supercompression */
    static const unsigned char channel[4] = {0, 1, 2, 15};
    for (int s = 0; s < 4; ++s) {
        unsigned char *w = d + 28 + 16 * s;
        uint32_t qualifiers = 0x80 | 0x40; /* KHR_DF_SAMPLE_DATATYPE_FLOAT | SIGNED */
        put32(w, (uint32_t)(s * bits) | (bits - 1) << 16 | (channel[s] | qualifiers) << 24);
        put32(w + 4, 0);          /* samplePosition */
        put32(w + 8, 0xBF800000); /* sampleLower: -1.0f */
        put32(w + 12, 0x3F800000); /* sampleUpper: 1.0f */
    }
}

/* crowdbake's tables as two JSON texts (malloc'ed, NUL-terminated). */
static char *clips_json(const cb_palette *p)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) return NULL;
    cb_json j;
    cb_json_init(&j, f);
    cb_json_array(&j, NULL);
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        cb_json_object(&j, NULL);
        cb_json_string(&j, "name", cl->name);
        cb_json_int(&j, "first_row", cl->first_row);
        cb_json_int(&j, "frames", cl->frames);
        cb_json_number(&j, "fps", cl->fps);
        cb_json_number(&j, "duration", cl->duration);
        cb_json_bool(&j, "loops", cl->loops);
        /* what `verify` needs to compare with the glTF, as the .pal's clip table holds it */
        cb_json_number(&j, "start", cl->start);
        cb_json_bool(&j, "fitted_rows", cl->fitted);
        if (cl->step) cb_json_bool(&j, "step_rows", true); /* held, not blended: the .pal's clip flag bit 2 */
        cb_json_inline_array(&j, "root_velocity");
        for (int k = 0; k < 3; ++k) cb_json_number(&j, NULL, cl->root_velocity[k]);
        cb_json_end(&j);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    return fclose(f) == 0 ? text : (free(text), NULL);
}

static char *palette_json(const cb_palette *p, const cb_model *m, int32_t skin, uint64_t hash, float speed, bool in_place)
{
    char *text = NULL, hex[17];
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) return NULL;
    cb_json j;
    cb_json_init(&j, f);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "layout", cb_layout_name(p->layout));
    cb_json_string(&j, "precision", cb_precision_name(p->precision));
    cb_json_int(&j, "bones", p->bone_count);
    cb_json_int(&j, "texels_per_bone", p->texels_per_bone);
    cb_json_int(&j, "row_texels", p->row_texels);
    cb_json_int(&j, "rows", p->rows);
    cb_json_int(&j, "blocks", p->blocks);
    cb_json_int(&j, "rows_per_block", p->height);
    cb_json_bool(&j, "positions_relative", p->positions_relative);
    cb_json_number(&j, "fps", p->fps);
    cb_json_string(&j, "root_motion", cb_root_motion_name(in_place ? CB_ROOT_MOTION_IN_PLACE : CB_ROOT_MOTION_KEEP));
    cb_json_bool(&j, "fitted_rows", p->fitted);
    cb_json_array(&j, "bone_names");
    for (uint32_t b = 0; b < p->bone_count; ++b) cb_json_string(&j, NULL, m->nodes[m->skins[skin].joints[b]].name);
    cb_json_end(&j);
    if (p->layout == CB_LAYOUT_QPOS || p->positions_relative) {
        cb_json_inline_array(&j, "bind_positions");
        for (uint32_t i = 0; i < p->bone_count * 3; ++i) cb_json_number(&j, NULL, p->bind_positions[i]);
        cb_json_end(&j);
    }
    if (p->positions_relative) { /* what the stored positions are relative to (docs/pal-format.md, version 3) */
        cb_json_inline_array(&j, "position_offsets");
        for (uint32_t i = 0; i < p->bone_count * 3; ++i) cb_json_number(&j, NULL, p->position_offsets[i]);
        cb_json_end(&j);
    }
    cb_json_number(&j, "model_height", p->model_height);
    cb_json_number(&j, "max_error", p->max_error);
    cb_json_number(&j, "visible_error", p->visible_error);
    cb_json_number(&j, "speed_reference", speed);
    snprintf(hex, sizeof hex, "%016llx", (unsigned long long)hash);
    cb_json_string(&j, "input_hash", hex);
    cb_json_end(&j);
    return fclose(f) == 0 ? text : (free(text), NULL);
}

/* One key/value entry: length, key NUL value NUL, padded to 4 bytes. Returns its size. */
static size_t kv_entry(unsigned char *d, const char *key, const char *value)
{
    size_t k = strlen(key) + 1, v = strlen(value) + 1, n = 4 + k + v, padded = (n + 3) / 4 * 4;
    if (d) {
        put32(d, (uint32_t)(k + v));
        memcpy(d + 4, key, k);
        memcpy(d + 4 + k, value, v);
        memset(d + n, 0, padded - n);
    }
    return padded;
}

/* The level as stored: the texels, or (zstd_level > 0) a Zstandard frame of them, as
 * `toktx --zcmp` writes them (supercompressionScheme 2). *level is the palette's own texels
 * (nothing to free) or a compressed copy (*owned). */
static cb_status stored_level(const cb_palette *p, int zstd_level, const void **level, size_t *bytes, void **owned,
                              cb_error *err)
{
    size_t raw = p->texel_bytes ? p->texel_bytes : 0;
    *level = p->texels, *bytes = raw, *owned = NULL;
    if (zstd_level <= 0) return CB_OK;
    size_t bound = ZSTD_compressBound(raw);
    if (!(*owned = malloc(bound ? bound : 1))) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    size_t n = ZSTD_compress(*owned, bound, p->texels, raw, zstd_level);
    if (ZSTD_isError(n)) return cb_fail(err, CB_ERR_INTERNAL, "zstd: %s", ZSTD_getErrorName(n));
    *level = *owned, *bytes = n;
    return CB_OK;
}

cb_status cb_ktx2_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin, uint64_t input_hash,
                        float speed_reference, bool in_place, cb_error *err)
{
    return cb_ktx2_write_zstd(path, p, model, skin, input_hash, speed_reference, in_place, 0, err);
}

cb_status cb_ktx2_write_zstd(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                             uint64_t input_hash, float speed_reference, bool in_place, int zstd_level, cb_error *err)
{
    if (p->precision == CB_PRECISION_U16)
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_PRECISION,
                               "%s: KTX2 palettes are RGBA16F or RGBA32F; a u16 palette would be RGBA16UI, which three.js's "
                               "KTX2Loader and most KTX2 loaders refuse: bake it with half or float precision", path);
    if (cb_palette_timed_clip(p))
        return cb_fail(err, CB_ERR_INPUT, "%s: clip %s has timed rows, and timed rows need a .pal (KTX2 has no place for "
                       "their map): write a .pal, or bake it at a fixed --fps", path, cb_palette_timed_clip(p)->name);
    uint32_t texel = cb_precision_texel_bytes(p->precision), bits = texel * 2;
    char *clips = clips_json(p), *meta = palette_json(p, model, skin, input_hash, speed_reference, in_place);
    if (!clips || !meta) {
        free(clips), free(meta);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    /* Keys sorted by their bytes, as the specification requires: 'K' sorts before 'c'. */
    const char *keys[3] = {"KTXwriter", "crowdbake.clips", "crowdbake.palette"};
    const char *values[3] = {"crowdbake " CROWDBAKE_VERSION, clips, meta};
    size_t kvd = 0;
    for (int i = 0; i < 3; ++i) kvd += kv_entry(NULL, keys[i], values[i]);
    size_t dfd_at = 80 + 24, kvd_at = dfd_at + DFD_BYTES, level_at = kvd_at + kvd;
    if (zstd_level <= 0) level_at = (level_at + texel - 1) / texel * texel; /* lcm(texel block size, 4); 1 supercompressed */
    /* Header, tables and padding here; the level is written from the palette's own texels. */
    size_t level_bytes = (size_t)p->width * p->height * texel, stored_bytes;
    const void *level;
    void *compressed = NULL;
    unsigned char *d = calloc(level_at, 1);
    if (!d || stored_level(p, zstd_level, &level, &stored_bytes, &compressed, err)) {
        free(clips), free(meta), free(d), free(compressed);
        return err->status ? err->status : cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    static const unsigned char id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    memcpy(d, id, 12);
    uint32_t header[9] = {p->precision == CB_PRECISION_FLOAT ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R16G16B16A16_SFLOAT,
                          texel / 4, p->width, p->height, 0 /* depth */, 0 /* layers */, 1 /* faces */, 1 /* levels */,
                          zstd_level > 0 ? 2u : 0u /* supercompressionScheme: Zstandard, or none */};
    for (int i = 0; i < 9; ++i) put32(d + 12 + 4 * i, header[i]);
    put32(d + 48, (uint32_t)dfd_at), put32(d + 52, DFD_BYTES);
    put32(d + 56, (uint32_t)kvd_at), put32(d + 60, (uint32_t)kvd);
    put64(d + 64, 0), put64(d + 72, 0); /* no supercompression global data */
    put64(d + 80, level_at), put64(d + 88, stored_bytes), put64(d + 96, level_bytes);
    write_dfd(d + dfd_at, bits, zstd_level > 0);
    size_t at = kvd_at;
    for (int i = 0; i < 3; ++i) at += kv_entry(d + at, keys[i], values[i]);
    free(clips), free(meta);
    cb_atomic_file f;
    cb_status rc = cb_atomic_open(&f, path, err);
    if (!rc && ((rc = cb_atomic_write(&f, d, level_at, err)) || (rc = cb_atomic_write(&f, level, stored_bytes, err))))
        cb_atomic_abort(&f);
    if (!rc) rc = cb_atomic_commit(&f, err);
    free(d), free(compressed);
    return rc;
}
