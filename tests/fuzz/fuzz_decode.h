/* fuzz_decode.h - what `verify`, `view` and the runtimes do with an opened palette, for the
 * palette fuzzers: every row of every clip, and every row of the texture, decoded for every
 * bone (cb_palette_decode), and each clip played back the way a runtime blends it
 * (cb_runtime_matrices). A header that passes the checks but lies about the texels reads past
 * them, which the sanitizers report. Rows are thinned evenly past ROW_BUDGET decoded bones, the
 * first and last of each range always kept, so a run stays in the milliseconds. And, for the
 * readers that read files (EXR, KTX2), the input written to a per-process temporary file. */
#ifndef FUZZ_DECODE_H
#define FUZZ_DECODE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "crowdbake/palette.h"
#include "crowdbake/runtime.h"

#define ROW_BUDGET (1u << 14)

/* The input as /tmp/crowdbake-fuzz-PID.EXT (its name into `path`), for a reader of files; false
 * when it cannot be written. The caller unlinks it. */
static inline bool fuzz_input_file(const uint8_t *data, size_t size, const char *ext, char path[64])
{
    snprintf(path, 64, "/tmp/crowdbake-fuzz-%d.%s", (int)getpid(), ext);
    FILE *f = fopen(path, "wb");
    if (!f) return false;
    fwrite(data, 1, size, f);
    fclose(f);
    return true;
}

static volatile double fuzz_sink;

static void fuzz_decode_rows(const cb_palette *p, const void *texels, uint32_t first, uint32_t count)
{
    if (count == 0 || p->bone_count == 0) return;
    uint64_t rows_allowed = ROW_BUDGET / p->bone_count + 2;
    uint32_t step = count <= rows_allowed ? 1 : (uint32_t)(count / rows_allowed) + 1;
    double m[16];
    for (uint64_t f = 0;; f += step) {
        if (f > count - 1) f = count - 1; /* the last row always */
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            cb_palette_decode(p, texels, first + (uint32_t)f, j, m);
            fuzz_sink += m[0] + m[15];
        }
        if (f == count - 1) break;
    }
}

static void fuzz_decode_palette(const cb_palette *p, const void *texels)
{
    fuzz_decode_rows(p, texels, 0, p->rows);
    double *matrices = p->bone_count <= 4096 ? malloc(sizeof(double) * 16 * (p->bone_count ? p->bone_count : 1)) : NULL;
    for (uint32_t i = 0; i < p->clip_count; ++i) {
        const cb_palette_clip *c = &p->clips[i];
        fuzz_decode_rows(p, texels, c->first_row, c->frames);
        if (!matrices || c->frames == 0) continue;
        /* as the roster starts it (a loop or a one-shot), at a few times: the game's numbers, not the file's */
        cb_instance in = {c->first_row, c->loops ? c->frames : -(double)c->frames, 30, 0.25};
        for (double t = 0.0; t < 40.0; t += 13.37) cb_runtime_matrices(p, texels, &in, t, matrices);
        cb_instance own = cb_instance_of(c); /* a timed clip's through its map (the reader checked it) */
        for (double t = -1.0; c->timed && t < 40.0; t += 7.77) cb_runtime_matrices(p, texels, &own, t, matrices);
        fuzz_sink += matrices[0];
    }
    free(matrices);
}

#endif
