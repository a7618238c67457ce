/* exr.h - palettes as OpenEXR images through OpenEXR's C API (OpenEXRCore): RGBA half or
 * float scanlines, width x height exactly as in the .pal, metadata as typed header
 * attributes prefixed "crowdbake.". */
#ifndef CB_EXR_IO_H
#define CB_EXR_IO_H

#include "export.h"

#include "palette.h"
#include "vat.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Lossless compressions only: the texels must read back bit-identical. */

CROWDBAKE_API cb_status cb_exr_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                     int compression, uint64_t input_hash, float speed_reference, cb_error *err);

/* A VAT: channels position.RGBA and normal.RGBA, half floats, one frame per row block. */
CROWDBAKE_API cb_status cb_exr_write_vat(const char *path, const cb_vat *vat, int compression, cb_error *err);

typedef struct cb_exr_image {
    uint32_t width, height;
    cb_precision precision;   /* half or float */
    void *texels;             /* RGBA interleaved, like the .pal payload; malloc'ed */
    size_t texel_bytes;
    char layout[16];
    int32_t bones, rows, blocks, rows_per_block, clips;
    uint64_t input_hash;
    float max_error, visible_error; /* the palette's encoding and visible errors (cb_palette), model units */
} cb_exr_image;

/* Reads the texels back through OpenEXR, and the main crowdbake attributes. */
CROWDBAKE_API cb_status cb_exr_read(const char *path, cb_exr_image *out, cb_error *err);
CROWDBAKE_API void cb_exr_image_free(cb_exr_image *img);

/* A palette EXR as a palette that decodes and skins like the .pal of the same bake: texels,
 * clip table (names included) and bind positions, all owned here. */
typedef struct cb_exr_palette {
    cb_palette palette;
    char *names; /* the clip names the palette points to */
} cb_exr_palette;

/* Fails, naming the file, when the crowdbake attributes are missing or disagree with the image. */
CROWDBAKE_API cb_status cb_exr_read_palette(const char *path, cb_exr_palette *out, cb_error *err);
CROWDBAKE_API void cb_exr_palette_free(cb_exr_palette *p);

#ifdef __cplusplus
}
#endif

#endif
