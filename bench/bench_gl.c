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
 * --local-rows: the palette baked with local rows (--bone-space local, bench_gl_local.h; the shipped GLSL with
 * CB_LOCAL_ROWS, the direct path and the bone pass walking each bone's chain); --pass-only: `bones` is the pass.
 *
 * The palette and the VAT are baked here from MODEL.glb alike (qpos/u16 and RGBA16F, 30 fps; --check 120, in
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
#include "bench_gl_check.h"
#include "bench_gl_local.h"
#include "bench_gl_mesh.h"
#include "bench_gl_scene.h"
#include "bench_gl_tiers.h"

/* runtimes/glsl/crowdbake_palette.glsl, embedded by the build (build/gen/palette_glsl.c). */
extern const char cb_palette_glsl[];

static const char *const method_names[METHODS] = {"palette", "bones", "vat"}; /* bones is "lod" with --lod */

/* ---- shaders: the shipped library, then a main ---- */

static const char *MAIN_HEAD =
    "in vec3 a_position; in vec3 a_normal; in ivec4 a_joints; in vec4 a_weights; in vec4 a_place; in vec4 a_inst;\n"
    "uniform float u_time; uniform mat4 u_view_projection;\n"
    "out vec3 v_normal; out vec3 v_world;\n";
static const char *MAIN_TAIL =
    "    float c = cos(a_place.w), s = sin(a_place.w);\n"
    "    mat3 yaw = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);\n"
    "    v_normal = yaw * n;\n"
    "    v_world = a_place.xyz + yaw * p;\n"
    "    gl_Position = u_view_projection * vec4(v_world, 1.0);\n"
    "}\n";
static const char *SKIN_PALETTE =
    "void main() {\n    vec3 p, n;\n"
    "    cb_skin_position_normal(a_position, a_normal, a_joints, a_weights, a_inst, u_time, p, n);\n";
static const char *SKIN_BONES = /* the pass placed each bone: world space straight away; --lod: the animation LOD */
    "uniform vec3 u_lod;\n" /* pixels tall at w = 1, the 2- and 1-influence thresholds (0: off) */
    "void main() {\n    vec3 p, n;\n    float pixels = u_lod.x / (u_view_projection * vec4(a_place.xyz, 1.0)).w;\n"
    "    cb_skin_bone_pass_influences(a_position, a_normal, a_joints, a_weights, gl_InstanceID,\n"
    "                                 cb_lod_influences(pixels, u_lod.y, u_lod.z), p, n);\n"
    "    v_normal = n, v_world = p;\n    gl_Position = u_view_projection * vec4(p, 1.0);\n}\n";
static const char *SKIN_TIER = /* one LOD tier, compiled in: a_bone_instance is the instance's row in the pass */
    "in int a_bone_instance;\n"
    "void main() {\n    vec3 p, n;\n"
    "    cb_skin_bone_pass(a_position, a_normal, a_joints, a_weights, a_bone_instance, p, n);\n"
    "    v_normal = n, v_world = p;\n    gl_Position = u_view_projection * vec4(p, 1.0);\n}\n";
static const char *SKIN_VAT =
    "uniform sampler2D u_vat_positions, u_vat_normals; uniform int u_frame_width, u_rows_per_frame, u_vat_rows;\n"
    "vec3 vat_fetch(sampler2D t, int frame) {\n"
    "    int row = frame * u_rows_per_frame + gl_VertexID / u_frame_width, block = row / u_vat_rows;\n"
    "    return texelFetch(t, ivec2(block * u_frame_width + gl_VertexID % u_frame_width, row - block * u_vat_rows), 0).xyz;\n"
    "}\n"
    "void main() {\n    int row0, row1; float fr;\n    cb_frame(a_inst, u_time, row0, row1, fr);\n"
    "    vec3 p = mix(vat_fetch(u_vat_positions, row0), vat_fetch(u_vat_positions, row1), fr);\n"
    "    vec3 n = normalize(mix(vat_fetch(u_vat_normals, row0), vat_fetch(u_vat_normals, row1), fr));\n";
/* A model without normals (Fox.glb): glTF asks for flat normals, the triangle's own, as the skinned zero normal (or
 * its normalize's NaN) would shade every method's image alike black. */
static const char *FRAGMENT =
    "#version 330 core\nin vec3 v_normal; in vec3 v_world; out vec4 o_color;\n"
    "void main() { vec3 n = dot(v_normal, v_normal) > 1e-12 ? v_normal : cross(dFdx(v_world), dFdy(v_world));\n"
    "              float l = 0.35 + 0.65 * max(dot(normalize(n), normalize(vec3(0.4, 0.8, 0.3))), 0.0);\n"
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
static GLuint program(const char *library, const cb_palette *p, bool local_rows, bool bones, int influences,
                      const char *const *vs, int vs_n, const char *const *fs, int fs_n)
{
    static const char *layouts[] = {"CB_LAYOUT_MAT4", "CB_LAYOUT_AFFINE", "CB_LAYOUT_QPOS"};
    static const char *precisions[] = {"CB_PRECISION_FLOAT", "CB_PRECISION_HALF", "CB_PRECISION_U16"};
    char defines[256], count[32] = "";
    if (influences) snprintf(count, sizeof count, "#define CB_INFLUENCES %d\n", influences);
    snprintf(defines, sizeof defines, "#version 330 core\n#define %s\n#define %s\n%s%s%s%s", layouts[p->layout],
             precisions[p->precision], p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "",
             local_rows ? "#define CB_LOCAL_ROWS\n" : "", bones ? "#define CB_BONE_TEXTURE\n" : "", count);
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
    bench_draw(s, method, n, time, vp, target);
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
        bench_place_herd(s, n, vp);
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
    /* --check compares what each method draws from the same rows. Between two rows the palette blends each bone (qpos)
     * and the VAT each vertex (linear), which differ by up to the rows' blend error: at 30 fps the robot's is 0.505
     * units, 11% of its height, and its palette and VAT differed by 0.3-2.2% of the pixels with the time; at the
     * auto rate's ceiling (the rate fps "auto" may ship) 0.017 units, and 0.3-0.6% (bench/RESULTS.txt gl43). */
    if (check) o.fps = CB_AUTO_MAX_FPS;
    o.affine_fallback = true; /* as the command's bake: a rig qpos cannot hold (the spider's non-uniform scale) in affine */
    cb_bake_options palette_options = o;
    for (int a = 3; a < argc; ++a)
        if (!strcmp(argv[a], "--local-rows")) palette_options.bone_space = CB_BONE_SPACE_LOCAL;
    cb_palette pal;
    cb_vat vat;
    if (!sampler || cb_palette_bake(sampler, &palette_options, NULL, 0, &pal, &err) != CB_OK ||
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
    s.local_rows = pal.bone_space == CB_BONE_SPACE_LOCAL;
    if (s.local_rows) bench_local_rows(&pal); /* the chains' depths, on stderr */
    for (int a = 3; a < argc; ++a) {
        s.lod |= !strcmp(argv[a], "--lod") || !strcmp(argv[a], "--lod-single");
        s.tiers &= strcmp(argv[a], "--lod-single") != 0;
        s.pass_only |= !strcmp(argv[a], "--pass-only");
    }
    s.instances = malloc((size_t)capacity * 32), s.order = malloc((size_t)capacity * 4);
    bench_upload_palette(&s);
    bench_bone_targets(&s, capacity);
    bench_upload_mesh(&s, model, capacity);
    const char *skins[METHODS] = {SKIN_PALETTE, SKIN_BONES, SKIN_VAT};
    const char *bones_path = getenv("BENCH_GL_BONES_GLSL"); /* another library for the bone pass and its draw: weighs a change */
    char *bones_glsl = bones_path ? bench_read_text(bones_path) : NULL;
    if (bones_path && !bones_glsl) bench_die("BENCH_GL_BONES_GLSL: cannot read that file (a GLSL library in place of the shipped one)");
    const char *bones_lib = bones_glsl ? bones_glsl : cb_palette_glsl;
    for (int m = 0; m < METHODS; ++m) {
        const char *vs[3] = {MAIN_HEAD, skins[m], MAIN_TAIL};
        s.prog[m] = program(m == 1 ? bones_lib : cb_palette_glsl, s.pal, s.local_rows, m == 1, 0, vs, m == 1 ? 2 : 3, NULL, 0);
    }
    const char *tier_vs[2] = {MAIN_HEAD, SKIN_TIER};
    for (int k = 0; k < 3; ++k) s.tier_prog[k] = program(bones_lib, s.pal, s.local_rows, true, 1 << k, tier_vs, 2, NULL, 0);
    const char *pass_path = getenv("BENCH_GL_PASS_GLSL"); /* another fragment main for the bone pass */
    char *pass_glsl = pass_path ? bench_read_text(pass_path) : NULL;
    if (pass_path && !pass_glsl) bench_die("BENCH_GL_PASS_GLSL: cannot read that file (a bone pass's fragment main)");
    const char *pass_fragment = pass_glsl ? pass_glsl : PASS_FRAGMENT;
    s.pass = program(bones_lib, s.pass_pal, s.local_rows, false, 0, &PASS_VERTEX, 1, &pass_fragment, 1);
    free(bones_glsl), free(pass_glsl);
    GLuint target = bench_offscreen_target(WIDTH, HEIGHT);
    int rc = check ? bench_check_images(&s, target) : (bench_counts(&s, argv[2], frames, target), 0);
    free(s.instances), free(s.order);
    cb_vat_free(&vat);
    cb_palette_free(&pal);
    cb_sampler_free(sampler);
    cb_model_free(model);
    return rc;
}
