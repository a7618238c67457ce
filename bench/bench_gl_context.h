/* bench_gl_context.h - bench_gl.c's OpenGL plumbing: an OpenGL 3.3 core context through EGL without a window (a
 * GPU's driver through EGL's device platform, Mesa's llvmpipe with EGL_PLATFORM=surfaceless), shaders, textures and
 * the offscreen target. Each failure ends the process with one line (bench_die). */
#ifndef CROWDBAKE_BENCH_GL_CONTEXT_H
#define CROWDBAKE_BENCH_GL_CONTEXT_H

#include <GL/gl.h>
#include <GL/glext.h>

/* "bench_gl: WHAT" on stderr, exit 1. */
void bench_die(const char *what);

/* Makes an OpenGL 3.3 core context current, without a surface. */
void bench_open_context(void);

/* A shader of the n source parts, compiled (its log on stderr when it does not). */
GLuint bench_shader(GLenum type, const char *const *parts, int n);

/* A 2D texture, nearest filtering, data as given (NULL: storage only). */
GLuint bench_texture(GLint internal, GLsizei w, GLsizei h, GLenum format, GLenum type, const void *data);

/* A framebuffer of width x height: RGBA8 colour, 24-bit depth. */
GLuint bench_offscreen_target(int width, int height);

#endif
