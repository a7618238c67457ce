/* budget.h - the arithmetic of GPU memory: texture geometry with wrapping, palette and
 * vertex-animation-texture (VAT) sizes, mesh buffers, and target profiles. docs/budget.md
 * gives every formula and the source of every profile. */
#ifndef CB_BUDGET_H
#define CB_BUDGET_H

#include "export.h"

#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_texture_geometry {
    uint32_t width, height, blocks; /* blocks of `height` rows side by side */
} cb_texture_geometry;

/* Lays `rows` rows of `row_texels` texels into a texture no dimension of which exceeds `max`:
 * blocks = ceil(rows / max), height = ceil(rows / blocks), width = blocks * row_texels.
 * False when even that does not fit. */
CROWDBAKE_API bool cb_wrap_rows(uint32_t row_texels, uint64_t rows, uint32_t max, cb_texture_geometry *out);

/* Texture bytes of a palette: wrapped geometry x texel bytes. 0 when it does not fit. */
CROWDBAKE_API uint64_t cb_palette_texture_bytes(uint32_t bones, uint32_t rows, cb_layout layout,
                                                cb_precision precision, uint32_t max, cb_texture_geometry *geometry);

/* A VAT stores every vertex of every frame. A frame of V vertices takes ceil(V / w) texture
 * rows of w = min(V, max) texels, then rows wrap like a palette's. Two textures (positions,
 * normals) of that geometry. */
typedef struct cb_vat_encoding {
    const char *name;
    uint32_t position_bytes, normal_bytes; /* per texel */
} cb_vat_encoding;

enum { CB_VAT_ENCODINGS = 3 };
CROWDBAKE_API extern const cb_vat_encoding cb_vat_encodings[CB_VAT_ENCODINGS];

/* Where both textures lie; false, with g empty, when no texture of max texels holds them. */
CROWDBAKE_API bool cb_vat_geometry(uint64_t vertices, uint32_t frames, uint32_t max, cb_texture_geometry *g);
/* Bytes of both textures laid out as g; when g is empty (they did not fit), the bytes the
 * frames would store unwrapped, so a report can still compare. */
CROWDBAKE_API uint64_t cb_vat_bytes(uint64_t vertices, uint32_t frames, const cb_vat_encoding *enc,
                                    const cb_texture_geometry *g);

typedef struct cb_target_profile {
    const char *name;
    uint64_t vram_bytes;
    uint32_t max_texture_size;
    const char *source;
} cb_target_profile;

/* A built-in profile by name (case-insensitive; '-' and '_' match a space), or NULL. */
CROWDBAKE_API const cb_target_profile *cb_find_profile(const char *name);
CROWDBAKE_API extern const cb_target_profile cb_profiles[];
CROWDBAKE_API extern const uint32_t cb_profile_count;

#ifdef __cplusplus
}
#endif

#endif
