/* fuzz_ktx2.c - libFuzzer target: cb_ktx2_read_palette on arbitrary bytes, as `inspect`,
 * `verify` and `preview` open a .ktx2 (the container's header and level index, the key/value
 * data and crowdbake's JSON tables in it), then the palette decoded as they decode it
 * (fuzz_decode.h). The reader reads files, so each input goes through a per-process temporary. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <unistd.h>

#include "crowdbake/ktx2.h"
#include "fuzz_decode.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    if (!fuzz_input_file(data, size, "ktx2", path)) return 0;
    cb_ktx2_palette pal;
    cb_error err = {0};
    if (cb_ktx2_read_palette(path, &pal, &err) == CB_OK) {
        fuzz_decode_palette(&pal.palette, pal.palette.texels);
        cb_ktx2_palette_free(&pal);
    }
    unlink(path);
    return 0;
}
