/* fuzz_pal.c - libFuzzer target: the .pal reader (include/crowdbake_pal.h) on arbitrary bytes,
 * with and without checksum verification, then every table entry, every bone's matrix at a few
 * times in every clip (cbpal_bone_matrix), its travel offset (cbpal_travel_offset) and rows (cbpal_clip_frame, a timed
 * clip's map: cbpal_timed_map), and the palette decoded as
 * `verify`, `view` and the runtimes decode it (cb_palette_view, fuzz_decode.h). */
#include <stdint.h>

#include "crowdbake_pal.h" /* the implementation is in libcrowdbake, with zstd */
#include "crowdbake/pal_view.h"
#include "fuzz_decode.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (unsigned flags = 0; flags <= CBPAL_VERIFY_CHECKSUM; ++flags) {
        cbpal_file f;
        char err[256];
        if (cbpal_open_memory(data, size, flags, &f, err, sizeof err) != 0) continue;
        volatile unsigned sink = 0;
        for (uint32_t i = 0; i < f.header.clip_count; ++i) {
            cbpal_clip c;
            cbpal_get_clip(&f, i, &c);
            sink += (unsigned char)c.name[0] + c.frames;
        }
        for (uint32_t i = 0; i < f.header.bone_count; ++i) {
            cbpal_bone b;
            cbpal_get_bone(&f, i, &b);
            sink += (unsigned char)b.name[0];
        }
        /* Every clip's every bone at times before, inside and far past the clip (a file's fps may be anything). */
        static const double times[] = {-1.0, 0.3, 1e6};
        for (uint32_t i = 0; i < f.header.clip_count; ++i)
            for (uint32_t j = 0; j < f.header.bone_count; ++j)
                for (int t = 0; t < 3; ++t) {
                    float m[16];
                    if (cbpal_bone_matrix(&f, i, times[t], j, m) == 0) sink += m[15] == 1.0f;
                }
        /* Version 7's timed clips: the rows each picks through its map, and every map texel. */
        for (uint32_t i = 0; i < f.header.clip_count; ++i) {
            cbpal_clip c;
            cbpal_get_clip(&f, i, &c);
            for (int t = 0; t < 3; ++t) {
                uint32_t r0, r1;
                float fr;
                if (cbpal_clip_frame(&f, i, times[t], &r0, &r1, &fr) == 0) sink += r0 + r1 + (fr > 0.5f);
            }
            for (uint32_t cell = 0; cell < c.cells && cell < 4096; ++cell) {
                float v[4];
                if (cbpal_timed_map(&f, i, cell, v) == 0) sink += v[0] > 0;
            }
        }
        /* Version 5's travel offsets at the same times (a table the header may point anywhere). */
        for (uint32_t i = 0; i < f.header.clip_count; ++i)
            for (int t = 0; t < 3; ++t) {
                float o[3];
                if (cbpal_travel_offset(&f, i, times[t], o) == 0) sink += o[0] == 0.0f;
            }
        (void)sink;
        cb_palette view;
        cb_error e = {0};
        if (flags == 0 && cb_palette_view(&f, &view, &e) == CB_OK) { /* the checksum changes nothing it decodes */
            fuzz_decode_palette(&view, f.texels);
            cb_palette_view_free(&view);
        }
        cbpal_close(&f);
    }
    return 0;
}
