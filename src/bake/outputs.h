/* outputs.h (internal) - the bake's side of the table of output formats (crowdbake/outputs.h):
 * each row's writer and reader. The bake job writes through it; nothing else needs it. */
#ifndef CB_BAKE_OUTPUTS_H
#define CB_BAKE_OUTPUTS_H

#include "crowdbake/bake.h"
#include "crowdbake/pal_write.h"
#include "internal/pal_mapping.h"

typedef struct bake_output_row {
    cb_output_format format; /* first: cb_output_format_at hands out its address */
    /* Writes the palette baked for `job` to out->path, out->input_hash recorded; `mapping` is the
     * .pal's mapped payload (pal_write.h), which only the .pal's writer uses. */
    cb_status (*write)(const cb_bake_job *job, const cb_palette *p, cb_pal_mapping *mapping,
                       const cb_bake_output *out, cb_error *err);
    cb_status (*read_facts)(const char *path, cb_output_facts *out, cb_error *err);
} bake_output_row;

/* The row of a format bit, or NULL. */
const bake_output_row *bake_output_row_of(unsigned format);

#endif
