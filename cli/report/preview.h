/* preview.h - a contact sheet of a palette: a row per clip, frames across, the model's mesh
 * skinned on OpenGL (Mesa's OSMesa, no GPU or display) by the shipped GLSL, shaded simply. */
#ifndef CB_PREVIEW_H
#define CB_PREVIEW_H

#include "crowdbake/palette.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_preview_options {
    uint32_t columns;   /* frames per clip */
    uint32_t cell;      /* pixels per frame, square */
    const char *title;  /* the header's first words (the files), or NULL */
} cb_preview_options;

/* The sheet, top to bottom: a header band (title, encoding, the palette's error), then per
 * clip a band (name, loop, rows, fps, length, its measured error) over a row of cells, each
 * labelled with its clip time. columns x cell pixels wide. */
enum { CB_PREVIEW_HEADER = 30, CB_PREVIEW_BAND = 22 };

/* Renders and writes a PNG (atomically). texels: the palette's payload. */
cb_status cb_preview_write(const cb_palette *p, const void *texels, const cb_model *model, int32_t skin,
                           const cb_preview_options *opt, const char *png_path, cb_error *err);

/* The shipped runtimes/glsl/crowdbake_palette.glsl, embedded at build time. */
extern const char cb_palette_glsl[];

#ifdef __cplusplus
}
#endif

#endif
