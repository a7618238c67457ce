/* lanes.h - GCC's vector types for the batched loops (sampling, encoding, measuring: a batch's
 * CB_SAMPLE_BATCH frames as lanes) and the 4x4 transpose that turns rows of values into lanes.
 * Internal. */
#ifndef CB_LANES_H
#define CB_LANES_H

#include <stdint.h>
#include <string.h>

#include "cb_math.h"
#include "crowdbake/core.h"

#if defined(__GNUC__) /* GCC and clang: vector types and __builtin_shufflevector */
typedef double v4df __attribute__((vector_size(32)));
typedef int64_t v4di __attribute__((vector_size(32)));

/* Four rows of four values (r[l]: row l) as lanes i .. i + 3 of four values: out[c][i + l] =
 * r[l][c]. A 4x4 transpose in 8 shuffles, then four vector stores. (The vectors by pointer: by
 * value, 32-byte vectors change the calling convention of the clone without AVX.) */
static CB_CLONE_INLINE void cb_rows_to_lanes4(const v4df *r, double (*out)[CB_SAMPLE_BATCH], int i)
{
    v4df r0 = r[0], r1 = r[1], r2 = r[2], r3 = r[3];
    v4df t0 = __builtin_shufflevector(r0, r1, 0, 4, 2, 6), t1 = __builtin_shufflevector(r0, r1, 1, 5, 3, 7);
    v4df t2 = __builtin_shufflevector(r2, r3, 0, 4, 2, 6), t3 = __builtin_shufflevector(r2, r3, 1, 5, 3, 7);
    v4df x = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), y = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    v4df z = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), w = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
    memcpy(&out[0][i], &x, sizeof x), memcpy(&out[1][i], &y, sizeof y);
    memcpy(&out[2][i], &z, sizeof z), memcpy(&out[3][i], &w, sizeof w);
}
#endif

#endif
