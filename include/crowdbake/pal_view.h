/* pal_view.h - a cb_palette that reads an opened .pal in place, for decoding and skinning. */
#ifndef CB_PAL_VIEW_H
#define CB_PAL_VIEW_H

#include "export.h"

#include "palette.h"
struct cbpal_file;

#ifdef __cplusplus
extern "C" {
#endif

/* Fills *view from the file's header and tables; the texels stay in the file (view->texels is
 * NULL: pass f->texels to the decoders). Clip names point into the file. Free with
 * cb_palette_view_free. */
CROWDBAKE_API cb_status cb_palette_view(const struct cbpal_file *f, cb_palette *view, cb_error *err);
CROWDBAKE_API void cb_palette_view_free(cb_palette *view);

#ifdef __cplusplus
}
#endif

#endif
