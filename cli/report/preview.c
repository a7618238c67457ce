/* preview.c - see preview.h. */
#define GL_GLEXT_PROTOTYPES /* for the prototypes gl_api takes its types from; nothing links them */
#include "report/preview.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <dlfcn.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "crowdbake/runtime.h"
#include "internal/atomic_file.h"
#include "font.h"

/* OpenGL through Mesa's OSMesa, opened when a preview is drawn: linking it would load Mesa and
 * LLVM (~20 ms of dynamic linking) into every crowdbake run. */
#define CB_GL_FUNCTIONS(X) \
    X(ActiveTexture) \
    X(AttachShader) \
    X(BindAttribLocation) \
    X(BindBuffer) \
    X(BindTexture) \
    X(BindVertexArray) \
    X(BufferData) \
    X(Clear) \
    X(ClearColor) \
    X(CompileShader) \
    X(CreateProgram) \
    X(CreateShader) \
    X(DeleteShader) \
    X(DrawArrays) \
    X(DrawElements) \
    X(Enable) \
    X(EnableVertexAttribArray) \
    X(Finish) \
    X(GenBuffers) \
    X(GenTextures) \
    X(GenVertexArrays) \
    X(GetError) \
    X(GetShaderInfoLog) \
    X(GetShaderiv) \
    X(GetUniformLocation) \
    X(LinkProgram) \
    X(PixelStorei) \
    X(ShaderSource) \
    X(TexImage2D) \
    X(TexParameteri) \
    X(Uniform1f) \
    X(Uniform1i) \
    X(Uniform3fv) \
    X(Uniform4fv) \
    X(UniformMatrix4fv) \
    X(UseProgram) \
    X(VertexAttribIPointer) \
    X(VertexAttribPointer) \
    X(Viewport)

typedef struct gl_api {
    void *library;
    __typeof__(&OSMesaCreateContextAttribs) CreateContextAttribs;
    __typeof__(&OSMesaMakeCurrent) MakeCurrent;
    __typeof__(&OSMesaDestroyContext) DestroyContext;
    __typeof__(&OSMesaGetProcAddress) GetProcAddress;
#define CB_GL_MEMBER(name) __typeof__(&gl##name) name;
    CB_GL_FUNCTIONS(CB_GL_MEMBER)
#undef CB_GL_MEMBER
} gl_api;

/* Resolves every entry point or none; `what` names the first one missing. */
static bool gl_open(gl_api *gl, const char **what)
{
    memset(gl, 0, sizeof *gl);
    *what = "libOSMesa.so.8";
    /* NODELETE: Mesa does not expect to be unloaded, and its few bytes kept past
     * OSMesaDestroyContext stay attributable to it (tests/lsan.supp). */
    gl->library = dlopen("libOSMesa.so.8", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!gl->library) return false;
#define CB_GL_SYMBOL(member, symbol) \
    if (!(*(void **)&gl->member = dlsym(gl->library, symbol))) return *what = symbol, false;
    CB_GL_SYMBOL(CreateContextAttribs, "OSMesaCreateContextAttribs")
    CB_GL_SYMBOL(MakeCurrent, "OSMesaMakeCurrent")
    CB_GL_SYMBOL(DestroyContext, "OSMesaDestroyContext")
    CB_GL_SYMBOL(GetProcAddress, "OSMesaGetProcAddress")
#define CB_GL_PROC(name) \
    if (!(*(void **)&gl->name = (void *)gl->GetProcAddress("gl" #name))) return *what = "gl" #name, false;
    CB_GL_FUNCTIONS(CB_GL_PROC)
#undef CB_GL_PROC
#undef CB_GL_SYMBOL
    return true;
}

static void gl_close(gl_api *gl)
{
    if (gl->library) dlclose(gl->library);
}

static const char *const layout_define[] = {"CB_LAYOUT_MAT4", "CB_LAYOUT_AFFINE", "CB_LAYOUT_QPOS"};
static const char *const precision_define[] = {"CB_PRECISION_FLOAT", "CB_PRECISION_HALF", "CB_PRECISION_U16"};

static GLuint shader(const gl_api *gl, GLenum type, const char *src, cb_error *err)
{
    GLuint s = gl->CreateShader(type);
    gl->ShaderSource(s, 1, &src, NULL);
    gl->CompileShader(s);
    GLint ok;
    gl->GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024];
        gl->GetShaderInfoLog(s, sizeof log, NULL, log);
        cb_fail(err, CB_ERR_INTERNAL, "the preview shader does not compile: %.400s", log);
    }
    return s;
}

static GLuint program(const gl_api *gl, const cb_palette *p, cb_error *err)
{
    size_t n = strlen(cb_palette_glsl) + 2048;
    char *vs = malloc(n);
    if (!vs) return cb_fail(err, CB_ERR_INTERNAL, "out of memory"), 0;
    snprintf(vs, n,
             "#version 330 core\n#define %s\n#define %s\n%s%s%s\n"
             "in vec3 a_position; in ivec4 a_joints; in vec4 a_weights;\n"
             "uniform vec4 u_instance; uniform float u_time; uniform mat4 u_view_projection;\nout vec3 v_world;\n"
             "void main() {\n  v_world = cb_skin_position(a_position, a_joints, a_weights, u_instance, u_time);\n"
             "  gl_Position = u_view_projection * vec4(v_world, 1.0);\n}\n",
             layout_define[p->layout], precision_define[p->precision],
             p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "",
             p->bone_space == CB_BONE_SPACE_LOCAL ? "#define CB_LOCAL_ROWS\n" : "", cb_palette_glsl);
    static const char fs[] = "#version 330 core\nin vec3 v_world; out vec4 color;\n"
                             "void main() {\n  vec3 n = normalize(cross(dFdx(v_world), dFdy(v_world)));\n"
                             "  float light = 0.35 + 0.65 * abs(dot(n, normalize(vec3(0.4, 0.8, 0.45))));\n"
                             "  color = vec4(vec3(0.85, 0.62, 0.38) * light, 1.0);\n}\n";
    GLuint v = shader(gl, GL_VERTEX_SHADER, vs, err), f = shader(gl, GL_FRAGMENT_SHADER, fs, err), prog = gl->CreateProgram();
    free(vs);
    gl->AttachShader(prog, v);
    gl->AttachShader(prog, f);
    gl->BindAttribLocation(prog, 0, "a_position");
    gl->BindAttribLocation(prog, 1, "a_joints");
    gl->BindAttribLocation(prog, 2, "a_weights");
    gl->LinkProgram(prog);
    gl->DeleteShader(v);
    gl->DeleteShader(f);
    return prog;
}

static GLuint texture(const gl_api *gl, GLenum internal, GLsizei w, GLsizei h, GLenum format, GLenum type, const void *data)
{
    GLuint t;
    gl->GenTextures(1, &t);
    gl->BindTexture(GL_TEXTURE_2D, t);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl->TexImage2D(GL_TEXTURE_2D, 0, (GLint)internal, w, h, 0, format, type, data);
    return t;
}

static void bind_palette(const gl_api *gl, const cb_palette *p, const void *texels, GLuint prog, GLuint *tex)
{
    gl->ActiveTexture(GL_TEXTURE1);
    uint32_t bind_rows = cb_bind_texels(p, NULL);
    float *bind = malloc((size_t)p->bone_count * bind_rows * 4 * sizeof(float));
    if (bind) cb_bind_texels(p, bind);
    tex[1] = texture(gl, GL_RGBA32F, (GLsizei)p->bone_count, (GLsizei)bind_rows, GL_RGBA, GL_FLOAT, bind);
    free(bind);
    gl->ActiveTexture(GL_TEXTURE0);
    if (p->precision == CB_PRECISION_FLOAT)
        tex[0] = texture(gl, GL_RGBA32F, (GLsizei)p->width, (GLsizei)p->height, GL_RGBA, GL_FLOAT, texels);
    else if (p->precision == CB_PRECISION_HALF)
        tex[0] = texture(gl, GL_RGBA16F, (GLsizei)p->width, (GLsizei)p->height, GL_RGBA, GL_HALF_FLOAT, texels);
    else
        tex[0] = texture(gl, GL_RGBA16UI, (GLsizei)p->width, (GLsizei)p->height, GL_RGBA_INTEGER, GL_UNSIGNED_SHORT, texels);
    gl->UseProgram(prog);
    gl->Uniform1i(gl->GetUniformLocation(prog, "cb_palette"), 0);
    gl->Uniform1i(gl->GetUniformLocation(prog, "cb_bind_positions"), 1);
    gl->Uniform1i(gl->GetUniformLocation(prog, "cb_row_texels"), (GLint)p->row_texels);
    gl->Uniform1i(gl->GetUniformLocation(prog, "cb_rows_per_block"), (GLint)p->height);
    gl->Uniform3fv(gl->GetUniformLocation(prog, "cb_bounds_min"), 1, p->bounds_min);
    gl->Uniform3fv(gl->GetUniformLocation(prog, "cb_bounds_max"), 1, p->bounds_max);
    gl->Uniform1f(gl->GetUniformLocation(prog, "cb_linear_range"), p->linear_range);
}

/* One VAO per primitive of the skin: positions, joints, weights and indices. */
static uint32_t upload_mesh(const gl_api *gl, const cb_model *m, int32_t skin, GLuint *vaos, GLsizei *counts, bool *indexed, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < m->primitive_count && n < cap; ++i) {
        const cb_primitive *prim = &m->primitives[i];
        if (prim->skin != skin) continue;
        GLuint vbo[4];
        gl->GenVertexArrays(1, &vaos[n]);
        gl->BindVertexArray(vaos[n]);
        gl->GenBuffers(4, vbo);
        int32_t *joints = malloc((size_t)prim->vertex_count * 4 * sizeof(int32_t));
        for (uint32_t k = 0; joints && k < prim->vertex_count * 4; ++k) joints[k] = prim->joints[k];
        gl->BindBuffer(GL_ARRAY_BUFFER, vbo[0]);
        gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)prim->vertex_count * 12, prim->positions, GL_STATIC_DRAW);
        gl->EnableVertexAttribArray(0);
        gl->VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, 0);
        gl->BindBuffer(GL_ARRAY_BUFFER, vbo[1]);
        gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)prim->vertex_count * 16, joints, GL_STATIC_DRAW);
        gl->EnableVertexAttribArray(1);
        gl->VertexAttribIPointer(1, 4, GL_INT, 0, 0);
        gl->BindBuffer(GL_ARRAY_BUFFER, vbo[2]);
        gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)prim->vertex_count * 16, prim->weights, GL_STATIC_DRAW);
        gl->EnableVertexAttribArray(2);
        gl->VertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 0, 0);
        free(joints);
        indexed[n] = prim->indices != NULL;
        counts[n] = (GLsizei)(indexed[n] ? prim->index_count : prim->vertex_count);
        if (indexed[n]) {
            gl->BindBuffer(GL_ELEMENT_ARRAY_BUFFER, vbo[3]);
            gl->BufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)prim->index_count * 4, prim->indices, GL_STATIC_DRAW);
        }
        ++n;
    }
    return n;
}

/* Center and radius of the skinned mesh at one time, skinned on the CPU the way the shader
 * does (src/runtime.c), so each cell is framed on the animal even when it travels. */
static void frame_bounds(const cb_palette *p, const void *texels, const cb_model *m, int32_t skin, const cb_instance *in,
                         double t, double center[3], double *radius)
{
    double *mats = malloc((size_t)p->bone_count * 16 * sizeof(double)), lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    if (!mats) return;
    cb_runtime_matrices(p, texels, in, t, mats);
    for (uint32_t i = 0; i < m->primitive_count; ++i) {
        const cb_primitive *prim = &m->primitives[i];
        double *pos = prim->skin == skin ? malloc((size_t)prim->vertex_count * 3 * sizeof(double)) : NULL;
        if (!pos) continue;
        cb_skin_positions(prim, mats, pos);
        for (uint32_t v = 0; v < prim->vertex_count * 3; ++v)
            lo[v % 3] = fmin(lo[v % 3], pos[v]), hi[v % 3] = fmax(hi[v % 3], pos[v]);
        free(pos);
    }
    free(mats);
    *radius = 0;
    for (int k = 0; k < 3; ++k) center[k] = 0.5 * (lo[k] + hi[k]), *radius += 0.25 * (hi[k] - lo[k]) * (hi[k] - lo[k]);
    *radius = isfinite(*radius) ? sqrt(*radius) : 1;
}

/* An orthographic three-quarter view of a sphere: column-major view-projection. */
static void camera(const double c[3], double r, float out[16])
{
    double d[3] = {0.75, 0.35, 0.56}, len = sqrt(0.75 * 0.75 + 0.35 * 0.35 + 0.56 * 0.56);
    for (int k = 0; k < 3; ++k) d[k] /= len;
    r = r * 1.05 + 1e-6;
    double up[3] = {0, 1, 0}, x[3] = {up[1] * d[2] - up[2] * d[1], up[2] * d[0] - up[0] * d[2], up[0] * d[1] - up[1] * d[0]};
    double xl = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (int k = 0; k < 3; ++k) x[k] /= xl;
    double y[3] = {d[1] * x[2] - d[2] * x[1], d[2] * x[0] - d[0] * x[2], d[0] * x[1] - d[1] * x[0]};
    /* rows of the view: x, y, d (looking along -d), scaled into [-1, 1] by the radius */
    for (int k = 0; k < 3; ++k) {
        out[k * 4 + 0] = (float)(x[k] / r);
        out[k * 4 + 1] = (float)(y[k] / r);
        out[k * 4 + 2] = (float)(-d[k] / r);
        out[k * 4 + 3] = 0;
    }
    double cx = x[0] * c[0] + x[1] * c[1] + x[2] * c[2], cy = y[0] * c[0] + y[1] * c[1] + y[2] * c[2];
    double cz = d[0] * c[0] + d[1] * c[1] + d[2] * c[2];
    out[12] = (float)(-cx / r), out[13] = (float)(-cy / r), out[14] = (float)(cz / r), out[15] = 1;
}

static cb_status write_png(const char *path, const unsigned char *rgba, uint32_t w, uint32_t h, cb_error *err)
{
    cb_atomic_file af;
    if (cb_atomic_open(&af, path, err)) return err->status;
    FILE *f = fdopen(af.fd, "wb");
    png_structp png = f ? png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL) : NULL;
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        if (png) png_destroy_write_struct(&png, &info);
        if (f) fclose(f), af.fd = -1;
        cb_atomic_abort(&af);
        return cb_fail(err, CB_ERR_IO, "%s: cannot write the PNG", path);
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (uint32_t y = 0; y < h; ++y) png_write_row(png, (png_const_bytep)(rgba + (size_t)(h - 1 - y) * w * 4)); /* GL is bottom-up */
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    if (fflush(f) != 0) {
        fclose(f), af.fd = -1;
        cb_atomic_abort(&af);
        return cb_fail(err, CB_ERR_IO, "%s: cannot write the PNG", path);
    }
    af.fd = dup(fileno(f));
    fclose(f);
    return cb_atomic_commit(&af, err);
}

/* Where a clip's row of cells starts, from the top. */
static uint32_t row_top(uint32_t clip, uint32_t cell) { return CB_PREVIEW_HEADER + clip * (CB_PREVIEW_BAND + cell) + CB_PREVIEW_BAND; }

/* The time of a clip's k-th cell: loops spread over a cycle, one-shots from first to last row. */
static double cell_time(const cb_palette_clip *clip, uint32_t k, uint32_t cols)
{
    cb_instance in = cb_instance_of(clip); /* a timed clip's steps are its map's cells, not its rows */
    double steps = fabs(in.frame_count), span = (clip->loops ? steps : steps - 1) / fabs(in.rate);
    return clip->loops ? span * k / cols : cols > 1 ? span * k / (cols - 1) : 0;
}

/* "0.0315", "3.66", "1220": three digits, never an exponent. */
static const char *millimetres(double v, char *buf, size_t size)
{
    snprintf(buf, size, v >= 100 ? "%.0f" : "%.3g", v);
    return buf;
}

/* The labels, drawn over the rendered sheet: what it is, each clip with its measured error
 * (at baked rows, and between them where blending adds its own), each cell's clip time. */
static cb_status draw_labels(cb_canvas *cv, const cb_palette *p, const void *texels, const cb_model *m, int32_t skin,
                             const cb_preview_options *opt, cb_error *err)
{
    static const uint8_t header_bg[3] = {52, 58, 64}, band_bg[3] = {214, 216, 208}, white[3] = {255, 255, 255},
                         ink[3] = {20, 20, 20}, faint[3] = {90, 90, 90}, warn[3] = {170, 0, 0};
    cb_font *bold = cb_font_open(14, true, err), *small = bold ? cb_font_open(11, false, err) : NULL;
    cb_sampler *s = small ? cb_sampler_create(m, skin, err) : NULL;
    if (!s) {
        cb_font_close(bold), cb_font_close(small);
        return err->status;
    }
    double lo[3], hi[3], height = cb_skin_rest_bounds(s, lo, hi), mm = height > 0 ? 1000 / height : 0;
    int w = (int)cv->width;
    char text[512];
    cb_canvas_fill(cv, 0, 0, w, CB_PREVIEW_HEADER, header_bg);
    int header_baseline = (CB_PREVIEW_HEADER + cb_font_ascent(bold) - cb_font_descent(bold)) / 2;
    char error[32];
    snprintf(text, sizeof text, "   %s/%s%s, %u bones, %u rows, baked error %s mm/m", cb_layout_name(p->layout),
             cb_precision_name(p->precision), p->bone_space == CB_BONE_SPACE_LOCAL ? " local rows" : "", p->bone_count,
             p->rows, millimetres(p->max_error * mm, error, sizeof error));
    int x = cb_font_draw(bold, cv, 8, header_baseline, w - 4, opt->title ? opt->title : "", white);
    cb_font_draw(small, cv, x, header_baseline, w - 4, text, white);
    for (uint32_t c = 0; c < p->clip_count && !err->status; ++c) {
        const cb_palette_clip *clip = &p->clips[c];
        int band = (int)(row_top(c, opt->cell) - CB_PREVIEW_BAND), baseline = band + (CB_PREVIEW_BAND + cb_font_ascent(bold)) / 2 - 1;
        cb_canvas_fill(cv, 0, band, w, CB_PREVIEW_BAND, band_bg);
        x = cb_font_draw(bold, cv, 8, baseline, w - 4, clip->name, ink);
        int32_t a = cb_model_find_animation(m, clip->name);
        cb_clip_error e;
        bool measured = a >= 0 && !cb_verify_clip(s, p, texels, c, a, 0, &e, err);
        char info[3][128] = {"", "", ""}, rows[2][64], between[2][64], q[32], b[32];
        if (clip->timed)
            snprintf(info[0], sizeof info[0], "   %s, %u rows on its keys, %.3g s", clip->loops ? "loop" : "one-shot",
                     clip->frames, clip->duration);
        else
            snprintf(info[0], sizeof info[0], "   %s, %u rows at %.3g fps, %.3g s", clip->loops ? "loop" : "one-shot",
                     clip->frames, clip->fps, clip->duration);
        snprintf(info[1], sizeof info[1], "   %s, %u rows", clip->loops ? "loop" : "one-shot", clip->frames);
        if (measured) {
            millimetres(e.quant_max * mm, q, sizeof q), millimetres(e.interp_max * mm, b, sizeof b);
            snprintf(rows[0], sizeof rows[0], "   error %s mm/m at rows", q), snprintf(between[0], sizeof between[0], ", %s between", b);
            snprintf(rows[1], sizeof rows[1], "   rows %s", q), snprintf(between[1], sizeof between[1], ", between %s", b);
        }
        /* The longest forms that fit, the errors kept longest (the unit is the header's) */
        static const int forms[4][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 1}}; /* info, errors */
        int fi = 0, fe = 0;
        for (int k = 0; k < 4; ++k) {
            fi = forms[k][0], fe = forms[k][1];
            int width = cb_font_width(small, info[fi]) + (measured ? cb_font_width(small, rows[fe]) + cb_font_width(small, between[fe]) : 0);
            if (x + width <= w - 4) break;
        }
        x = cb_font_draw(small, cv, x, baseline, w - 4, info[fi], faint);
        if (measured) { /* over 1 mm/m shows in red */
            x = cb_font_draw(small, cv, x, baseline, w - 4, rows[fe], e.quant_max * mm > 1 ? warn : ink);
            cb_font_draw(small, cv, x, baseline, w - 4, between[fe], e.interp_max * mm > 1 ? warn : ink);
        }
        for (uint32_t k = 0; k < opt->columns; ++k) {
            snprintf(text, sizeof text, "%.2f s", cell_time(clip, k, opt->columns));
            int cx = (int)(k * opt->cell);
            cb_font_draw(small, cv, cx + 4, (int)row_top(c, opt->cell) + 3 + cb_font_ascent(small), cx + (int)opt->cell - 2,
                         text, faint);
        }
    }
    cb_sampler_free(s);
    cb_font_close(bold);
    cb_font_close(small);
    return err->status;
}

cb_status cb_preview_write(const cb_palette *p, const void *texels, const cb_model *m, int32_t skin,
                           const cb_preview_options *opt, const char *png_path, cb_error *err)
{
    uint32_t cols = opt->columns, cell = opt->cell, w = cols * cell, h = row_top(p->clip_count, cell) - CB_PREVIEW_BAND;
    if (!cols || !cell || w > 8192 || h > 8192)
        return cb_fail(err, CB_ERR_SETTINGS, "a contact sheet of %ux%u pixels is out of range (1..8192)", w, h);
    const int attrs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    gl_api api, *gl = &api;
    const char *missing;
    if (!gl_open(gl, &missing)) {
        gl_close(gl);
        return cb_fail(err, CB_ERR_INTERNAL, "preview needs Mesa's OSMesa: %s not found (install libosmesa6)", missing);
    }
    OSMesaContext ctx = gl->CreateContextAttribs(attrs, NULL);
    unsigned char *pixels = malloc((size_t)w * h * 4);
    if (!ctx || !pixels || !gl->MakeCurrent(ctx, pixels, GL_UNSIGNED_BYTE, (GLsizei)w, (GLsizei)h)) {
        free(pixels);
        if (ctx) gl->DestroyContext(ctx);
        gl_close(gl);
        return cb_fail(err, CB_ERR_INTERNAL, "no OpenGL 3.3 context from OSMesa (Mesa's libosmesa6)");
    }
    GLuint prog = program(gl, p, err), tex[2] = {0, 0}, vaos[64];
    GLsizei counts[64];
    bool indexed[64];
    if (!err->status) {
        bind_palette(gl, p, texels, prog, tex);
        uint32_t prims = upload_mesh(gl, m, skin, vaos, counts, indexed, 64);
        gl->Enable(GL_DEPTH_TEST);
        gl->ClearColor(0.93f, 0.93f, 0.9f, 1);
        gl->Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        double *centers = malloc((size_t)cols * 3 * sizeof(double));
        for (uint32_t c = 0; centers && c < p->clip_count; ++c) {
            const cb_palette_clip *clip = &p->clips[c];
            cb_instance in = cb_instance_of(clip);
            float inst[4] = {(float)in.first_row, (float)in.frame_count, (float)in.rate, 0};
            gl->Uniform4fv(gl->GetUniformLocation(prog, "u_instance"), 1, inst);
            double radius = 0;
            for (uint32_t k = 0; k < cols; ++k) { /* one scale for the row, a center per frame */
                double r = 0;
                frame_bounds(p, texels, m, skin, &in, cell_time(clip, k, cols), centers + k * 3, &r);
                radius = fmax(radius, r);
            }
            for (uint32_t k = 0; k < cols; ++k) {
                double t = cell_time(clip, k, cols);
                float vp[16];
                camera(centers + k * 3, radius, vp);
                gl->UniformMatrix4fv(gl->GetUniformLocation(prog, "u_view_projection"), 1, GL_FALSE, vp);
                gl->Uniform1f(gl->GetUniformLocation(prog, "u_time"), (float)t);
                gl->Viewport((GLint)(k * cell), (GLint)(h - row_top(c, cell) - cell), (GLsizei)cell, (GLsizei)cell); /* GL: bottom-up */
                for (uint32_t i = 0; i < prims; ++i) {
                    gl->BindVertexArray(vaos[i]);
                    if (indexed[i]) gl->DrawElements(GL_TRIANGLES, counts[i], GL_UNSIGNED_INT, 0);
                    else gl->DrawArrays(GL_TRIANGLES, 0, counts[i]);
                }
            }
        }
        free(centers);
        gl->Finish();
        if (gl->GetError() != GL_NO_ERROR) cb_fail(err, CB_ERR_INTERNAL, "OpenGL failed while rendering the preview");
    }
    cb_canvas canvas = {pixels, w, h, true};
    if (!err->status) draw_labels(&canvas, p, texels, m, skin, opt, err);
    if (!err->status) write_png(png_path, pixels, w, h, err);
    gl->DestroyContext(ctx);
    gl_close(gl);
    free(pixels);
    return err->status;
}
