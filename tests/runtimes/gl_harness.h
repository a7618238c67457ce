/* gl_harness.h - the GL tests' harness: an OSMesa context (Mesa's llvmpipe, no GPU), the shipped
 * GLSL compiled into a transform-feedback program, a palette uploaded as the runtimes upload it, and
 * a way to break one line of the shader on purpose. Header-only, like testutil.h. */
#ifndef CROWDBAKE_TEST_GL_HARNESS_H
#define CROWDBAKE_TEST_GL_HARNESS_H

#include "testutil.h"
#include "runtimes/shader_source.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include "crowdbake/palette.h"
#include "crowdbake/runtime.h" /* cb_bind_texels */

#define GLSL_PATH "runtimes/glsl/crowdbake_palette.glsl"

static OSMesaContext ctx; /* the tests' one context, made by setup */
static unsigned char framebuffer[16 * 16 * 4];

static inline int setup(void **state)
{
    (void)state;
    const int attrs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                         OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    ctx = OSMesaCreateContextAttribs(attrs, NULL);
    if (!ctx || !OSMesaMakeCurrent(ctx, framebuffer, GL_UNSIGNED_BYTE, 16, 16)) return -1;
    printf("  %s on %s\n", (const char *)glGetString(GL_VERSION), (const char *)glGetString(GL_RENDERER));
    return 0;
}

static inline int teardown(void **state)
{
    (void)state;
    OSMesaDestroyContext(ctx);
    return 0;
}


/* Compiles and links a vertex shader (with a do-nothing fragment shader) that writes v_skinned. */
static inline GLuint link_program(const char *src, bool es)
{
    const char *fs_src = es ? "#version 300 es\nprecision mediump float;\nout vec4 c; void main() { c = vec4(1.0); }\n"
                            : "#version 330 core\nout vec4 c; void main() { c = vec4(1.0); }\n";
    GLuint vs = glCreateShader(GL_VERTEX_SHADER), fs = glCreateShader(GL_FRAGMENT_SHADER), prog = glCreateProgram();
    glShaderSource(vs, 1, &src, NULL);
    glCompileShader(vs);
    glShaderSource(fs, 1, &fs_src, NULL);
    glCompileShader(fs);
    GLint ok;
    char log[4096];
    glGetShaderiv(vs, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        glGetShaderInfoLog(vs, sizeof log, NULL, log);
        fail_msg("%s shader does not compile: %s", es ? "ES 3.00" : "330 core", log);
    }
    glAttachShader(prog, vs);
    glAttachShader(prog, fs);
    const char *varyings[] = {"v_skinned"};
    glTransformFeedbackVaryings(prog, 1, varyings, GL_INTERLEAVED_ATTRIBS);
    glBindAttribLocation(prog, 0, "a_position");
    glBindAttribLocation(prog, 1, "a_joints");
    glBindAttribLocation(prog, 2, "a_weights");
    glBindAttribLocation(prog, 3, "a_instance");
    glBindAttribLocation(prog, 4, "a_time");
    glBindAttribLocation(prog, 5, "a_instance_id");
    glLinkProgram(prog);
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(prog, sizeof log, NULL, log);
        fail_msg("does not link: %s", log);
    }
    glDeleteShader(vs);
    glDeleteShader(fs);
    return prog;
}

static inline GLuint compile(const cb_palette *p, const char *library, bool es)
{
    static char src[1 << 16];
    snprintf(src, sizeof src,
             "%s\n#define %s\n#define %s\n%s%s\n"
             "in vec3 a_position; in ivec4 a_joints; in vec4 a_weights; in vec4 a_instance; in float a_time;\n"
             "out vec3 v_skinned;\n"
             "void main() { v_skinned = cb_skin_position(a_position, a_joints, a_weights, a_instance, a_time); "
             "gl_Position = vec4(0.0); }\n",
             es ? "#version 300 es" : "#version 330 core", layout_define[p->layout], precision_define[p->precision],
             p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "", library);
    return link_program(src, es);
}

/* The palette's texels as a texture, optionally with every mat4 bone transposed. */
static inline GLuint upload(const cb_palette *p, bool transpose)
{
    GLuint tex;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    const void *data = p->texels;
    float *t = NULL;
    if (transpose) { /* the reference runtime's shipped bug: rows stored where columns belong */
        t = malloc(p->texel_bytes);
        memcpy(t, p->texels, p->texel_bytes);
        for (size_t b = 0; b + 16 <= p->texel_bytes / 4; b += 16)
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) t[b + r * 4 + c] = ((const float *)p->texels)[b + c * 4 + r];
        data = t;
    }
    if (p->precision == CB_PRECISION_FLOAT)
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, (GLsizei)p->width, (GLsizei)p->height, 0, GL_RGBA, GL_FLOAT, data);
    else if (p->precision == CB_PRECISION_HALF)
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, (GLsizei)p->width, (GLsizei)p->height, 0, GL_RGBA, GL_HALF_FLOAT, data);
    else
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16UI, (GLsizei)p->width, (GLsizei)p->height, 0, GL_RGBA_INTEGER,
                     GL_UNSIGNED_SHORT, data);
    free(t);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    return tex;
}

/* cb_bind_positions, as cb_bind_texels lays it out (local rows: 5 rows). */
static inline GLuint upload_bind_positions(const cb_palette *p)
{
    uint32_t n = p->bone_count, rows = cb_bind_texels(p, NULL);
    float *rgba = malloc((size_t)n * rows * 4 * sizeof(float));
    cb_bind_texels(p, rgba);
    GLuint tex;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, (GLsizei)n, (GLsizei)rows, 0, GL_RGBA, GL_FLOAT, rgba);
    free(rgba);
    return tex;
}

/* Binds the palette texture (and qpos's bind positions) and the header's uniforms to prog;
 * tex[0], tex[1] (0 when none) are the textures to delete after the draw. */
static inline void use_palette(const cb_palette *p, GLuint prog, bool transpose, GLuint tex[2])
{
    glActiveTexture(GL_TEXTURE0);
    tex[0] = upload(p, transpose), tex[1] = 0;
    glUseProgram(prog);
    if (p->layout == CB_LAYOUT_QPOS || p->positions_relative) {
        glActiveTexture(GL_TEXTURE1);
        tex[1] = upload_bind_positions(p); /* uploading binds it to the active unit: 1 */
        glUniform1i(glGetUniformLocation(prog, "cb_bind_positions"), 1);
    }
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, tex[0]);
    glUniform1i(glGetUniformLocation(prog, "cb_palette"), 0);
    glUniform1i(glGetUniformLocation(prog, "cb_row_texels"), (GLint)p->row_texels);
    glUniform1i(glGetUniformLocation(prog, "cb_rows_per_block"), (GLint)p->height);
    glUniform3fv(glGetUniformLocation(prog, "cb_bounds_min"), 1, p->bounds_min);
    glUniform3fv(glGetUniformLocation(prog, "cb_bounds_max"), 1, p->bounds_max);
    glUniform1f(glGetUniformLocation(prog, "cb_linear_range"), p->linear_range);
}

#endif
