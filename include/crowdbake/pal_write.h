/* pal_write.h - writes a cb_palette as a .pal file (docs/pal-format.md), atomically. */
#ifndef CB_PAL_WRITE_H
#define CB_PAL_WRITE_H

#include "export.h"

#include "atomic_file.h"
#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_pal_write_options {
    bool zstd;              /* compress the payload */
    int zstd_level;
    uint64_t input_hash;    /* of everything that produced the palette */
    float speed_reference;  /* model units/s at playback rate 1, or 0 */
    bool in_place;          /* root motion was removed */
} cb_pal_write_options;

CROWDBAKE_API cb_status cb_pal_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                     const cb_pal_write_options *opt, cb_error *err);

/* An uncompressed .pal written where it is baked: the bake's texels (cb_bake_options.texel_memory
 * = {cb_pal_map_texels, &mapping}) are the payload of the temporary file, mapped, so they are
 * never copied; cb_pal_write_mapped then adds the header and tables and renames it into place.
 * Where the file cannot be mapped, cb_pal_map_texels answers NULL, the bake allocates its own
 * texels, and cb_pal_write writes them as before. */
typedef struct cb_pal_mapping {
    const char *path;
    const cb_model *model;
    int32_t skin;
    cb_atomic_file file;
    bool open;
    unsigned char *base; /* the whole file */
    size_t meta_size;    /* the payload's offset */
} cb_pal_mapping;

CROWDBAKE_API void cb_pal_mapping_init(cb_pal_mapping *mapping, const char *path, const cb_model *model, int32_t skin);
CROWDBAKE_API void *cb_pal_map_texels(void *mapping, const cb_palette *p);
/* Whether p's texels are the mapping's payload. */
CROWDBAKE_API bool cb_pal_mapping_holds(const cb_pal_mapping *mapping, const cb_palette *p);
/* opt->zstd must be false. Releases the mapping, written or not. */
CROWDBAKE_API cb_status cb_pal_write_mapped(cb_pal_mapping *mapping, const cb_palette *p,
                                            const cb_pal_write_options *opt, cb_error *err);
/* Removes the temporary file, if any (after a failed bake; a no-op once written). */
CROWDBAKE_API void cb_pal_mapping_abort(cb_pal_mapping *mapping);

#ifdef __cplusplus
}
#endif

#endif
