/* roster_fresh.c - whether a type's outputs on disk are this bake's (the roster's up-to-date
 * check): each format's file read back, its recorded input hash and rows compared. */
#include "roster_files.h"

#include "crowdbake/exr.h"
#include "crowdbake_pal.h"

/* True when every output exists and records this key; fills the geometry from the .pal. */
bool roster_outputs_up_to_date(cb_roster_type *t, unsigned formats)
{
    char msg[256];
    if (formats & CB_FORMAT_PAL) {
        cbpal_file f;
        /* Verified (memory speed): a file torn by a power loss is baked again, not trusted. */
        if (cbpal_open(t->pal_path, CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg) != 0) return false;
        bool same = f.header.input_hash == t->input_hash && f.header.rows == t->rows;
        if (same) {
            t->width = f.header.width, t->height = f.header.height, t->blocks = f.header.blocks;
            t->layout = (cb_layout)f.header.layout, t->precision = (cb_precision)f.header.precision;
            t->max_error = f.header.max_error;
            t->visible_error = f.header.visible_error;
            t->palette_bytes = f.header.payload_raw_size;
        }
        cbpal_close(&f);
        if (!same) return false;
    }
    if (formats & CB_FORMAT_EXR) {
        cb_exr_image img;
        cb_error e = {0};
        if (cb_exr_read(t->exr_path, &img, &e)) return false;
        bool same = img.input_hash == t->input_hash && (uint32_t)img.rows == t->rows;
        if (same && !(formats & CB_FORMAT_PAL)) {
            t->width = img.width, t->height = img.height, t->blocks = (uint32_t)img.blocks;
            cb_layout_parse(img.layout, &t->layout);
            t->precision = img.precision;
            t->palette_bytes = img.texel_bytes;
            t->max_error = img.max_error, t->visible_error = img.visible_error;
        }
        cb_exr_image_free(&img);
        if (!same) return false;
    }
    return !(formats & CB_FORMAT_BABYLON) || roster_babylon_up_to_date(t);
}
