/* ktx2.h - a palette as an uncompressed KTX2 texture (Khronos KTX 2.0 specification):
 * one 2D level, VK_FORMAT_R16G16B16A16_SFLOAT (half) or VK_FORMAT_R32G32B32A32_SFLOAT (float),
 * the texels exactly as in the .pal payload (row 0 first, KTX2's default "rd" orientation), a
 * basic data format descriptor, and crowdbake's tables as key/value data:
 *   KTXwriter          "crowdbake VERSION"
 *   crowdbake.clips    JSON: [{name, first_row, frames, fps, duration, loops}, ...]
 *   crowdbake.palette  JSON: layout, precision, bones, texels_per_bone, row_texels, rows, blocks,
 *                      rows_per_block, positions_relative, bind_positions (qpos), model_height,
 *                      max_error, visible_error, speed_reference, input_hash
 * (values are UTF-8 text ending in NUL). u16 palettes (RGBA16UI) are refused: three.js's
 * KTX2Loader and most engines' KTX2 loaders take no integer formats. */
#ifndef CB_KTX2_WRITE_H
#define CB_KTX2_WRITE_H

#include "export.h"

#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

CROWDBAKE_API cb_status cb_ktx2_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                      uint64_t input_hash, float speed_reference, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
