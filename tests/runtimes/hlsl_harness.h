/* hlsl_harness.h - what the HLSL runtime's tests share: compiling HLSL with glslang's HLSL front
 * end (and validating the SPIR-V with spirv-val), a palette as Vulkan textures, bakes of the
 * sample models, the instances and times to skin at, and the C runtime's answer for them
 * (cb_runtime_matrices_crossfade; its matrices are cb_runtime_matrices', which `crowdbake verify`
 * compares with exact skinning). */
#ifndef CB_HLSL_HARNESS_H
#define CB_HLSL_HARNESS_H

#include <math.h>
#include <sys/stat.h>

#include "crowdbake/runtime.h"
#include "vulkan_compute.h"
#include "runtimes/shader_source.h"


/* Compiles a compute shader (entry main) with glslangValidator's HLSL front end, include paths
 * `includes` (-I...), and validates the module with spirv-val; returns the SPIR-V words. */
static inline uint32_t *compile_hlsl(const char *src, const char *name, const char *includes, size_t *bytes)
{
    char path[512], spv[512], cmd[4096], log[8192];
    mkdir(TEST_TMP, 0755);
    snprintf(path, sizeof path, "%s/%s.hlsl", TEST_TMP, name);
    snprintf(spv, sizeof spv, "%s/%s.spv", TEST_TMP, name);
    write_text(path, src);
    snprintf(cmd, sizeof cmd, "glslangValidator -V -D -S comp -e main --target-env vulkan1.1 %s -o %s %s 2>&1", includes, spv, path);
    if (run_command(cmd, log, sizeof log) != 0)
        fail_msg("glslang (Debian glslang-tools) does not compile %s:\n%s", path, log);
    snprintf(cmd, sizeof cmd, "spirv-val --target-env vulkan1.1 %s 2>&1", spv);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("spirv-val (Debian spirv-tools) rejects %s:\n%s", spv, log);
    return (uint32_t *)read_whole_file(spv, bytes);
}

typedef struct fixture {
    cb_model *model;
    cb_palette palette;
} fixture;

/* Bakes the model's first skin, every clip, in place, as test_gl does; fitted rows when `fit`;
 * local rows (.pal version 6) when `space` says. */
static inline void bake_space(const char *path, cb_layout l, cb_precision pr, bool fit, cb_bone_space space, fixture *f)
{
    f->model = load_or_fail(path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(f->model, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = l, o.precision = pr, o.root_motion = CB_ROOT_MOTION_IN_PLACE, o.fit = fit, o.bone_space = space;
    assert_int_equal(cb_palette_bake(s, &o, NULL, 0, &f->palette, &err), CB_OK);
    assert_int_equal(f->palette.bone_space, space);
    cb_sampler_free(s);
}

static inline void bake(const char *path, cb_layout l, cb_precision pr, bool fit, fixture *f)
{
    bake_space(path, l, pr, fit, CB_BONE_SPACE_GLOBAL, f);
}

static inline void release(fixture *f)
{
    cb_palette_free(&f->palette);
    cb_model_free(f->model);
}

/* test_gl's tolerance: 1e-5 of the model's height (at least 1e-5), for positions; 1e-5 for unit normals. */
static inline double tolerance(const fixture *f) { return 1e-5 * fmax(1.0, f->palette.model_height); }

/* The palette's texels as a texture (u16: RGBA16UI, or RGBA16 UNORM with `unorm`), optionally with
 * every mat4 bone transposed (the reference runtime's shipped bug test_gl also plants). */
static inline vkc_resource upload_palette(vkc_context *c, const cb_palette *p, bool unorm, bool transpose)
{
    const void *data = p->texels;
    float *t = NULL;
    if (transpose) {
        t = malloc(p->texel_bytes);
        for (size_t b = 0; b + 16 <= p->texel_bytes / 4; b += 16)
            for (int r = 0; r < 4; ++r)
                for (int k = 0; k < 4; ++k) t[b + r * 4 + k] = ((const float *)p->texels)[b + k * 4 + r];
        data = t;
    }
    VkFormat format = p->precision == CB_PRECISION_FLOAT  ? VK_FORMAT_R32G32B32A32_SFLOAT
                      : p->precision == CB_PRECISION_HALF ? VK_FORMAT_R16G16B16A16_SFLOAT
                      : unorm                             ? VK_FORMAT_R16G16B16A16_UNORM
                                                          : VK_FORMAT_R16G16B16A16_UINT;
    vkc_resource r = vkc_image(c, format, p->width, p->height, cb_precision_texel_bytes(p->precision), data, false);
    free(t);
    return r;
}

/* cb_bind_positions, as cb_bind_texels lays it out (local rows: 5 rows). */
static inline vkc_resource upload_bind_positions(vkc_context *c, const cb_palette *p)
{
    uint32_t n = p->bone_count, rows = cb_bind_texels(p, NULL);
    float *rgba = malloc((size_t)n * rows * 4 * sizeof(float));
    cb_bind_texels(p, rgba);
    vkc_resource r = vkc_image(c, VK_FORMAT_R32G32B32A32_SFLOAT, n, rows, 16, rgba, false);
    free(rgba);
    return r;
}

/* The header's numbers as the test shaders' cbuffer lays them out (see HEADER_CBUFFER). */
typedef struct header_block {
    float bounds_min[3], row_texels, bounds_max[3], rows_per_block, linear_range;
    uint32_t vertex_count, sample_count, pad;
} header_block;
#define HEADER_CBUFFER                                                                                                 \
    "float3 cb_bounds_min; float cb_row_texels; float3 cb_bounds_max; float cb_rows_per_block; float cb_linear_range; " \
    "uint cb_vertex_count; uint cb_sample_count;"

static inline header_block header_of(const cb_palette *p, uint32_t vertex_count, uint32_t sample_count)
{
    header_block h = {.row_texels = (float)p->row_texels, .rows_per_block = (float)p->height, .linear_range = p->linear_range,
                      .vertex_count = vertex_count, .sample_count = sample_count};
    memcpy(h.bounds_min, p->bounds_min, sizeof h.bounds_min);
    memcpy(h.bounds_max, p->bounds_max, sizeof h.bounds_max);
    return h;
}

/* What the test shaders skin: an instance, the clip it fades from, the fade weight, the time, the
 * step back to the previous frame, and which of the runtime's functions to call (mode). */
typedef struct sample {
    cb_instance inst, from;
    double fade, time, dt;
    int mode;
} sample;
typedef struct gpu_sample {
    float inst[4], from[4], fade_time_dt_mode[4];
} gpu_sample;

/* Instances of every clip at many times (test_gl's: mid-frames, the loop seam, random phases;
 * one before 0), each also cross-faded from another clip in the modes that fade; mode = index % 4. */
static inline uint32_t make_samples(const cb_palette *p, sample *out, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        cb_instance in = {cl->first_row, cl->loops ? cl->frames : -(double)cl->frames, cl->fps, 0};
        double span = cl->frames / cl->fps;
        /* ...and a time before 0 (a herd's clock offset): GLSL's floored mod, not HLSL's fmod. */
        double times[] = {0.3 / cl->fps, 2.5 / cl->fps, span * 0.37, span - 0.4 / cl->fps /* the seam */, span * 1.5,
                          -span * 0.37};
        for (int k = 0; k < 6 && n < cap; ++k) out[n++] = (sample){.inst = in, .time = times[k]};
        for (int k = 0; k < 3 && n < cap; ++k) {
            cb_instance phased = in;
            phased.phase = fmod((k + 1) * 0.6180339887, 1.0);
            out[n++] = (sample){.inst = phased, .time = 0.77 * (k + 1)};
        }
    }
    for (uint32_t s = 0; s < n; ++s) {
        out[s].mode = (int)(s % 4);
        out[s].dt = 1.0 / 60;
        out[s].from = out[(s * 7 + 3) % n].inst;
        out[s].fade = out[s].mode >= 2 ? fmod(0.37 * s + 0.1, 1.0) : 1.0;
    }
    return n;
}

static inline gpu_sample *gpu_samples(const sample *s, uint32_t n, double row_offset)
{
    gpu_sample *g = calloc(n, sizeof *g);
    for (uint32_t i = 0; i < n; ++i) {
        const cb_instance *a = &s[i].inst, *b = &s[i].from;
        float v[12] = {(float)(a->first_row + row_offset), (float)a->frame_count, (float)a->rate, (float)a->phase,
                       (float)(b->first_row + row_offset), (float)b->frame_count, (float)b->rate, (float)b->phase,
                       (float)s[i].fade, (float)s[i].time, (float)s[i].dt, (float)s[i].mode};
        memcpy(&g[i], v, sizeof v);
    }
    return g;
}

/* The C runtime's bone matrices of a sample at time t, cross-faded as the shaders fade
 * (cb_runtime_matrices_crossfade: global rows' matrices mixed term by term, local rows faded before
 * they compose). */
static inline void cpu_matrices(const cb_palette *p, const sample *s, double t, double *mats)
{
    if (!cb_runtime_matrices_crossfade(p, p->texels, &s->from, &s->inst, s->fade, t, mats)) fail_msg("out of memory");
}

/* Skinned normals (normalized), as src/core/vat.c skins them. */
static inline void cpu_normals(const cb_primitive *prim, const double *mats, double *out)
{
    for (uint32_t v = 0; v < prim->vertex_count; ++v) {
        double *o = out + (size_t)v * 3, len;
        const float *n = prim->normals + (size_t)v * 3;
        o[0] = o[1] = o[2] = 0;
        for (int i = 0; i < 4; ++i) {
            double w = prim->weights[(size_t)v * 4 + i];
            if (w == 0) continue;
            const double *m = mats + (size_t)prim->joints[(size_t)v * 4 + i] * 16;
            for (int k = 0; k < 3; ++k) o[k] += w * (m[k] * n[0] + m[4 + k] * n[1] + m[8 + k] * n[2]);
        }
        len = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
        for (int k = 0; k < 3 && len > 0; ++k) o[k] /= len;
    }
}

/* Largest |GPU - C runtime| of the positions (now and at time - dt) and of the normals; gpu holds
 * three float4 per (sample, vertex): position, normal, previous position. */
static inline void compare(const cb_palette *p, const cb_primitive *prim, const sample *s, uint32_t n, const float *gpu,
                    double *position_error, double *normal_error)
{
    size_t verts = prim->vertex_count;
    double *mats = malloc(p->bone_count * 16 * sizeof(double));
    double *pos = malloc(verts * 3 * sizeof(double)), *nrm = malloc(verts * 3 * sizeof(double));
    *position_error = *normal_error = 0;
    for (uint32_t i = 0; i < n; ++i)
        for (int before = 0; before < 2; ++before) {
            cpu_matrices(p, &s[i], s[i].time - (before ? s[i].dt : 0), mats);
            cb_skin_positions(prim, mats, pos);
            cpu_normals(prim, mats, nrm);
            for (size_t v = 0; v < verts; ++v)
                for (int k = 0; k < 3; ++k) {
                    const float *g = gpu + ((size_t)i * verts + v) * 12;
                    *position_error = fmax(*position_error, fabs(pos[v * 3 + k] - g[(before ? 8 : 0) + k]));
                    if (!before) *normal_error = fmax(*normal_error, fabs(nrm[v * 3 + k] - g[4 + k]));
                }
        }
    free(mats), free(pos), free(nrm);
}

/* A primitive's vertices as the test shaders read them: position, normal, joints, weights (float4 each). */
static inline vkc_resource upload_vertices(vkc_context *c, const cb_primitive *prim)
{
    size_t verts = prim->vertex_count;
    float *v = calloc(verts * 16, sizeof(float));
    for (size_t i = 0; i < verts; ++i) {
        memcpy(v + i * 16, prim->positions + i * 3, 3 * sizeof(float));
        if (prim->normals) memcpy(v + i * 16 + 4, prim->normals + i * 3, 3 * sizeof(float));
        for (int k = 0; k < 4; ++k) {
            int32_t j = prim->joints[i * 4 + k];
            memcpy(v + i * 16 + 8 + k, &j, 4);
        }
        memcpy(v + i * 16 + 12, prim->weights + i * 4, 4 * sizeof(float));
    }
    vkc_resource r = vkc_buffer(c, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, v, verts * 64);
    free(v);
    return r;
}

/* The HLSL side of the above: the vertex and sample structures and their buffers. */
#define HARNESS_BUFFERS                                                                                                \
    "struct cb_test_vertex { float4 position; float4 normal; int4 joints; float4 weights; };\n"                       \
    "struct cb_test_sample { float4 inst; float4 from_inst; float4 fade_time_dt_mode; };\n"

/* The skinning half of the bone pass's check: one invocation per (sample, vertex) skins the vertex
 * from the pass's textures (cb_skin_bone_pass), into the harness's 12 floats per (sample, vertex). */
#define HARNESS_BONE_SKIN_MAIN                                                                                         \
    HARNESS_BUFFERS                                                                                                    \
    "[[vk::binding(6)]] StructuredBuffer<cb_test_vertex> cb_vertices;\n"                                               \
    "[[vk::binding(7)]] RWStructuredBuffer<float4> cb_skinned;\n"                                                      \
    "[numthreads(64, 1, 1)]\n"                                                                                         \
    "void main(uint3 id : SV_DispatchThreadID)\n"                                                                      \
    "{\n"                                                                                                              \
    "    uint s = id.x / cb_vertex_count, i = id.x - s * cb_vertex_count;\n"                                           \
    "    if (s >= cb_sample_count) return;\n"                                                                          \
    "    cb_test_vertex v = cb_vertices[i];\n"                                                                         \
    "    float3 p, n;\n"                                                                                               \
    "    cb_skin_bone_pass(v.position.xyz, v.normal.xyz, v.joints, v.weights, int(s), p, n);\n"                        \
    "    cb_skinned[id.x * 3] = float4(p, 1.0);\n"                                                                     \
    "    cb_skinned[id.x * 3 + 1] = float4(n, 0.0);\n"                                                                 \
    "    cb_skinned[id.x * 3 + 2] = float4(p, 1.0);\n"                                                                 \
    "}\n"

/* The globals form's declarations, bound where the harness puts them (the library declares them
 * itself unless told, with no bindings: Unity assigns its own): the palette's defines, CB_U16_UNORM
 * where `unorm` says, then `extra`. */
static inline void hlsl_globals_prefix(char *out, size_t size, const cb_palette *p, bool unorm, const char *extra)
{
    snprintf(out, size,
             "#define %s\n#define %s\n%s%s%s%s"
             "#define CB_TEXTURES_DECLARED\n#define CB_HEADER_DECLARED\n"
             "[[vk::binding(0)]] Texture2D<%s> cb_palette;\n"
             "[[vk::binding(1)]] Texture2D<float4> cb_bind_positions;\n"
             "[[vk::binding(2)]] cbuffer cb_test_header { " HEADER_CBUFFER " };\n",
             layout_define[p->layout], precision_define[p->precision],
             p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "",
             p->bone_space == CB_BONE_SPACE_LOCAL ? "#define CB_LOCAL_ROWS\n" : "", unorm ? "#define CB_U16_UNORM\n" : "", extra,
             p->precision == CB_PRECISION_U16 && !unorm ? "uint4" : "float4");
}

#endif
