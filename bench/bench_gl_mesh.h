/* bench_gl_mesh.h - the herd mesh's preparation for bench_gl.c, as the WebGL2 Crowd prepares it
 * (runtimes/web/crowdbake_bones.mjs): influences largest first, triangles grouped by influence count, the
 * animation LOD's thresholds; and bench_gl's CPU-side helpers (a text file, two images compared). */
#ifndef CROWDBAKE_BENCH_GL_MESH_H
#define CROWDBAKE_BENCH_GL_MESH_H

#include <stdint.h>

#include "crowdbake/crowdbake.h"

/* Each vertex's four (joint, weight) pairs, largest weight first: the order the animation LOD keeps. */
void bench_sort_influences(int32_t *joints, float *weights, uint32_t vertices);

/* The triangles ordered by the most influences any of their vertices reads (stable within a count): a CPU
 * rasteriser shades neighbouring vertices of the index list together, each influence loop as long as
 * the longest of them. The same triangles. */
void bench_sort_triangles(uint32_t *indices, uint32_t index_count, const float *weights);

/* The animation LOD's thresholds as the runtimes' lod 'auto' measures them (runtimes/web/crowdbake_bones.mjs,
 * lodThresholds): out[0] the pixels tall (for an instance whose animated bounds' largest side is `size`) under which
 * its largest influence alone, out[1] its 2 largest, move no vertex more than `pixel_error` pixels from its full skin,
 * the worst vertex over `poses` poses spread over every clip's rows (sampled from the model; joints and weights
 * sorted largest first). A tier that moves nothing: 1e6 pixels. */
void bench_lod_thresholds(cb_sampler *sampler, const cb_palette *pal, const float *positions, const int32_t *joints,
                          const float *weights, uint32_t vertices, double size, double pixel_error, int poses, float out[2]);

/* The herd's camera: perspective(50 degrees, aspect a) x lookAt(eye (0, 0.8, 0.7) x side, the origin), column-major:
 * a grid `side` wide seen whole from above. */
void bench_herd_view(double side, double a, float view_projection[16]);

/* A whole text file, NUL-terminated, for the caller to free; NULL when it cannot be read. */
char *bench_read_text(const char *path);

/* Share of the pixels covered (not black) in either RGBA8 image whose colours differ by more than 8 of 255. */
double bench_image_difference(const unsigned char *a, const unsigned char *b, int width, int height, long *covered);

#endif
