/* bench_gl_scene.h - bench_gl's herd (bench/bench_gl.c): the palette, bone pass and VAT textures, the mesh, the
 * instances' placement and one frame drawn by a method (0 palette, 1 bone pass, 2 VAT) into the offscreen target. */
#ifndef CROWDBAKE_BENCH_GL_SCENE_H
#define CROWDBAKE_BENCH_GL_SCENE_H

#include <GL/gl.h>
#include <stdbool.h>
#include <stdint.h>

#include "crowdbake/crowdbake.h"

#define WIDTH 960
#define HEIGHT 540
#define METHODS 3

typedef struct scene {
    const cb_palette *pal, *pass_pal; /* pass_pal: what the bone pass reads (pal itself; --local-rows: both local) */
    const cb_vat *vat;
    bool local_rows; /* --local-rows: the palette's rows are local (CB_LOCAL_ROWS) */
    GLuint pass_tex, palette_tex, bind_tex, vat_pos, vat_nrm, bone_tex[3], bone_fbo, bone_rows, bone_width;
    GLuint prog[METHODS], tier_prog[3], pass, vao, pass_vao, instance_vbo, tier_vbo;
    GLsizei index_count;
    bool lod; /* --lod: the bone pass's animation LOD, as the WebGL2 Crowd's default (lod 'auto') */
    bool pass_only; /* --pass-only: `bones` times the bone pass alone (no draw) */
    bool tiers; /* its tiers drawn apart (tier_prog), not found per vertex (prog[1]; --lod-single) */
    bool blended; /* some vertex reads more than one influence: the LOD has something to drop */
    float lod_pixels[2]; /* its thresholds: 1 influence under [0] pixels tall, 2 under [1] (bench_lod_thresholds) */
    float *instances; /* the herd's 8 floats an instance (place, inst), kept for the tiers' sort */
    int32_t *order;   /* the instances by tier, a frame's (bench_sort_by_tier) */
    cb_sampler *sampler;
} scene;

/* The palette (and the pass's rows), the bind positions' rows and the VAT as textures. */
void bench_upload_palette(scene *s);

/* The bone pass's three RGBA32F targets for `capacity` instances, in column blocks of the texture limit. */
void bench_bone_targets(scene *s, uint32_t capacity);

/* The largest side of any clip's animated bounds: the grid's spacing and the LOD's size of an instance. */
float bench_herd_size(const cb_palette *p);

/* Every primitive of the first skin, in the VAT's vertex order, and the instance buffers for `capacity`. */
void bench_upload_mesh(scene *s, const cb_model *m, uint32_t capacity);

/* n instances drawn by `method` at `time` into `target` (method 1: the bone pass first). */
void bench_draw(const scene *s, int method, uint32_t n, float time, const float *view_projection, GLuint target);

/* n instances walking in a grid, the camera looking down at all of them (none culled). */
void bench_place_herd(const scene *s, uint32_t n, float view_projection[16]);

#endif
