/* fuzz_exr.c - libFuzzer target: crowdbake's EXR reader (header, crowdbake.* attributes and
 * texels through OpenEXR) on arbitrary bytes. OpenEXR reads files, so each input goes through
 * a per-process temporary file. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <unistd.h>

#include "crowdbake/exr.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/crowdbake-fuzz-%d.exr", (int)getpid());
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    cb_exr_image img;
    cb_error err = {0};
    if (cb_exr_read(path, &img, &err) == CB_OK) cb_exr_image_free(&img);
    return 0;
}
