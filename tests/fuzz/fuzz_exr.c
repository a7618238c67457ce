/* fuzz_exr.c - libFuzzer target: crowdbake's EXR readers on arbitrary bytes: cb_exr_read (the
 * header, the main crowdbake.* attributes and the texels through OpenEXR) and
 * cb_exr_read_palette, as `verify` and `preview` open a palette (the clip table and palette
 * attributes too), then the palette decoded as they decode it (fuzz_decode.h). OpenEXR reads
 * files, so each input goes through a per-process temporary file. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <unistd.h>

#include "crowdbake/exr.h"
#include "fuzz_decode.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    if (!fuzz_input_file(data, size, "exr", path)) return 0;
    cb_exr_image img;
    cb_error err = {0};
    if (cb_exr_read(path, &img, &err) == CB_OK) cb_exr_image_free(&img);
    cb_exr_palette pal;
    err.status = CB_OK;
    if (cb_exr_read_palette(path, &pal, &err) == CB_OK) {
        fuzz_decode_palette(&pal.palette, pal.palette.texels);
        cb_exr_palette_free(&pal);
    }
    unlink(path);
    return 0;
}
