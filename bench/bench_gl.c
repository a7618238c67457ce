/* bench_gl.c - the native crowd benchmark: N instances of a model drawn from its palette (the
 * shipped runtimes/glsl/crowdbake_palette.glsl, per-vertex blending), from the bone pass (the
 * same GLSL's cb_bone_pass and CB_BONE_TEXTURE) and from a VAT of the same frames, each as one
 * instanced draw into a 960x540 offscreen framebuffer, timed with GL timer queries
 * (GL_TIME_ELAPSED). OpenGL 3.3 core through EGL without a window: Mesa's llvmpipe here
 * (EGL_PLATFORM=surfaceless), a GPU's driver through EGL's device platform elsewhere, unchanged.
 *
 *   bench_gl MODEL.glb N1,N2,... [--frames K] [--lod]   JSON: per count and method, median and min frame ms
 *   bench_gl MODEL.glb --check                    the three images of 16 instances must agree
 * --lod: the bone pass with the runtimes' animation LOD (lod 'auto'), its tiers drawn apart (instances sorted by tier
 * on the CPU, a program each, compiled with CB_INFLUENCES 1, 2, 4; --lod-single: one draw, the tier found per vertex);
 * BENCH_GL_BONES_GLSL=FILE: the bone pass and its draw from another library, the palette and the VAT from the shipped
 * one (weighs a change in one run); BENCH_GL_PASS_GLSL=FILE: the bone pass's fragment main from FILE, after it;
 * --local-rows: the pass reads local rows (bench_gl_local.h, bench/bones_local.glsl); --pass-only: `bones` is the pass.
 *
 * The palette and the VAT are baked here from MODEL.glb alike (qpos/u16 and RGBA16F, 30 fps, in
 * place), so both play the same frames. Methods alternate within a count (a change of the
 * machine's load hits all alike). */
#define GL_GLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "crowdbake/crowdbake.h"
#include "bench_gl_context.h"
#include "bench_gl_local.h"
#include "bench_gl_mesh.h"
#include "bench_gl_tiers.h"

/* runtimes/glsl/crowdbake_palette.glsl, embedded by the build (build/gen/palette_glsl.c). */
extern const char cb_palette_glsl[];

#define WIDTH 960
#define HEIGHT 540
#define METHODS 3
static const char *const method_names[METHODS] = {"palette", "bones", "vat"}; /* bones is "lod" with --lod */

/* ---- shaders: the shipped library, then a main ---- */

static const char *MAIN_HEAD =
    "in vec3 a_position; in vec3 a_normal; in ivec4 a_joints; in vec4 a_weights; in vec4 a_place; in vec4 a_inst;\n"
    "uniform float u_time; uniform mat4 u_view_projection;\n"
    "out vec3 v_normal;\n";
static const char *MAIN_TAIL =
    "    float c = cos(a_place.w), s = sin(a_place.w);\n"
    "    mat3 yaw = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);\n"
    "    v_normal = yaw * n;\n"
    "    gl_Position = u_view_projection * vec4(a_place.xyz + yaw * p, 1.0);\n"
    "}\n";
static const char *SKIN_PALETTE =
    "void main() {\n    vec3 p, n;\n"
    "    cb_skin_position_normal(a_position, a_normal, a_joints, a_weights, a_inst, u_time, p, n);\n";
static const char *SKIN_BONES = /* the pass placed each bone: world space straight away; --lod: the animation LOD */
    "uniform vec3 u_lod;\n" /* pixels tall at w = 1, the 2- and 1-influence thresholds (0: off) */
    "void main() {\n    vec3 p, n;\n    float pixels = u_lod.x / (u_view_projection * vec4(a_place.xyz, 1.0)).w;\n"
    "    cb_skin_bone_pass_influences(a_position, a_normal, a_joints, a_weights, gl_InstanceID,\n"
    "                                 cb_lod_influences(pixels, u_lod.y, u_lod.z), p, n);\n"
    "    v_normal = n;\n    gl_Position = u_view_projection * vec4(p, 1.0);\n}\n";
static const char *SKIN_TIER = /* one LOD tier, compiled in: a_bone_instance is the instance's row in the pass */
    "in int a_bone_instance;\n"
    "void main() {\n    vec3 p, n;\n"
    "    cb_skin_bone_pass(a_position, a_normal, a_joints, a_weights, a_bone_instance, p, n);\n"
    "    v_normal = n;\n    gl_Position = u_view_projection * vec4(p, 1.0);\n}\n";
static const char *SKIN_VAT =
    "uniform sampler2D u_vat_positions, u_vat_normals; uniform int u_frame_width, u_rows_per_frame, u_vat_rows;\n"
    "vec3 vat_fetch(sampler2D t, int frame) {\n"
    "    int row = frame * u_rows_per_frame + gl_VertexID / u_frame_width, block = row / u_vat_rows;\n"
    "    return texelFetch(t, ivec2(block * u_frame_width + gl_VertexID % u_frame_width, row - block * u_vat_rows), 0).xyz;\n"
    "}\n"
    "void main() {\n    int row0, row1; float fr;\n    cb_frame(a_inst, u_time, row0, row1, fr);\n"
    "    vec3 p = mix(vat_fetch(u_vat_positions, row0), vat_fetch(u_vat_positions, row1), fr);\n"
    "    vec3 n = normalize(mix(vat_fetch(u_vat_normals, row0), vat_fetch(u_vat_normals, row1), fr));\n";
static const char *FRAGMENT =
    "#version 330 core\nin vec3 v_normal; out vec4 o_color;\n"
    "void main() { float l = 0.35 + 0.65 * max(dot(normalize(v_normal), normalize(vec3(0.4, 0.8, 0.3))), 0.0);\n"
    "              o_color = vec4(vec3(0.8, 0.7, 0.55) * l, 1.0); }\n";
static const char *PASS_VERTEX =
    "in vec4 a_place; in vec4 a_inst; uniform float u_time; uniform int u_rows; uniform vec2 u_size;\n"
    "flat out vec4 v_place; flat out vec4 v_inst; flat out int v_x0;\n"
    "void main() {\n"
    "    int block = gl_InstanceID / u_rows, row = gl_InstanceID - block * u_rows, bones = cb_row_texels / CB_TEXELS_PER_BONE;\n"
    "    v_x0 = block * bones;\n"
    "    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));\n"
    "    gl_Position = vec4(vec2(float(v_x0) + corner.x * float(bones), float(row) + corner.y) / u_size * 2.0 - 1.0, 0.0, 1.0);\n"
    "    v_place = a_place, v_inst = a_inst;\n"
    "}\n";
static const char *PASS_FRAGMENT =
    "flat in vec4 v_place; flat in vec4 v_inst; flat in int v_x0; uniform float u_time;\n"
    "layout(location = 0) out vec4 o_c0; layout(location = 1) out vec4 o_c1; layout(location = 2) out vec4 o_c2;\n"
    "void main() { cb_bone_pass_placed(int(gl_FragCoord.x) - v_x0, v_inst, v_inst, 1.0, u_time, v_place, 1.0, o_c0, o_c1, o_c2); }\n";

/* The shipped library with the palette's defines (and CB_BONE_TEXTURE for `bones`, CB_INFLUENCES for `influences`
 * other than 0) before each stage's main. */
static GLuint program(const char *library, const cb_palette *p, bool bones, int influences, const char *const *vs, int vs_n,
                      const char *const *fs, int fs_n)
{
    static const char *layouts[] = {"CB_LAYOUT_MAT4", "CB_LAYOUT_AFFINE", "CB_LAYOUT_QPOS"};
    static const char *precisions[] = {"CB_PRECISION_FLOAT", "CB_PRECISION_HALF", "CB_PRECISION_U16"};
    char defines[256], count[32] = "";
    if (influences) snprintf(count, sizeof count, "#define CB_INFLUENCES %d\n", influences);
    snprintf(defines, sizeof defines, "#version 330 core\n#define %s\n#define %s\n%s%s%s", layouts[p->layout],
             precisions[p->precision], p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "",
             bones ? "#define CB_BONE_TEXTURE\n" : "", count);
    const char *v[8] = {defines, library}, *f[8] = {defines, library};
    for (int i = 0; i < vs_n; ++i) v[2 + i] = vs[i];
    for (int i = 0; i < fs_n; ++i) f[2 + i] = fs[i];
    GLuint prog = glCreateProgram();
    glAttachShader(prog, bench_shader(GL_VERTEX_SHADER, v, 2 + vs_n));
    glAttachShader(prog, fs_n ? bench_shader(GL_FRAGMENT_SHADER, f, 2 + fs_n) : bench_shader(GL_FRAGMENT_SHADER, &FRAGMENT, 1));
    const char *attrs[] = {"a_position", "a_normal", "a_joints", "a_weights", "a_place", "a_inst", "a_bone_instance"};
    for (GLuint a = 0; a < 7; ++a) glBindAttribLocation(prog, a, attrs[a]);
    glLinkProgram(prog);
    GLint ok;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) bench_die("a program does not link");
    return prog;
}

/* ---- textures ---- */

typedef struct scene {
    const cb_palette *pal, *pass_pal; /* pass_pal: what the bone pass reads (--local-rows: local rows), else pal */
    const cb_vat *vat;
    const float *bone_meta; /* cb_bind_positions rows 2 and 3 (8 floats a bone): row 2's w the parent (bench_gl_local.h) */
    GLuint pass_tex, palette_tex, bind_tex, vat_pos, vat_nrm, bone_tex[3], bone_fbo, bone_rows, bone_width;
    GLuint prog[METHODS], tier_prog[3], pass, vao, pass_vao, instance_vbo, tier_vbo;
    GLsizei index_count;
    bool lod; /* --lod: the bone pass's animation LOD, as the WebGL2 Crowd's default (lod 'auto') */
    bool pass_only; /* --pass-only: `bones` times the bone pass alone (no draw) */
    bool tiers; /* its tiers drawn apart (tier_prog), not found per vertex (prog[1]; --lod-single) */
    float lod_pixels[2]; /* its thresholds: 1 influence under [0] pixels tall, 2 under [1] (bench_lod_thresholds) */
    float *instances; /* the herd's 8 floats an instance (place, inst), kept for the tiers' sort */
    int32_t *order;   /* the instances by tier, a frame's (bench_sort_by_tier) */
    cb_sampler *sampler;
} scene;

static void upload_palette(scene *s)
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
    float *rgba = calloc((size_t)p->bone_count * 16, sizeof(float)); /* row 0: bind positions; 1: position offsets; 2, 3 */
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        memcpy(rgba + j * 4, p->bind_positions + j * 3, 3 * sizeof(float));
        if (p->positions_relative) memcpy(rgba + (p->bone_count + j) * 4, p->position_offsets + j * 3, 3 * sizeof(float));
    }
    memcpy(rgba + p->bone_count * 8, s->bone_meta, p->bone_count * 8 * sizeof(float));
    s->bind_tex = bench_texture(GL_RGBA32F, (GLsizei)p->bone_count, 4, GL_RGBA, GL_FLOAT, rgba);
    free(rgba);
    s->vat_pos = bench_texture(GL_RGBA16F, (GLsizei)s->vat->geometry.width, (GLsizei)s->vat->geometry.height, GL_RGBA,
                         GL_HALF_FLOAT, s->vat->positions);
    s->vat_nrm = bench_texture(GL_RGBA16F, (GLsizei)s->vat->geometry.width, (GLsizei)s->vat->geometry.height, GL_RGBA,
                         GL_HALF_FLOAT, s->vat->normals);
}

/* The bone pass's three RGBA32F targets for `capacity` instances, in column blocks of the texture limit. */
static void bone_targets(scene *s, uint32_t capacity)
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
static float herd_size(const cb_palette *p)
{
    float size = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c)
        for (int k = 0; k < 3; ++k) size = fmaxf(size, p->clips[c].bounds_max[k] - p->clips[c].bounds_min[k]);
    return size;
}

/* ---- the mesh: every primitive of the first skin, in the VAT's vertex order ---- */

static void upload_mesh(scene *s, const cb_model *m, uint32_t capacity)
{
    uint32_t verts = 0, indices = 0;
    for (uint32_t i = 0; i < m->primitive_count; ++i)
        if (m->primitives[i].skin == 0) verts += m->primitives[i].vertex_count, indices += m->primitives[i].index_count;
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
        for (uint32_t k = 0; k < p->index_count; ++k) idx[i0 + k] = v0 + p->indices[k];
        v0 += p->vertex_count, i0 += p->index_count;
    }
    bench_sort_influences(j, w, verts); /* as the WebGL2 Crowd: every method draws the same order */
    if (s->lod) /* as lod 'auto' of the runtimes: where the worst vertex of 64 poses moves at most a pixel */
        bench_lod_thresholds(s->sampler, s->pal, pos, j, w, verts, herd_size(s->pal), 1.0, 64, s->lod_pixels);
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

static void draw(const scene *s, int method, uint32_t n, float time, const float *view_projection, GLuint target)
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
    float lod[3] = {herd_size(s->pal) * 0.5f * HEIGHT * hypotf(hypotf(view_projection[1], view_projection[5]), view_projection[9]),
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
static void place_herd(const scene *s, uint32_t n, float view_projection[16])
{
    const cb_palette *p = s->pal;
    const cb_palette_clip *clip = &p->clips[0];
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].loops) { clip = &p->clips[c]; break; }
    float size = herd_size(p);
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

/* ---- the offscreen target, timing and the image check ---- */

static int by_value(const void *a, const void *b) { return (*(const double *)a > *(const double *)b) - (*(const double *)a < *(const double *)b); }

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

/* The process's CPU time (ms): llvmpipe rasterises on this process's threads, and on a machine shared
 * with other work a frame's CPU time is its own where its wall time is also the others' load. */
static double cpu_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

/* Milliseconds of one frame on the GPU, as GL_TIME_ELAPSED measures from the clear to the draw's end; *wall:
 * from the clear's call to glFinish's return (llvmpipe rasterizes at the flush, which its query may leave out). */
static double timed_frame(const scene *s, int method, uint32_t n, float time, const float *vp, GLuint target, double *wall,
                          double *cpu)
{
    GLuint q;
    GLuint64 ns = 0;
    glGenQueries(1, &q);
    double t0 = now_ms(), c0 = cpu_ms();
    glBeginQuery(GL_TIME_ELAPSED, q);
    draw(s, method, n, time, vp, target);
    glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    *wall = now_ms() - t0, *cpu = cpu_ms() - c0;
    glGetQueryObjectui64v(q, GL_QUERY_RESULT, &ns);
    glDeleteQueries(1, &q);
    return ns / 1e6;
}

static void bench_counts(const scene *s, const char *counts, int frames, GLuint target)
{
    printf("{\"renderer\": \"%s\", \"version\": \"%s\", \"vertices\": %llu, \"palette_bytes\": %llu, \"vat_bytes\": %llu, "
           "\"frames\": %d, \"lod_two_pixels\": %.1f, \"lod_one_pixels\": %.1f, \"counts\": {", (const char *)glGetString(GL_RENDERER),
           (const char *)glGetString(GL_VERSION),
           (unsigned long long)s->vat->vertices, (unsigned long long)s->pal->width * s->pal->height * 8,
           (unsigned long long)s->vat->geometry.width * s->vat->geometry.height * 16, frames, s->lod ? s->lod_pixels[1] : 0.0,
           s->lod ? s->lod_pixels[0] : 0.0);
    const char *c = counts;
    for (int first = 1; *c; first = 0) {
        uint32_t n = (uint32_t)strtoul(c, (char **)&c, 10);
        if (*c == ',') ++c;
        float vp[16];
        place_herd(s, n, vp);
        double ms[METHODS][64], wall[METHODS][64], cpu[METHODS][64], w, u;
        for (int f = -1; f < frames && f < 64; ++f) /* frame -1 warms up (shader compile, upload) */
            for (int k = 0; k < METHODS; ++k) {
                int m = f % 2 ? k : METHODS - 1 - k; /* in turns: a b c, c b a, ... */
                double t = timed_frame(s, m, n, 0.5f + (float)f / 30, vp, target, &w, &u);
                if (f >= 0) ms[m][f] = t, wall[m][f] = w, cpu[m][f] = u;
            }
        printf("%s\"%u\": {", first ? "" : ", ", n);
        double pair[2][64]; /* frame f's VAT time over each method's: pairs the same moment's load hit alike */
        for (int k = 0; k < 4; ++k) {
            double (*t)[64] = k < 2 ? wall : cpu;
            for (int f = 0; f < frames; ++f) pair[k % 2][f] = t[2][f] / t[k % 2][f];
            qsort(pair[k % 2], (size_t)frames, sizeof(double), by_value);
            printf("\"%svat_over_%s\": %.4f, ", k < 2 ? "" : "cpu_", (k % 2 == 1 && s->lod ? "lod" : method_names[k % 2]), pair[k % 2][frames / 2]);
        }
        for (int m = 0; m < METHODS; ++m) {
            const char *name = m == 1 && s->lod ? "lod" : method_names[m];
            qsort(ms[m], (size_t)frames, sizeof(double), by_value);
            qsort(wall[m], (size_t)frames, sizeof(double), by_value);
            qsort(cpu[m], (size_t)frames, sizeof(double), by_value);
            printf("%s\"%s_ms\": %.3f, \"%s_min_ms\": %.3f, \"%s_wall_ms\": %.3f", m ? ", " : "", name,
                   ms[m][frames / 2], name, ms[m][0], name, wall[m][frames / 2]);
            printf(", \"%s_cpu_ms\": %.3f", name, cpu[m][frames / 2]);
        }
        printf("}");
        fflush(stdout);
    }
    printf("}}\n");
}

/* The LOD's tiers drawn apart against one draw finding each vertex's tier (the same decision: thresholds that put a
 * third of the 16 instances on each tier, far from any of them): the bytes of the two images that differ (*bytes, 0
 * for the same image), and the share of pixels where the LOD's image differs from every influence's (`all`). */
static double check_tiers(const scene *s, GLuint target, const float *vp, const unsigned char *all, long *bytes)
{
    scene t = *s;
    float lod[3] = {herd_size(s->pal) * 0.5f * HEIGHT * hypotf(hypotf(vp[1], vp[5]), vp[9]), 0, 0};
    bench_split_tiers(s->instances, 8, 16, vp, lod);
    t.lod = true, t.lod_pixels[1] = lod[1], t.lod_pixels[0] = lod[2];
    unsigned char *img[2];
    for (int k = 0; k < 2; ++k) {
        t.tiers = k == 1;
        img[k] = malloc((size_t)WIDTH * HEIGHT * 4);
        draw(&t, 1, 16, 0.77f, vp, target);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, target);
        glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, img[k]);
    }
    *bytes = 0;
    for (size_t i = 0; i < (size_t)WIDTH * HEIGHT * 4; ++i) *bytes += img[0][i] != img[1][i];
    bench_tiers tiers;
    bench_sort_by_tier(s->instances, 8, 16, vp, lod, s->order, &tiers);
    long covered;
    double vs_all = bench_image_difference(all, img[1], WIDTH, HEIGHT, &covered);
    printf("the LOD's tiers (%u / %u / %u instances on 1 / 2 / 4 influences, under %.1f / %.1f pixels tall) drawn apart vs "
           "in one draw: %ld bytes differ; vs every influence %.4f of the pixels differ\n", tiers.count[0], tiers.count[1],
           tiers.count[2], lod[2], lod[1], *bytes, vs_all);
    free(img[0]), free(img[1]);
    return vs_all;
}

/* 16 instances drawn by each method at the same time must give the same image; the VAT a
 * quarter second later (a runtime playing the wrong rows) must not. */
static int check_images(const scene *s, GLuint target)
{
    unsigned char *img[METHODS + 1];
    float vp[16];
    place_herd(s, 16, vp);
    for (int m = 0; m <= METHODS; ++m) {
        img[m] = malloc((size_t)WIDTH * HEIGHT * 4);
        draw(s, m < METHODS ? m : 2, 16, m < METHODS ? 0.77f : 0.77f + 0.25f, vp, target);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, target);
        glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, img[m]);
    }
    long covered;
    double late = bench_image_difference(img[0], img[3], WIDTH, HEIGHT, &covered), bones = bench_image_difference(img[0], img[1], WIDTH, HEIGHT, &covered),
           vat = bench_image_difference(img[0], img[2], WIDTH, HEIGHT, &covered);
    printf("16 instances on %s, %ld pixels covered: palette vs bone pass %.4f, palette vs VAT %.4f of the pixels differ; "
           "the VAT 0.25 s late %.4f\n", (const char *)glGetString(GL_RENDERER), covered, bones, vat, late);
    long tier_bytes = 0;
    double tiers_vs_all = check_tiers(s, target, vp, img[1], &tier_bytes);
    for (int m = 0; m <= METHODS; ++m) free(img[m]);
    bool ok = covered > 1000 && bones <= 0.01 && vat <= 0.01 && late > 0.05 && tier_bytes == 0 && tiers_vs_all > 0 &&
              glGetError() == GL_NO_ERROR;
    if (!ok) fprintf(stderr, "bench_gl: the images disagree (limits: 0.01 alike, > 0.05 0.25 s late, the LOD's tiers drawn "
                             "apart the same bytes as in one draw, some pixels off every influence's)\n");
    return ok ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc < 3) bench_die("usage: bench_gl MODEL.glb N1,N2,... [--frames K] [--lod | --lod-single] [--local-rows] [--pass-only] | bench_gl MODEL.glb --check");
    bool check = !strcmp(argv[2], "--check");
    int frames = argc > 4 && !strcmp(argv[3], "--frames") ? atoi(argv[4]) : 5;
    if (frames < 1 || frames > 64) bench_die("--frames: 1 to 64");
    cb_error err = {0};
    cb_model *model = cb_gltf_load(argv[1], NULL, &err);
    cb_sampler *sampler = model ? cb_sampler_create(model, 0, &err) : NULL;
    cb_bake_options o = cb_default_bake_options();
    o.root_motion = CB_ROOT_MOTION_IN_PLACE;
    cb_palette pal;
    cb_vat vat;
    if (!sampler || cb_palette_bake(sampler, &o, NULL, 0, &pal, &err) != CB_OK ||
        cb_vat_bake(sampler, &o, NULL, 0, true, &vat, &err) != CB_OK) {
        fprintf(stderr, "bench_gl: %s\n", err.message);
        return 1;
    }
    bench_open_context();
    uint32_t capacity = 16;
    for (const char *c = argv[2]; !check && *c; ++c)
        if (*c >= '0' && *c <= '9') {
            uint32_t n = (uint32_t)strtoul(c, (char **)&c, 10);
            capacity = n > capacity ? n : capacity;
            if (!*c) break;
        }
    scene s = {.pal = &pal, .pass_pal = &pal, .vat = &vat, .sampler = sampler, .tiers = true};
    int32_t *parents = malloc(pal.bone_count * 4);
    float *meta = calloc(pal.bone_count * 8, sizeof(float));
    bench_joint_parents(model, 0, parents, meta); /* and the chains' depths, on stderr */
    s.bone_meta = meta;
    cb_palette local = {0};
    for (int a = 3; a < argc; ++a) {
        if (!strcmp(argv[a], "--local-rows") && !local.texels) bench_local_palette(&pal, parents, &local, meta), s.pass_pal = &local;
        s.lod |= !strcmp(argv[a], "--lod") || !strcmp(argv[a], "--lod-single");
        s.tiers &= strcmp(argv[a], "--lod-single") != 0;
        s.pass_only |= !strcmp(argv[a], "--pass-only");
    }
    s.instances = malloc((size_t)capacity * 32), s.order = malloc((size_t)capacity * 4);
    upload_palette(&s);
    bone_targets(&s, capacity);
    upload_mesh(&s, model, capacity);
    const char *skins[METHODS] = {SKIN_PALETTE, SKIN_BONES, SKIN_VAT};
    const char *bones_path = getenv("BENCH_GL_BONES_GLSL"); /* another library for the bone pass and its draw: weighs a change */
    char *bones_glsl = bones_path ? bench_read_text(bones_path) : NULL;
    if (bones_path && !bones_glsl) bench_die("BENCH_GL_BONES_GLSL: cannot read that file (a GLSL library in place of the shipped one)");
    const char *bones_lib = bones_glsl ? bones_glsl : cb_palette_glsl;
    for (int m = 0; m < METHODS; ++m) {
        const char *vs[3] = {MAIN_HEAD, skins[m], MAIN_TAIL};
        s.prog[m] = program(m == 1 ? bones_lib : cb_palette_glsl, &pal, m == 1, 0, vs, m == 1 ? 2 : 3, NULL, 0);
    }
    const char *tier_vs[2] = {MAIN_HEAD, SKIN_TIER};
    for (int k = 0; k < 3; ++k) s.tier_prog[k] = program(bones_lib, &pal, true, 1 << k, tier_vs, 2, NULL, 0);
    const char *pass_path = getenv("BENCH_GL_PASS_GLSL"); /* another fragment main for the bone pass */
    char *pass_glsl = pass_path ? bench_read_text(pass_path) : NULL;
    if (pass_path && !pass_glsl) bench_die("BENCH_GL_PASS_GLSL: cannot read that file (a bone pass's fragment main)");
    const char *pass_fragment = pass_glsl ? pass_glsl : PASS_FRAGMENT;
    s.pass = program(bones_lib, s.pass_pal, false, 0, &PASS_VERTEX, 1, &pass_fragment, 1);
    free(bones_glsl), free(pass_glsl);
    GLuint target = bench_offscreen_target(WIDTH, HEIGHT);
    int rc = check ? check_images(&s, target) : (bench_counts(&s, argv[2], frames, target), 0);
    free(s.instances), free(s.order), free(parents), free(meta), free(local.texels);
    cb_vat_free(&vat);
    cb_palette_free(&pal);
    cb_sampler_free(sampler);
    cb_model_free(model);
    return rc;
}
