/* pal_mapping.h (internal) - a .pal baked straight into its own file's payload (the bake job's
 * memory saving, formats/pal_write.c): not exported, not installed. */
#ifndef CB_INTERNAL_PAL_MAPPING_H
#define CB_INTERNAL_PAL_MAPPING_H

#include "crowdbake/pal_write.h"
#include "internal/atomic_file.h"

#ifdef __cplusplus
extern "C" {
#endif

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

void cb_pal_mapping_init(cb_pal_mapping *mapping, const char *path, const cb_model *model, int32_t skin);
void *cb_pal_map_texels(void *mapping, const cb_palette *p);
/* Whether p's texels are the mapping's payload. */
bool cb_pal_mapping_holds(const cb_pal_mapping *mapping, const cb_palette *p);
/* opt->zstd must be false. Releases the mapping, written or not. */
cb_status cb_pal_write_mapped(cb_pal_mapping *mapping, const cb_palette *p,
                                            const cb_pal_write_options *opt, cb_error *err);
/* Removes the temporary file, if any (after a failed bake; a no-op once written). */
void cb_pal_mapping_abort(cb_pal_mapping *mapping);

#ifdef __cplusplus
}
#endif

#endif
