/* ktx2.h - a palette as an uncompressed KTX2 texture (Khronos KTX 2.0 specification):
 * one 2D level, VK_FORMAT_R16G16B16A16_SFLOAT (half) or VK_FORMAT_R32G32B32A32_SFLOAT (float),
 * the texels exactly as in the .pal payload (row 0 first, KTX2's default "rd" orientation), a
 * basic data format descriptor, and crowdbake's tables as key/value data:
 *   KTXwriter          "crowdbake VERSION"
 *   crowdbake.clips    JSON: [{name, first_row, frames, fps, duration, loops, start, fitted_rows,
 *                      root_velocity}, ...]
 *   crowdbake.palette  JSON: layout, precision, bones, texels_per_bone, row_texels, rows, blocks,
 *                      rows_per_block, positions_relative, fps, root_motion, fitted_rows, bone_names,
 *                      bind_positions (qpos), position_offsets (relative), model_height, max_error,
 *                      visible_error, speed_reference, input_hash
 * (values are UTF-8 text ending in NUL). u16 palettes (RGBA16UI) are refused: three.js's
 * KTX2Loader and most engines' KTX2 loaders take no integer formats. */
#ifndef CB_KTX2_WRITE_H
#define CB_KTX2_WRITE_H

#include "export.h"

#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/* in_place: root motion was taken out of the rows (the clips' root_velocity says how much). */
CROWDBAKE_API cb_status cb_ktx2_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                      uint64_t input_hash, float speed_reference, bool in_place, cb_error *err);
/* The same with the level supercompressed by Zstandard at zstd_level (1..22; 0: none), as
 * `toktx --zcmp` writes it (supercompressionScheme 2): readers that take KTX2's zstd, such as
 * three.js's KTX2Loader and ktx-parse with a zstd decoder, get the same texels. */
CROWDBAKE_API cb_status cb_ktx2_write_zstd(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                           uint64_t input_hash, float speed_reference, bool in_place, int zstd_level,
                                           cb_error *err);

/* A KTX2 palette read back as a palette that decodes and skins like the .pal of the same bake:
 * texels, clip table (names included), bones and bind positions, all owned here. */
typedef struct cb_ktx2_palette {
    cb_palette palette;
    bool in_place;           /* root motion taken out of the rows */
    uint64_t input_hash;
    float speed_reference;
    const char **bone_names; /* palette.bone_count of them */
    char *strings;           /* the names point into it */
} cb_ktx2_palette;

/* Reads a KTX2 palette that cb_ktx2_write wrote: every size and offset is checked against the
 * file and against each other before anything is read through it. Fails naming the file and
 * what is wrong (not KTX2, not a crowdbake palette, truncated, tables that disagree). */
CROWDBAKE_API cb_status cb_ktx2_read_palette(const char *path, cb_ktx2_palette *out, cb_error *err);
CROWDBAKE_API void cb_ktx2_palette_free(cb_ktx2_palette *p);

#ifdef __cplusplus
}
#endif

#endif
