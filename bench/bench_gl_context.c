/* bench_gl_context.c - see bench_gl_context.h. */
#define GL_GLEXT_PROTOTYPES
#include "bench_gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void bench_die(const char *what)
{
    fprintf(stderr, "bench_gl: %s\n", what);
    exit(1);
}

/* EGL's first device that is a GPU (not Mesa's software one), else its first; NULL when it lists none. */
static EGLDeviceEXT first_device(void)
{
    PFNEGLQUERYDEVICESEXTPROC query_devices = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
    PFNEGLQUERYDEVICESTRINGEXTPROC query_string =
        (PFNEGLQUERYDEVICESTRINGEXTPROC)eglGetProcAddress("eglQueryDeviceStringEXT");
    EGLDeviceEXT devices[8];
    EGLint n = 0;
    if (!query_devices || !query_string || !query_devices(8, devices, &n) || !n) return NULL;
    for (EGLint i = 0; i < n; ++i) {
        const char *ext = query_string(devices[i], EGL_EXTENSIONS);
        if (!ext || !strstr(ext, "EGL_MESA_device_software")) return devices[i];
    }
    return devices[0];
}

/* An OpenGL 3.3 core context without a surface: EGL's device platform when it has one (a GPU's
 * driver, or Mesa's llvmpipe), else the default display (Mesa with EGL_PLATFORM=surfaceless,
 * which also skips the devices). */
void bench_open_context(void)
{
    EGLDisplay dpy = EGL_NO_DISPLAY;
    PFNEGLGETPLATFORMDISPLAYEXTPROC platform_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    EGLDeviceEXT device = getenv("EGL_PLATFORM") || !platform_display ? NULL : first_device();
    if (device) dpy = platform_display(EGL_PLATFORM_DEVICE_EXT, device, NULL);
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, NULL, NULL)) {
        dpy = eglGetDisplay(EGL_DEFAULT_DISPLAY);
        if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, NULL, NULL)) bench_die("no EGL display (Mesa: EGL_PLATFORM=surfaceless)");
    }
    const EGLint config_attrs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_NONE};
    EGLConfig config;
    EGLint configs = 0;
    if (!eglChooseConfig(dpy, config_attrs, &config, 1, &configs) || !configs) bench_die("no EGL config for desktop OpenGL");
    if (!eglBindAPI(EGL_OPENGL_API)) bench_die("EGL cannot bind desktop OpenGL");
    const EGLint ctx_attrs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3, EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, ctx_attrs);
    if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx))
        bench_die("no OpenGL 3.3 core context without a surface (EGL_KHR_surfaceless_context)");
}

GLuint bench_shader(GLenum type, const char *const *parts, int n)
{
    GLuint s = glCreateShader(type);
    glShaderSource(s, n, parts, NULL);
    glCompileShader(s);
    GLint ok;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        fprintf(stderr, "bench_gl: a shader does not compile: %s\n", log);
        exit(1);
    }
    return s;
}

GLuint bench_texture(GLint internal, GLsizei w, GLsizei h, GLenum format, GLenum type, const void *data)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, type, data);
    return t;
}

GLuint bench_offscreen_target(int width, int height)
{
    GLuint fbo, rb[2];
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenRenderbuffers(2, rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) bench_die("the offscreen target is not renderable");
    return fbo;
}
