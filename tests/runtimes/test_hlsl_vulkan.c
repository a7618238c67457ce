/* test_hlsl_vulkan.c - the HLSL runtime (runtimes/hlsl/crowdbake_palette.hlsl) compiled by glslang's
 * HLSL front end to SPIR-V (validated by spirv-val) and run as a compute shader on Mesa's lavapipe,
 * one invocation per (instance, vertex). For every layout x precision its skinned positions, normals
 * and previous-frame positions - through every skinning function, cross-faded or not - must equal
 * the C runtime's (src/core/runtime.c, which verify compares with exact skinning) within test_gl's
 * tolerance; the bone pass too; and the broken variants test_gl plants must fail the comparison. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <time.h>

#include "bone_order.h"
#include "hlsl_harness.h"

#define LIBRARY "runtimes/hlsl/crowdbake_palette.hlsl"

VKC_TEST_DEVICE("the HLSL runtime")

#define REQUIRE_DEVICE()                                                                                               \
    do {                                                                                                               \
        if (!have_device) skip();                                                                                      \
    } while (0)

/* Calls every skinning function of the globals form, as the sample's mode says. */
static const char *skin_main =
    HARNESS_BUFFERS
    "[[vk::binding(3)]] StructuredBuffer<cb_test_vertex> cb_vertices;\n"
    "[[vk::binding(4)]] StructuredBuffer<cb_test_sample> cb_samples;\n"
    "[[vk::binding(5)]] RWStructuredBuffer<float4> cb_skinned;\n"
    "[numthreads(64, 1, 1)]\n"
    "void main(uint3 id : SV_DispatchThreadID)\n"
    "{\n"
    "    uint s = id.x / cb_vertex_count, i = id.x - s * cb_vertex_count;\n"
    "    if (s >= cb_sample_count) return;\n"
    "    cb_test_vertex v = cb_vertices[i];\n"
    "    cb_test_sample k = cb_samples[s];\n"
    "    float fade = k.fade_time_dt_mode.x, time = k.fade_time_dt_mode.y, earlier = time - k.fade_time_dt_mode.z;\n"
    "    int mode = int(k.fade_time_dt_mode.w);\n"
    "    float3 p, n, before;\n"
    "    if (mode == 0) {\n"
    "        cb_skin_position_normal(v.position.xyz, v.normal.xyz, v.joints, v.weights, k.inst, time, p, n);\n"
    "        before = cb_skin_position(v.position.xyz, v.joints, v.weights, k.inst, earlier);\n"
    "    } else if (mode == 1) {\n"
    "        p = cb_skin_position(v.position.xyz, v.joints, v.weights, k.inst, time);\n"
    "        n = cb_skin_normal(v.normal.xyz, v.joints, v.weights, k.inst, time);\n"
    "        before = cb_skin_position(v.position.xyz, v.joints, v.weights, k.inst, earlier);\n"
    "    } else if (mode == 2) {\n"
    "        cb_skin_position_normal_crossfade(v.position.xyz, v.normal.xyz, v.joints, v.weights, k.from_inst, k.inst, fade,\n"
    "                                          time, p, n);\n"
    "        before = cb_skin_position_crossfade(v.position.xyz, v.joints, v.weights, k.from_inst, k.inst, fade, earlier);\n"
    "    } else {\n"
    "        p = cb_skin_position_crossfade(v.position.xyz, v.joints, v.weights, k.from_inst, k.inst, fade, time);\n"
    "        n = cb_skin_normal_crossfade(v.normal.xyz, v.joints, v.weights, k.from_inst, k.inst, fade, time);\n"
    "        before = cb_skin_position_crossfade(v.position.xyz, v.joints, v.weights, k.from_inst, k.inst, fade, earlier);\n"
    "    }\n"
    "    cb_skinned[id.x * 3] = float4(p, 1.0);\n"
    "    cb_skinned[id.x * 3 + 1] = float4(n, 0.0);\n"
    "    cb_skinned[id.x * 3 + 2] = float4(before, 1.0);\n"
    "}\n";

typedef struct variant {
    bool unorm, transpose;
    double row_offset;
    bool local;      /* local rows (.pal version 6): CB_LOCAL_ROWS */
    bool reversed;   /* local: the bone order reversed, every parent after its children (reverse_bones) */
    double *seconds; /* when set: adds the dispatch's wall time (lavapipe), for the cost of the chain walk */
} variant;

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + t.tv_nsec * 1e-9;
}

/* Runs the compute shader `src` over every (sample, vertex); returns 12 floats per pair. */
static float *gpu_skin(const cb_palette *p, const cb_primitive *prim, const sample *s, uint32_t n, const char *src,
                       const char *name, variant v)
{
    size_t spv_bytes, verts = prim->vertex_count;
    uint32_t *spv = compile_hlsl(src, name, "", &spv_bytes);
    header_block h = header_of(p, (uint32_t)verts, n);
    gpu_sample *g = gpu_samples(s, n, v.row_offset);
    vkc_resource r[6] = {upload_palette(&vk, p, v.unorm, v.transpose), upload_bind_positions(&vk, p),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &h, sizeof h), upload_vertices(&vk, prim),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, g, n * sizeof *g),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, NULL, n * verts * 48)};
    vkc_pipeline pipe = vkc_compute(&vk, spv, spv_bytes, r, 6);
    VkCommandBuffer cmd = vkc_begin(&vk);
    vkc_dispatch(cmd, &pipe, (uint32_t)((n * verts + 63) / 64));
    double start = now_seconds();
    vkc_submit(&vk, cmd);
    if (v.seconds) *v.seconds += now_seconds() - start;
    float *out = malloc(n * verts * 48);
    vkc_read(&vk, &r[5], out);
    vkc_free_pipeline(&vk, &pipe);
    for (int i = 0; i < 6; ++i) vkc_free(&vk, &r[i]);
    free(spv), free(g);
    return out;
}

/* Worst position error / tolerance of the library text `library` on a bake of `model` (a sample's
 * name or a path); the normal error / tolerance in *normal_ratio when wanted. */
static double run_case(const char *model, cb_layout l, cb_precision pr, bool fit, const char *library, variant v,
                       double *normal_ratio, bool print)
{
    char path[1024], name[64];
    if (strchr(model, '/')) snprintf(path, sizeof path, "%s", model);
    else snprintf(path, sizeof path, "%s/%s", samples_dir(), model);
    fixture f;
    bake_space(path, l, pr, fit, v.local ? CB_BONE_SPACE_LOCAL : CB_BONE_SPACE_GLOBAL, &f);
    if (fit) assert_true(f.palette.fitted);
    if (v.reversed) reverse_bones(&f.palette, &f.model->primitives[0]);
    sample samples[64];
    uint32_t n = make_samples(&f.palette, samples, 64);
    static char src[1 << 17];
    hlsl_globals_prefix(src, sizeof src, &f.palette, v.unorm, "");
    size_t used = strlen(src);
    snprintf(src + used, sizeof src - used, "%s\n%s", library, skin_main);
    snprintf(name, sizeof name, "hlsl_%s_%s%s%s", cb_layout_name(l), cb_precision_name(pr), v.unorm ? "_unorm" : "",
             v.local ? "_local" : "");
    const cb_primitive *prim = &f.model->primitives[0];
    float *gpu = gpu_skin(&f.palette, prim, samples, n, src, name, v);
    double pe, ne, tol = tolerance(&f);
    compare(&f.palette, prim, samples, n, gpu, &pe, &ne);
    if (print)
        printf("  %-6s %-5s%-6s%-7s%s%s %u instances x %zu vertices: positions %.2g, normals %.2g (tolerance %.2g, %.2g)\n",
               cb_layout_name(l), cb_precision_name(pr), v.unorm ? " unorm" : "", fit ? " fitted" : "", v.local ? " local" : "",
               v.reversed ? ", bones reversed" : "", n,
               (size_t)prim->vertex_count, pe, ne, tol, 1e-5);
    if (normal_ratio) *normal_ratio = ne / 1e-5;
    free(gpu);
    release(&f);
    return pe / tol;
}

static void test_every_layout_and_precision_matches_the_c_runtime(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    char *lib = read_whole_file(LIBRARY, NULL);
    for (int l = 0; l < 3; ++l)
        for (int pr = 0; pr < 3; ++pr)
            for (int unorm = 0; unorm < (pr == CB_PRECISION_U16 ? 2 : 1); ++unorm) {
                double normals, positions = run_case("quadruped.glb", (cb_layout)l, (cb_precision)pr, false, lib,
                                                     (variant){.unorm = unorm != 0}, &normals, true);
                assert_true(positions <= 1 && normals <= 1);
            }
    free(lib);
}

static void test_fitted_rows_and_one_shots_match(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    char *lib = read_whole_file(LIBRARY, NULL), fox[1024];
    double normals, positions = run_case("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, true, lib, (variant){0}, &normals, true);
    assert_true(positions <= 1 && normals <= 1);
    /* A real third-party model: Cow (loops and one-shots), qpos/half. */
    shared_path(fox, sizeof fox, "assets/quaternius-cow/Cow.glb");
    positions = run_case(fox, CB_LAYOUT_QPOS, CB_PRECISION_HALF, false, lib, (variant){0}, &normals, true);
    assert_true(positions <= 1 && normals <= 1);
    free(lib);
}

static double broken(const char *model, cb_layout l, cb_precision pr, const char *marker, const char *line, variant v)
{
    char *lib = read_whole_file(LIBRARY, NULL);
    if (marker) {
        char *b = break_shader(lib, marker, line);
        free(lib);
        lib = b;
    }
    double worst = run_case(model, l, pr, false, lib, v, NULL, false);
    free(lib);
    return worst;
}

static void test_broken_variants_are_caught(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    double transposed = broken("quadruped.glb", CB_LAYOUT_MAT4, CB_PRECISION_FLOAT, NULL, NULL, (variant){.transpose = true});
    double off_by_one = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, NULL, NULL, (variant){.row_offset = 1});
    double no_wrap = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_HALF, "cb:wrap", "        f1 = f0 + 1.0;", (variant){0});
    char multitrack[1024];
    shared_path(multitrack, sizeof multitrack, "assets/multitrack-luanti/gltf_multi_track_1.glb");
    /* multitrack's bones spin a full turn per loop: their last and first rows are -q apart. */
    double no_flip = broken(multitrack, CB_LAYOUT_QPOS, CB_PRECISION_FLOAT, "cb:hemisphere", "", (variant){0});
    double bind_offset = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_HALF, "cb:offset -", "    ps.xyz += b;", (variant){0});
    double matrix_offset = broken("quadruped.glb", CB_LAYOUT_MAT4, CB_PRECISION_HALF, "cb:offset-matrix",
                                  "    float3 p = t + b;", (variant){0});
    /* HLSL's fmod truncates (D3D's, as written; glslang turns it into SPIR-V's floored OpFMod). */
    double truncated_mod = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_FLOAT, "cb:mod",
                                  "    return x - y * trunc(x / y);", (variant){0});
    printf("  error / tolerance: transposed %.0f, rows off by one %.0f, no wrap %.0f, no hemisphere flip %.0f, bind position "
           "as offset %.0f (qpos), %.0f (mat4), HLSL's fmod for GLSL's mod %.0f\n",
           transposed, off_by_one, no_wrap, no_flip, bind_offset, matrix_offset, truncated_mod);
    assert_true(transposed > 10 && off_by_one > 10 && no_wrap > 10 && no_flip > 10 && bind_offset > 10 && matrix_offset > 10);
    assert_true(truncated_mod > 10);
    /* ...and the same multitrack palette with the shipped shader passes. */
    assert_true(broken(multitrack, CB_LAYOUT_QPOS, CB_PRECISION_FLOAT, NULL, NULL, (variant){0}) <= 1);
}

/* ---- the bone pass: cb_bone_pass once per (instance, bone) into three RGBA32F textures, then
 * CB_BONE_TEXTURE's cb_skin_bone_pass from them ---- */

#define BONE_ROWS 7 /* instances per column block of the bone textures: several blocks */

static const char *bone_pass_main =
    HARNESS_BUFFERS
    "[[vk::binding(3)]] StructuredBuffer<cb_test_sample> cb_samples;\n"
    "[[vk::binding(4)]] [[vk::image_format(\"rgba32f\")]] RWTexture2D<float4> cb_out0;\n"
    "[[vk::binding(5)]] [[vk::image_format(\"rgba32f\")]] RWTexture2D<float4> cb_out1;\n"
    "[[vk::binding(6)]] [[vk::image_format(\"rgba32f\")]] RWTexture2D<float4> cb_out2;\n"
    "[numthreads(64, 1, 1)]\n"
    "void main(uint3 id : SV_DispatchThreadID)\n"
    "{\n"
    "    int bones = int(cb_row_texels + 0.5) / CB_TEXELS_PER_BONE;\n"
    "    int instance = int(id.x) / bones, bone = int(id.x) - instance * bones;\n"
    "    if (instance >= int(cb_sample_count)) return;\n"
    "    cb_test_sample k = cb_samples[instance];\n"
    "    float4 c0, c1, c2;\n"
    "    cb_bone_pass(bone, k.from_inst, k.inst, k.fade_time_dt_mode.x, k.fade_time_dt_mode.y, c0, c1, c2);\n"
    "    int block = instance / int(cb_bone_rows);\n"
    "    int2 xy = int2(block * bones + bone, instance - block * int(cb_bone_rows));\n"
    "    cb_out0[xy] = c0;\n"
    "    cb_out1[xy] = c1;\n"
    "    cb_out2[xy] = c2;\n"
    "}\n";

/* Both passes of the bone pass over every sample (an instance each; dt 0: no previous frame). */
static float *gpu_bone_pass(const cb_palette *p, const cb_primitive *prim, const sample *s, uint32_t n, const char *library)
{
    static char src[2][1 << 17];
    char extra[512];
    snprintf(extra, sizeof extra, "static const float cb_bone_rows = %d;\n", BONE_ROWS);
    hlsl_globals_prefix(src[0], sizeof src[0], p, false, extra);
    size_t used = strlen(src[0]);
    snprintf(src[0] + used, sizeof src[0] - used, "%s\n%s", library, bone_pass_main);
    strcat(extra, "#define CB_BONE_TEXTURE\n[[vk::binding(3)]] Texture2D<float4> cb_bones0;\n"
                  "[[vk::binding(4)]] Texture2D<float4> cb_bones1;\n[[vk::binding(5)]] Texture2D<float4> cb_bones2;\n");
    hlsl_globals_prefix(src[1], sizeof src[1], p, false, extra);
    used = strlen(src[1]);
    snprintf(src[1] + used, sizeof src[1] - used, "%s\n%s", library, HARNESS_BONE_SKIN_MAIN);
    size_t bytes[2], verts = prim->vertex_count;
    uint32_t *spv[2] = {compile_hlsl(src[0], "hlsl_bone_pass", "", &bytes[0]),
                        compile_hlsl(src[1], "hlsl_bone_skin", "", &bytes[1])};
    uint32_t blocks = (n + BONE_ROWS - 1) / BONE_ROWS;
    header_block h = header_of(p, (uint32_t)verts, n);
    gpu_sample *g = gpu_samples(s, n, 0);
    vkc_resource r[8] = {upload_palette(&vk, p, false, false), upload_bind_positions(&vk, p),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &h, sizeof h),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, g, n * sizeof *g)};
    for (int k = 0; k < 3; ++k)
        r[4 + k] = vkc_image(&vk, VK_FORMAT_R32G32B32A32_SFLOAT, blocks * p->bone_count, BONE_ROWS, 16, NULL, true);
    vkc_pipeline pass = vkc_compute(&vk, spv[0], bytes[0], r, 7);
    vkc_resource skin[8] = {r[0], r[1], r[2], r[4], r[5], r[6], upload_vertices(&vk, prim),
                            vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, NULL, n * verts * 48)};
    for (int k = 3; k < 6; ++k) skin[k].type = VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE; /* written above, read here */
    vkc_pipeline skinning = vkc_compute(&vk, spv[1], bytes[1], skin, 8);
    VkCommandBuffer cmd = vkc_begin(&vk);
    vkc_dispatch(cmd, &pass, (n * p->bone_count + 63) / 64);
    vkc_dispatch(cmd, &skinning, (uint32_t)((n * verts + 63) / 64));
    vkc_submit(&vk, cmd);
    float *out = malloc(n * verts * 48);
    vkc_read(&vk, &skin[7], out);
    vkc_free_pipeline(&vk, &pass), vkc_free_pipeline(&vk, &skinning);
    for (int i = 0; i < 7; ++i) vkc_free(&vk, &r[i]);
    vkc_free(&vk, &skin[6]), vkc_free(&vk, &skin[7]);
    free(spv[0]), free(spv[1]), free(g);
    return out;
}

static double bone_pass_case(cb_layout l, cb_precision pr, bool local, const char *library, double *normal_ratio)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    fixture f;
    bake_space(path, l, pr, false, local ? CB_BONE_SPACE_LOCAL : CB_BONE_SPACE_GLOBAL, &f);
    sample samples[64];
    uint32_t n = make_samples(&f.palette, samples, 64);
    for (uint32_t i = 0; i < n; ++i) samples[i].dt = 0;
    const cb_primitive *prim = &f.model->primitives[0];
    float *gpu = gpu_bone_pass(&f.palette, prim, samples, n, library);
    double pe, ne;
    compare(&f.palette, prim, samples, n, gpu, &pe, &ne);
    printf("  bone pass %-6s %-5s%s %u instances (%d a block) x %u vertices: positions %.2g, normals %.2g (tolerance %.2g)\n",
           cb_layout_name(l), cb_precision_name(pr), local ? " local" : "", n, BONE_ROWS, prim->vertex_count, pe, ne, tolerance(&f));
    *normal_ratio = ne / 1e-5;
    pe /= tolerance(&f);
    free(gpu);
    release(&f);
    return pe;
}

static void test_the_bone_pass_matches_the_c_runtime(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    char *lib = read_whole_file(LIBRARY, NULL);
    double normals;
    for (int l = 0; l < 3; ++l) {
        double positions = bone_pass_case((cb_layout)l, l == CB_LAYOUT_QPOS ? CB_PRECISION_U16 : CB_PRECISION_FLOAT, false, lib, &normals);
        assert_true(positions <= 1 && normals <= 1);
    }
    /* Broken variant: the bone textures' columns read as rows. */
    char *b = break_shader(lib, "cb:bone-columns",
                           "    return cb_make_affine(float3x3(c0.xyz, c1.xyz, c2.xyz), float3(c0.w, c1.w, c2.w));");
    double rows_for_columns = bone_pass_case(CB_LAYOUT_QPOS, CB_PRECISION_U16, false, b, &normals);
    printf("  bone pass with columns read as rows: error / tolerance %.0f\n", rows_for_columns);
    assert_true(rows_for_columns > 10);
    free(b), free(lib);
}

/* ---- local rows (.pal version 6): every skinning function walks each influence's chain, the bone
 * pass each bone's; held to the C runtime (cb_runtime_matrices_crossfade: composing, and mid-fade the
 * two clips' local rows blended before composing) ---- */

static const variant local_rows = {.local = true};

static void test_local_rows_match_the_c_runtime(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    char *lib = read_whole_file(LIBRARY, NULL), cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    double normals, positions;
    for (int pr = 0; pr < 3; pr += 2) { /* u16 (each bone's ranges) and float; half is refused */
        positions = run_case("quadruped.glb", CB_LAYOUT_QPOS, (cb_precision)pr, false, lib, local_rows, &normals, true);
        assert_true(positions <= 1 && normals <= 1);
    }
    variant unorm = local_rows;
    unorm.unorm = true;
    positions = run_case("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, false, lib, unorm, &normals, true);
    assert_true(positions <= 1 && normals <= 1);
    positions = run_case(cow, CB_LAYOUT_QPOS, CB_PRECISION_U16, false, lib, local_rows, &normals, true);
    assert_true(positions <= 1 && normals <= 1);
    positions = bone_pass_case(CB_LAYOUT_QPOS, CB_PRECISION_U16, true, lib, &normals);
    assert_true(positions <= 1 && normals <= 1);
    /* Every parent after its children (the bone order reversed): the walk assumes no order. */
    variant reversed = local_rows;
    reversed.reversed = true;
    positions = run_case("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, false, lib, reversed, &normals, true);
    assert_true(positions <= 1 && normals <= 1);
    free(lib);
}

static double broken_local(const char *marker, const char *line)
{
    char *lib = read_whole_file(LIBRARY, NULL), *b = break_shader(lib, marker, line);
    double worst = run_case("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, false, b, local_rows, NULL, false);
    free(lib), free(b);
    return worst;
}

/* The broken local variants: no chain walk (each bone's local row skinned as if global), and u16
 * positions decoded in the unit box instead of the bone's own. */
static void test_broken_local_variants_are_caught(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    double no_walk = broken_local("cb:local-compose", "");
    double no_range = broken_local("cb:local-ranges", "    return float4(float3(u.xyz) / 65535.0, lo.w * float(u.w) / 65535.0);");
    printf("  local rows, error / tolerance: no chain walk %.0f, positions outside the bone's box %.0f\n", no_walk, no_range);
    assert_true(no_walk > 10 && no_range > 10);
}

/* What the per-vertex walk costs on lavapipe: the same quadruped samples through the global and the
 * local qpos/u16 library, dispatches interleaved (global, local, ...) three times; the SPIR-V size
 * of each. Printed, not asserted: a measurement, not a threshold. */
static void test_local_walk_cost(void **state)
{
    (void)state;
    REQUIRE_DEVICE();
    char *lib = read_whole_file(LIBRARY, NULL);
    double seconds[2] = {0, 0};
    for (int round = 0; round < 3; ++round)
        for (int local = 0; local < 2; ++local) {
            variant v = {.local = local != 0, .seconds = &seconds[local]};
            assert_true(run_case("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, false, lib, v, NULL, false) <= 1);
        }
    size_t bytes[2];
    for (int local = 0; local < 2; ++local) {
        char path[256];
        snprintf(path, sizeof path, "%s/hlsl_qpos_u16%s.spv", TEST_TMP, local ? "_local" : "");
        free(read_whole_file(path, &bytes[local]));
    }
    printf("  per-vertex chain walk (quadruped qpos/u16, every skinning function, lavapipe): dispatch time local / global "
           "%.2f (%.3f s / %.3f s over 3 interleaved runs); SPIR-V %zu / %zu bytes\n",
           seconds[1] / seconds[0], seconds[1], seconds[0], bytes[1], bytes[0]);
    free(lib);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_layout_and_precision_matches_the_c_runtime),
        cmocka_unit_test(test_fitted_rows_and_one_shots_match),
        cmocka_unit_test(test_broken_variants_are_caught),
        cmocka_unit_test(test_the_bone_pass_matches_the_c_runtime),
        cmocka_unit_test(test_local_rows_match_the_c_runtime),
        cmocka_unit_test(test_broken_local_variants_are_caught),
        cmocka_unit_test(test_local_walk_cost),
    };
    return cmocka_run_group_tests_name("hlsl_vulkan", tests, setup, teardown);
}
