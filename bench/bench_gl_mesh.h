/* bench_gl_mesh.h - the herd mesh's preparation for bench_gl.c, as the WebGL2 Crowd prepares it
 * (runtimes/web/crowdbake_bones.mjs): influences largest first, triangles grouped by influence count. */
#ifndef CROWDBAKE_BENCH_GL_MESH_H
#define CROWDBAKE_BENCH_GL_MESH_H

#include <stdint.h>

/* Each vertex's four (joint, weight) pairs, largest weight first: the order the animation LOD keeps. */
void bench_sort_influences(int32_t *joints, float *weights, uint32_t vertices);

/* The triangles ordered by the most influences any of their vertices reads (stable within a count): a CPU
 * rasteriser shades neighbouring vertices of the index list together, each influence loop as long as
 * the longest of them. The same triangles. */
void bench_sort_triangles(uint32_t *indices, uint32_t index_count, const float *weights);

#endif
