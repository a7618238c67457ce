/* bench_gl_tiers.h - the animation LOD's far tiers drawn apart (bench_gl.c --lod): each frame every instance's tier
 * is decided once on the CPU, by the rule the bone pass's draw applies per vertex (cb_lod_influences of
 * runtimes/glsl/crowdbake_palette.glsl), and the instances are bucketed by tier (stable, into the caller's array: no
 * allocation a frame), so that each tier draws with a program compiled for its influences (CB_INFLUENCES 1, 2, 4). */
#ifndef CROWDBAKE_BENCH_GL_TIERS_H
#define CROWDBAKE_BENCH_GL_TIERS_H

#include <stdint.h>

/* Instances by tier: tier k (0: 1 influence, 1: 2, 2: every one) is order[first[k] .. first[k] + count[k]). */
typedef struct bench_tiers {
    uint32_t first[3], count[3];
} bench_tiers;

/* The tier (0, 1, 2) of an instance at `place` (x, y, z): its size on screen, lod[0] pixels tall at w = 1 over
 * its w under view_projection (column-major), under lod[2] pixels: 1 influence, under lod[1]: 2, else every one. */
int bench_lod_tier(const float place[3], const float view_projection[16], const float lod[3]);

/* The n instances (each `stride` floats, its place first) bucketed by tier into order (n entries). */
void bench_sort_by_tier(const float *instances, uint32_t stride, uint32_t n, const float view_projection[16],
                        const float lod[3], int32_t *order, bench_tiers *tiers);

/* Thresholds (lod[1], lod[2]) that split the n instances into three tiers of about a third each, half way between
 * neighbouring sizes (bench_gl --check draws every tier, far from any threshold). */
void bench_split_tiers(const float *instances, uint32_t stride, uint32_t n, const float view_projection[16], float lod[3]);

#endif
