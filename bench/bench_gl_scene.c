/* bench_gl_scene.c - see bench_gl_scene.h. */
#define GL_GLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_gl_context.h"
#include "bench_gl_mesh.h"
#include "bench_gl_scene.h"
#include "bench_gl_tiers.h"

/* ---- textures ---- */

void bench_upload_palette(scene *s)
{
    const cb_palette *p = s->pal;
    static const GLint internal[] = {GL_RGBA32F, GL_RGBA16F, GL_RGBA16UI};
    static const GLenum format[] = {GL_RGBA, GL_RGBA, GL_RGBA_INTEGER}, type[] = {GL_FLOAT, GL_HALF_FLOAT, GL_UNSIGNED_SHORT};
    for (int k = 0; k < 2; ++k) {
        const cb_palette *t = k ? s->pass_pal : p;
        GLuint tex = bench_texture(internal[t->precision], (GLsizei)t->width, (GLsizei)t->height, format[t->precision],
                                   type[t->precision], t->texels);
        *(k ? &s->pass_tex : &s->palette_tex) = tex;
    }
    float *rgba = calloc((size_t)p->bone_count * 20, sizeof(float)); /* 5 rows, whichever cb_bind_texels fills */
    cb_bind_texels(p, rgba);
    s->bind_tex = bench_texture(GL_RGBA32F, (GLsizei)p->bone_count, 5, GL_RGBA, GL_FLOAT, rgba);
    free(rgba);
    s->vat_pos = bench_texture(GL_RGBA16F, (GLsizei)s->vat->geometry.width, (GLsizei)s->vat->geometry.height, GL_RGBA,
                         GL_HALF_FLOAT, s->vat->positions);
    s->vat_nrm = bench_texture(GL_RGBA16F, (GLsizei)s->vat->geometry.width, (GLsizei)s->vat->geometry.height, GL_RGBA,
                         GL_HALF_FLOAT, s->vat->normals);
}

/* The bone pass's three RGBA32F targets for `capacity` instances, in column blocks of the texture limit. */
void bench_bone_targets(scene *s, uint32_t capacity)
{
    GLint max;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max);
    s->bone_rows = capacity < (uint32_t)max ? capacity : (uint32_t)max;
    s->bone_width = (capacity + s->bone_rows - 1) / s->bone_rows * s->pal->bone_count;
    if (s->bone_width > (uint32_t)max) bench_die("too many instances for the bone pass's textures");
    glGenFramebuffers(1, &s->bone_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, s->bone_fbo);
    for (int k = 0; k < 3; ++k) {
        s->bone_tex[k] = bench_texture(GL_RGBA32F, (GLsizei)s->bone_width, (GLsizei)s->bone_rows, GL_RGBA, GL_FLOAT, NULL);
        glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + (GLenum)k, GL_TEXTURE_2D, s->bone_tex[k], 0);
    }
    const GLenum buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, buffers);
    if (glCheckFramebufferStatus(GL_DRAW_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) bench_die("the bone textures are not renderable");
}

/* The largest side of any clip's animated bounds: the grid's spacing and the LOD's size of an instance. */
float bench_herd_size(const cb_palette *p)
{
    float size = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c)
        for (int k = 0; k < 3; ++k) size = fmaxf(size, p->clips[c].bounds_max[k] - p->clips[c].bounds_min[k]);
    return size;
}

/* ---- the mesh: every primitive of the first skin, in the VAT's vertex order ---- */

/* A primitive's triangle corners: its indices, or its vertices in order where it has none (glTF's non-indexed
 * primitive, as Fox.glb's: drawn with no indices it drew nothing). */
static uint32_t primitive_indices(const cb_primitive *p) { return p->indices ? p->index_count : p->vertex_count; }

void bench_upload_mesh(scene *s, const cb_model *m, uint32_t capacity)
{
    uint32_t verts = 0, indices = 0;
    for (uint32_t i = 0; i < m->primitive_count; ++i)
        if (m->primitives[i].skin == 0) verts += m->primitives[i].vertex_count, indices += primitive_indices(&m->primitives[i]);
    float *pos = malloc(verts * 12), *nrm = calloc(verts, 12), *w = malloc(verts * 16);
    int32_t *j = malloc(verts * 16);
    uint32_t *idx = malloc(indices * 4), v0 = 0, i0 = 0;
    for (uint32_t i = 0; i < m->primitive_count; ++i) {
        const cb_primitive *p = &m->primitives[i];
        if (p->skin != 0) continue;
        memcpy(pos + v0 * 3, p->positions, p->vertex_count * 12);
        if (p->normals) memcpy(nrm + v0 * 3, p->normals, p->vertex_count * 12);
        memcpy(w + v0 * 4, p->weights, p->vertex_count * 16);
        for (uint32_t k = 0; k < p->vertex_count * 4; ++k) j[v0 * 4 + k] = p->joints[k];
        for (uint32_t k = 0; k < primitive_indices(p); ++k) idx[i0 + k] = v0 + (p->indices ? p->indices[k] : k);
        v0 += p->vertex_count, i0 += primitive_indices(p);
    }
    bench_sort_influences(j, w, verts); /* as the WebGL2 Crowd: every method draws the same order */
    for (uint32_t v = 0; v < verts && !s->blended; ++v) s->blended = w[v * 4 + 1] > 0;
    if (s->lod) /* as lod 'auto' of the runtimes: where the worst vertex of 64 poses moves at most a pixel */
        bench_lod_thresholds(s->sampler, s->pal, pos, j, w, verts, bench_herd_size(s->pal), 1.0, 64, s->lod_pixels);
    bench_sort_triangles(idx, indices, w);
    glGenVertexArrays(1, &s->vao);
    glBindVertexArray(s->vao);
    const void *data[4] = {pos, nrm, j, w};
    const int size[4] = {3, 3, 4, 4};
    for (GLuint a = 0; a < 4; ++a) {
        GLuint b;
        glGenBuffers(1, &b);
        glBindBuffer(GL_ARRAY_BUFFER, b);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)verts * size[a] * 4, data[a], GL_STATIC_DRAW);
        glEnableVertexAttribArray(a);
        if (a == 2) glVertexAttribIPointer(a, 4, GL_INT, 0, 0);
        else glVertexAttribPointer(a, size[a], GL_FLOAT, GL_FALSE, 0, 0);
    }
    GLuint ib;
    glGenBuffers(1, &ib);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ib);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)indices * 4, idx, GL_STATIC_DRAW);
    s->index_count = (GLsizei)indices;
    glGenBuffers(1, &s->instance_vbo);
    glBindBuffer(GL_ARRAY_BUFFER, s->instance_vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)capacity * 32, NULL, GL_STATIC_DRAW);
    for (GLuint a = 4; a < 6; ++a) { /* a_place, a_inst: 8 floats an instance */
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 32, (const void *)(uintptr_t)((a - 4) * 16));
        glVertexAttribDivisor(a, 1);
    }
    glGenBuffers(1, &s->tier_vbo); /* a_bone_instance: the tiers' order, pointed at a tier's first by each draw */
    glBindBuffer(GL_ARRAY_BUFFER, s->tier_vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)capacity * 4, NULL, GL_STREAM_DRAW);
    glEnableVertexAttribArray(6);
    glVertexAttribIPointer(6, 1, GL_INT, 4, 0);
    glVertexAttribDivisor(6, 1);
    glGenVertexArrays(1, &s->pass_vao);
    glBindVertexArray(s->pass_vao);
    glBindBuffer(GL_ARRAY_BUFFER, s->instance_vbo);
    for (GLuint a = 4; a < 6; ++a) { /* the pass places each bone: it reads a_place too */
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 32, (const void *)(uintptr_t)((a - 4) * 16));
        glVertexAttribDivisor(a, 1);
    }
    glBindVertexArray(0);
    free(pos), free(nrm), free(w), free(j), free(idx);
}

/* ---- a frame ---- */

static void bind_rows(const scene *s, GLuint prog, const cb_palette *p, GLuint rows)
{
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, rows);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, s->bind_tex);
    glUniform1i(glGetUniformLocation(prog, "cb_palette"), 0);
    glUniform1i(glGetUniformLocation(prog, "cb_bind_positions"), 1);
    glUniform1i(glGetUniformLocation(prog, "cb_row_texels"), (GLint)p->row_texels);
    glUniform1i(glGetUniformLocation(prog, "cb_rows_per_block"), (GLint)p->height);
    glUniform3fv(glGetUniformLocation(prog, "cb_bounds_min"), 1, p->bounds_min);
    glUniform3fv(glGetUniformLocation(prog, "cb_bounds_max"), 1, p->bounds_max);
    glUniform1f(glGetUniformLocation(prog, "cb_linear_range"), p->linear_range);
}

static void bind_palette(const scene *s, GLuint prog) { bind_rows(s, prog, s->pal, s->palette_tex); }

/* The bone pass: every instance's bones blended once into the three targets. */
static void run_bone_pass(const scene *s, uint32_t n, float time)
{
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, s->bone_fbo);
    glViewport(0, 0, (GLsizei)s->bone_width, (GLsizei)s->bone_rows);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(s->pass);
    bind_rows(s, s->pass, s->pass_pal, s->pass_tex);
    glUniform1f(glGetUniformLocation(s->pass, "u_time"), time);
    glUniform1i(glGetUniformLocation(s->pass, "u_rows"), (GLint)s->bone_rows);
    glUniform2f(glGetUniformLocation(s->pass, "u_size"), (float)s->bone_width, (float)s->bone_rows);
    glBindVertexArray(s->pass_vao);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, (GLsizei)n);
}

/* The bone pass's textures for a draw that skins from them. */
static void bind_bones(const scene *s, GLuint prog)
{
    for (int k = 0; k < 3; ++k) {
        char name[16];
        snprintf(name, sizeof name, "cb_bones%d", k);
        glActiveTexture(GL_TEXTURE2 + (GLenum)k);
        glBindTexture(GL_TEXTURE_2D, s->bone_tex[k]);
        glUniform1i(glGetUniformLocation(prog, name), 2 + k);
    }
    glUniform1i(glGetUniformLocation(prog, "cb_bone_rows"), (GLint)s->bone_rows);
}

/* The LOD's tiers drawn apart: the instances sorted by tier (lod: pixels tall at w = 1, the 2- and 1-influence
 * thresholds), then one draw a tier with its own program, a_bone_instance pointed at the tier's first. */
static void draw_tiers(const scene *s, uint32_t n, const float *view_projection, const float lod[3])
{
    bench_tiers tiers;
    bench_sort_by_tier(s->instances, 8, n, view_projection, lod, s->order, &tiers);
    glBindVertexArray(s->vao);
    glBindBuffer(GL_ARRAY_BUFFER, s->tier_vbo);
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)n * 4, s->order);
    for (int k = 0; k < 3; ++k) {
        if (!tiers.count[k]) continue;
        GLuint prog = s->tier_prog[k];
        glUseProgram(prog);
        bind_palette(s, prog);
        bind_bones(s, prog);
        glUniformMatrix4fv(glGetUniformLocation(prog, "u_view_projection"), 1, GL_FALSE, view_projection);
        glVertexAttribIPointer(6, 1, GL_INT, 4, (const void *)(uintptr_t)(tiers.first[k] * 4));
        glDrawElementsInstanced(GL_TRIANGLES, s->index_count, GL_UNSIGNED_INT, 0, (GLsizei)tiers.count[k]);
    }
}

void bench_draw(const scene *s, int method, uint32_t n, float time, const float *view_projection, GLuint target)
{
    if (method == 1) run_bone_pass(s, n, time);
    if (method == 1 && s->pass_only) return;
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, target);
    glViewport(0, 0, WIDTH, HEIGHT);
    glEnable(GL_DEPTH_TEST);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    GLuint prog = s->prog[method];
    glUseProgram(prog);
    if (method == 2) {
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, s->vat_pos);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, s->vat_nrm);
        glUniform1i(glGetUniformLocation(prog, "u_vat_positions"), 0);
        glUniform1i(glGetUniformLocation(prog, "u_vat_normals"), 1);
        glUniform1i(glGetUniformLocation(prog, "u_frame_width"), (GLint)s->vat->frame_width);
        glUniform1i(glGetUniformLocation(prog, "u_rows_per_frame"), (GLint)s->vat->rows_per_frame);
        glUniform1i(glGetUniformLocation(prog, "u_vat_rows"), (GLint)s->vat->geometry.height);
    } else bind_palette(s, prog);
    float lod[3] = {bench_herd_size(s->pal) * 0.5f * HEIGHT * hypotf(hypotf(view_projection[1], view_projection[5]), view_projection[9]),
                    s->lod ? s->lod_pixels[1] : 0.0f, s->lod ? s->lod_pixels[0] : 0.0f};
    if (method == 1 && s->lod && s->tiers) {
        draw_tiers(s, n, view_projection, lod);
        return;
    }
    if (method == 1) {
        bind_bones(s, prog);
        glUniform3fv(glGetUniformLocation(prog, "u_lod"), 1, lod);
    }
    glUniform1f(glGetUniformLocation(prog, "u_time"), time);
    glUniformMatrix4fv(glGetUniformLocation(prog, "u_view_projection"), 1, GL_FALSE, view_projection);
    glBindVertexArray(s->vao);
    glDrawElementsInstanced(GL_TRIANGLES, s->index_count, GL_UNSIGNED_INT, 0, (GLsizei)n);
}

/* n instances walking in a grid, the camera looking down at all of them (none culled). */
void bench_place_herd(const scene *s, uint32_t n, float view_projection[16])
{
    const cb_palette *p = s->pal;
    const cb_palette_clip *clip = &p->clips[0];
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].loops) { clip = &p->clips[c]; break; }
    float size = bench_herd_size(p);
    uint32_t g = (uint32_t)ceil(sqrt((double)n));
    float *inst = s->instances;
    for (uint32_t i = 0; i < n; ++i) {
        float v[8] = {((float)(i % g) - (float)g / 2) * size * 1.5f, 0, ((float)(i / g) - (float)g / 2) * size * 1.5f,
                      (float)i * 2.4f, (float)clip->first_row, clip->loops ? (float)clip->frames : -(float)clip->frames,
                      (float)clip->fps, (float)fmod(i * 0.6180339887, 1.0)};
        memcpy(inst + i * 8, v, sizeof v);
    }
    glBindBuffer(GL_ARRAY_BUFFER, s->instance_vbo);
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)n * 32, inst);
    bench_herd_view(g * size * 1.5, (double)WIDTH / HEIGHT, view_projection);
}
