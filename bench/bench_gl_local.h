/* bench_gl_local.h - bench_gl --local-rows: the palette baked with local rows (.pal version 6, --bone-space local:
 * each row a bone in its parent's frame), drawn by the shipped GLSL with CB_LOCAL_ROWS, whose direct path and bone
 * pass walk each bone's chain; the image checked against the VAT's (--check), not only timed. */
#ifndef CROWDBAKE_BENCH_GL_LOCAL_H
#define CROWDBAKE_BENCH_GL_LOCAL_H

#include "crowdbake/crowdbake.h"

/* cb_bind_positions rows 2..4 of a palette of local rows into meta (12 floats a bone: row 2 x the parent, row 3
 * pos_min and scale_max, row 4 pos_max and 0, as runtimes/glsl/README.md defines them); the chains' depths (the
 * ancestors a bone walks) on stderr. */
void bench_local_rows(const cb_palette *p, float *meta);

#endif
