/* bench_gl_check.h - bench_gl --check (bench/bench_gl.c): 16 instances drawn by the palette, the bone pass and the
 * VAT at the same time must give the same image, the VAT a quarter second later must not, and the animation LOD's
 * tiers drawn apart the same bytes as in one draw. */
#ifndef CROWDBAKE_BENCH_GL_CHECK_H
#define CROWDBAKE_BENCH_GL_CHECK_H

#include "bench_gl_scene.h"

/* 0 when the images agree, else 1 (and a line on stderr); the numbers on stdout. */
int bench_check_images(const scene *s, GLuint target);

#endif
