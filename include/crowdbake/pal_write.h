/* pal_write.h - writes a cb_palette as a .pal file (docs/pal-format.md), atomically. */
#ifndef CB_PAL_WRITE_H
#define CB_PAL_WRITE_H

#include "export.h"

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


#ifdef __cplusplus
}
#endif

#endif
