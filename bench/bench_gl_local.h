/* bench_gl_local.h - bench_gl --local-rows: the palette baked with local rows (.pal version 6, --bone-space local:
 * each row a bone in its parent's frame), drawn by the shipped GLSL with CB_LOCAL_ROWS, whose direct path and bone
 * pass walk each bone's chain; the image checked against the VAT's (--check), not only timed. */
#ifndef CROWDBAKE_BENCH_GL_LOCAL_H
#define CROWDBAKE_BENCH_GL_LOCAL_H

#include "crowdbake/crowdbake.h"

/* The chains' depths of a palette of local rows (the ancestors a bone walks), on stderr; cb_bind_texels gives
 * the shaders' rows 2..4 (parents and ranges). */
void bench_local_rows(const cb_palette *p);

#endif
