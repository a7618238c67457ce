/* test_unreal_shader.c - the Unreal plugin's shader (runtimes/unreal/Crowdbake/Shaders/Private:
 * Crowdbake.ush and the material Custom node's code, CrowdbakeCustomNode.hlsl) through the same
 * glslang -> SPIR-V -> lavapipe harness as the HLSL runtime, with Unreal's shader environment
 * stubbed (unreal_stub.ush; /Plugin/Crowdbake mapped to the plugin's Shaders folder, as Unreal
 * maps it). The node's code is wrapped in a function the way Unreal's material compiler wraps a
 * Custom node (its inputs as parameters, a Texture Object with its sampler, additional outputs
 * inout) and fed a static mesh as Unreal holds it: centimetres, Z up, the vertex id in a UV
 * channel, the joints and weights in the skin texture, the instance's numbers as custom data.
 * World Position Offset + the position, and the normal, must equal the C runtime's for every
 * layout x precision; the previous frame's offset too. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <unistd.h>

#include "hlsl_harness.h"

#define SHADERS "runtimes/unreal/Crowdbake/Shaders"
#define SKIN_WIDTH 128 /* vertices a row of the skin texture: the test's mesh wraps */

VKC_TEST_DEVICE("the Unreal shader")

static void test_the_plugin_carries_the_hlsl_runtime_unchanged(void **state)
{
    (void)state;
    size_t a, b;
    char *runtime = read_whole_file("runtimes/hlsl/crowdbake_palette.hlsl", &a);
    char *copy = read_whole_file(SHADERS "/Private/CrowdbakePalette.ush", &b);
    if (a != b || memcmp(runtime, copy, a) != 0)
        fail_msg(SHADERS "/Private/CrowdbakePalette.ush differs from runtimes/hlsl/crowdbake_palette.hlsl: copy it again "
                         "(cp runtimes/hlsl/crowdbake_palette.hlsl " SHADERS "/Private/CrowdbakePalette.ush)");
    free(runtime), free(copy);
}

/* The Custom node as Unreal's material compiler emits it, then a compute shader that calls it and
 * CrowdbakeMaterialPreviousOffset for every (sample, vertex). */
static void unreal_source(char *out, size_t size, const cb_palette *p, const char *node_code)
{
    snprintf(out, size,
             "#define %s 1\n#define %s 1\n%s%s"
             "#include \"unreal_stub.ush\"\n"
             "#include \"/Plugin/Crowdbake/Private/Crowdbake.ush\"\n"
             "MaterialFloat3 CustomExpression0(FMaterialVertexParameters Parameters, Texture2D Palette, SamplerState PaletteSampler,\n"
             "    Texture2D BindPositions, SamplerState BindPositionsSampler, Texture2D Skin, SamplerState SkinSampler,\n"
             "    MaterialFloat3 Header, MaterialFloat3 BoundsMin, MaterialFloat3 BoundsMax, MaterialFloat2 VertexIdUV,\n"
             "    MaterialFloat3 LocalPosition, MaterialFloat3 LocalNormal, MaterialFloat4 Clip, MaterialFloat4 FromClip,\n"
             "    MaterialFloat2 Fade, MaterialFloat Time, inout MaterialFloat3 SkinnedNormal)\n"
             "{\n%s\n}\n"
             "[[vk::binding(0)]] Texture2D cb_palette_texture;\n"
             "[[vk::binding(1)]] Texture2D cb_bind_texture;\n"
             "[[vk::binding(2)]] Texture2D cb_skin_texture;\n"
             "[[vk::binding(3)]] SamplerState cb_sampler;\n"
             "[[vk::binding(4)]] cbuffer cb_test_header { " HEADER_CBUFFER " };\n"
             HARNESS_BUFFERS
             "[[vk::binding(5)]] StructuredBuffer<cb_test_vertex> cb_vertices;\n"
             "[[vk::binding(6)]] StructuredBuffer<cb_test_sample> cb_samples;\n"
             "[[vk::binding(7)]] RWStructuredBuffer<float4> cb_skinned;\n"
             "[numthreads(64, 1, 1)]\n"
             "void main(uint3 id : SV_DispatchThreadID)\n"
             "{\n"
             "    uint s = id.x / cb_vertex_count, i = id.x - s * cb_vertex_count;\n"
             "    if (s >= cb_sample_count) return;\n"
             "    cb_test_vertex v = cb_vertices[i];\n"
             "    cb_test_sample k = cb_samples[s];\n"
             "    float weight = k.fade_time_dt_mode.x, time = k.fade_time_dt_mode.y, dt = k.fade_time_dt_mode.z;\n"
             "    float2 fade = weight < 1.0 ? float2(time - weight, 1.0) : float2(0.0, 0.0); // custom data 8-9\n"
             "    float2 fade_before = weight < 1.0 ? float2(time - dt - weight, 1.0) : fade;\n"
             "    float3 header = float3(cb_row_texels, cb_rows_per_block, cb_linear_range);\n"
             "    FMaterialVertexParameters parameters;\n"
             "    parameters.WorldPosition = float3(0.0, 0.0, 0.0);\n"
             "    float3 normal = float3(0.0, 0.0, 0.0);\n"
             "    float3 offset = CustomExpression0(parameters, cb_palette_texture, cb_sampler, cb_bind_texture, cb_sampler,\n"
             "        cb_skin_texture, cb_sampler, header, cb_bounds_min, cb_bounds_max, float2(float(i), 0.0), v.position.xyz,\n"
             "        v.normal.xyz, k.inst, k.from_inst, fade, time, normal);\n"
             "    float3 before = CrowdbakeMaterialPreviousOffset(cb_palette_texture, cb_bind_texture, cb_skin_texture, header,\n"
             "        cb_bounds_min, cb_bounds_max, float(i), v.position.xyz, k.inst, k.from_inst, fade_before, time, dt);\n"
             "    cb_skinned[id.x * 3] = float4(v.position.xyz + offset, 1.0);\n"
             "    cb_skinned[id.x * 3 + 1] = float4(normal, 0.0);\n"
             "    cb_skinned[id.x * 3 + 2] = float4(v.position.xyz + before, 1.0);\n"
             "}\n",
             layout_define[p->layout], precision_define[p->precision],
             p->positions_relative ? "#define CB_POSITIONS_RELATIVE 1\n" : "",
             p->bone_space == CB_BONE_SPACE_LOCAL ? "#define CB_LOCAL_ROWS 1\n" : "", node_code);
}

/* glTF (x, y, z) metres -> Unreal (100 x, 100 z, 100 y), as Crowdbake.ush assumes by default. */
static void to_unreal(float *v, float scale)
{
    float y = v[1];
    v[0] *= scale, v[1] = v[2] * scale, v[2] = y * scale;
}

/* The mesh as Unreal holds it: positions and normals in Unreal's space (the vertex buffer), the
 * joints and weights in the skin texture by vertex id. */
static void unreal_mesh(const cb_primitive *prim, vkc_resource *vertices, vkc_resource *skin)
{
    size_t verts = prim->vertex_count, rows = (verts + SKIN_WIDTH - 1) / SKIN_WIDTH;
    float *positions = malloc(verts * 3 * sizeof(float)), *normals = malloc(verts * 3 * sizeof(float));
    float *texels = calloc(SKIN_WIDTH * rows * 2 * 4, sizeof(float));
    memcpy(positions, prim->positions, verts * 3 * sizeof(float));
    memcpy(normals, prim->normals, verts * 3 * sizeof(float));
    for (size_t v = 0; v < verts; ++v) {
        to_unreal(positions + v * 3, 100), to_unreal(normals + v * 3, 1);
        size_t x = v % SKIN_WIDTH, y = 2 * (v / SKIN_WIDTH);
        for (int k = 0; k < 4; ++k) {
            texels[(y * SKIN_WIDTH + x) * 4 + k] = (float)prim->joints[v * 4 + k];
            texels[((y + 1) * SKIN_WIDTH + x) * 4 + k] = prim->weights[v * 4 + k];
        }
    }
    cb_primitive moved = *prim;
    moved.positions = positions, moved.normals = normals;
    *vertices = upload_vertices(&vk, &moved);
    *skin = vkc_image(&vk, VK_FORMAT_R32G32B32A32_SFLOAT, SKIN_WIDTH, (uint32_t)rows * 2, 16, texels, false);
    free(positions), free(normals), free(texels);
}

/* Runs the Unreal shader over every (sample, vertex); returns 12 floats per pair, back in glTF space. */
static float *gpu_unreal(const cb_palette *p, const cb_primitive *prim, const sample *s, uint32_t n, const char *node_code)
{
    static char src[1 << 17];
    char name[64], includes[1200], cwd[512], link[600];
    unreal_source(src, sizeof src, p, node_code);
    /* Unreal's virtual path /Plugin/Crowdbake is the plugin's Shaders folder. */
    assert_non_null(getcwd(cwd, sizeof cwd));
    mkdir(TEST_TMP, 0755), mkdir(TEST_TMP "/unreal", 0755), mkdir(TEST_TMP "/unreal/Plugin", 0755);
    snprintf(link, sizeof link, "%s/" SHADERS, cwd);
    unlink(TEST_TMP "/unreal/Plugin/Crowdbake");
    assert_int_equal(symlink(link, TEST_TMP "/unreal/Plugin/Crowdbake"), 0);
    snprintf(includes, sizeof includes, "-I%s/tests/runtimes -I%s/%s/unreal", cwd, cwd, TEST_TMP);
    snprintf(name, sizeof name, "unreal_%s_%s%s", cb_layout_name(p->layout), cb_precision_name(p->precision),
             p->bone_space == CB_BONE_SPACE_LOCAL ? "_local" : "");
    size_t spv_bytes, verts = prim->vertex_count;
    uint32_t *spv = compile_hlsl(src, name, includes, &spv_bytes);
    header_block h = header_of(p, (uint32_t)verts, n);
    gpu_sample *g = gpu_samples(s, n, 0);
    vkc_resource r[8] = {upload_palette(&vk, p, true, false), upload_bind_positions(&vk, p)};
    unreal_mesh(prim, &r[5], &r[2]);
    r[3] = vkc_sampler(&vk);
    r[4] = vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &h, sizeof h);
    r[6] = vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, g, n * sizeof *g);
    r[7] = vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, NULL, n * verts * 48);
    vkc_pipeline pipe = vkc_compute(&vk, spv, spv_bytes, r, 8);
    VkCommandBuffer cmd = vkc_begin(&vk);
    vkc_dispatch(cmd, &pipe, (uint32_t)((n * verts + 63) / 64));
    vkc_submit(&vk, cmd);
    float *out = malloc(n * verts * 48);
    vkc_read(&vk, &r[7], out);
    for (size_t i = 0; i < n * verts * 3; ++i) { /* Unreal -> glTF: (x, z, y) / 100; the normal unscaled */
        float *v = out + i * 4, y = v[2];
        float scale = i % 3 == 1 ? 1.0f : 0.01f;
        v[2] = v[1] * scale, v[1] = y * scale, v[0] *= scale;
    }
    vkc_free_pipeline(&vk, &pipe);
    for (int i = 0; i < 8; ++i) vkc_free(&vk, &r[i]);
    free(spv), free(g);
    return out;
}

/* Worst position error / tolerance of the node code on a bake of `path` (local rows when `space`
 * says); normals' in *normal_ratio. */
static double run_node(const char *path, cb_layout l, cb_precision pr, cb_bone_space space, const char *node, double *normal_ratio,
                       bool print)
{
    fixture f;
    bake_space(path, l, pr, false, space, &f);
    sample samples[48];
    uint32_t n = make_samples(&f.palette, samples, 48);
    const cb_primitive *prim = &f.model->primitives[0];
    float *gpu = gpu_unreal(&f.palette, prim, samples, n, node);
    double pe, ne, tol = tolerance(&f);
    compare(&f.palette, prim, samples, n, gpu, &pe, &ne);
    if (print)
        printf("  Cow %-6s %-5s%s %u instances x %u vertices: positions %.2g, normals %.2g (tolerance %.2g, %.2g)\n",
               cb_layout_name(l), cb_precision_name(pr), space == CB_BONE_SPACE_LOCAL ? " local" : "", n, prim->vertex_count, pe, ne, tol, 1e-5);
    *normal_ratio = ne / 1e-5;
    free(gpu);
    release(&f);
    return pe / tol;
}

static void test_the_custom_node_matches_the_c_runtime(void **state)
{
    (void)state;
    if (!have_device) skip();
    char *node = read_whole_file(SHADERS "/Private/CrowdbakeCustomNode.hlsl", NULL), cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    for (int l = 0; l < 3; ++l)
        for (int pr = 0; pr < 3; ++pr) {
            double normals, positions = run_node(cow, (cb_layout)l, (cb_precision)pr, CB_BONE_SPACE_GLOBAL, node, &normals, true);
            assert_true(positions <= 1 && normals <= 1);
        }
    for (int pr = 0; pr < 3; pr += 2) { /* local rows (.pal version 6): qpos, u16 (as UNORM16) and float */
        double normals, positions = run_node(cow, CB_LAYOUT_QPOS, (cb_precision)pr, CB_BONE_SPACE_LOCAL, node, &normals, true);
        assert_true(positions <= 1 && normals <= 1);
    }
    /* Broken variant: the node with its two clips swapped (a cross-fade played backwards). */
    const char *call = "Clip, FromClip, Fade";
    char *at = strstr(node, call), *swapped = malloc(strlen(node) + 1);
    assert_non_null(at);
    sprintf(swapped, "%.*sFromClip, Clip, Fade%s", (int)(at - node), node, at + strlen(call));
    double normals, backwards = run_node(cow, CB_LAYOUT_QPOS, CB_PRECISION_U16, CB_BONE_SPACE_GLOBAL, swapped, &normals, false);
    printf("  the node with its clips swapped: error / tolerance %.0f\n", backwards);
    assert_true(backwards > 10);
    free(node), free(swapped);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_plugin_carries_the_hlsl_runtime_unchanged),
        cmocka_unit_test(test_the_custom_node_matches_the_c_runtime),
    };
    return cmocka_run_group_tests_name("unreal_shader", tests, setup, teardown);
}
