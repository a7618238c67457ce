/* test_hlsl_conformance.c - the runtime conformance cases (conformance.h: the one set every
 * runtime's test reads) through the HLSL runtime (runtimes/hlsl/crowdbake_palette.hlsl), compiled by
 * glslang's HLSL front end and run as a compute shader on Mesa's lavapipe: every case's instances,
 * cross-fades included, skinned by cb_skin_position_crossfade, against the C runtime's expected
 * positions within 1e-5 of the model's height; every broken case it can express (bones transposed,
 * rows off by one, a shader line broken) misses by far. The bone-pass cases are the web runtime's;
 * test_hlsl_vulkan.c runs the HLSL bone pass.
 *
 * The local cases (.pal version 6, CB_LOCAL_ROWS) run through the same check, cross-fades included (conf_expected
 * fades local rows before composing, cb_runtime_matrices_crossfade); with the library's compose line removed they
 * miss by far. The timed cases (.pal version 7) read each cell's map texel from the palette (cb_frame's
 * cb_timed_map); broken-timed-map-ignored, and every timed case with the library's map read skipped, miss by far. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include "runtimes/conformance.h"
#include "runtimes/hlsl_harness.h"

#define TMP TEST_TMP "/hlsl-conformance"
#define LIBRARY "runtimes/hlsl/crowdbake_palette.hlsl"

VKC_TEST_DEVICE("the HLSL runtime")

/* The globals form, bound where the harness puts them; one invocation per (instance, vertex). */
static char *case_source(const cb_palette *p, const char *library)
{
    static char src[1 << 17];
    hlsl_globals_prefix(src, sizeof src, p, false, "");
    size_t used = strlen(src);
    snprintf(src + used, sizeof src - used,
             "%s\n" HARNESS_BUFFERS
             "struct cb_conf_instance { float4 clip; float4 from_clip; float4 fade_time; };\n"
             "[[vk::binding(3)]] StructuredBuffer<cb_test_vertex> cb_vertices;\n"
             "[[vk::binding(4)]] StructuredBuffer<cb_conf_instance> cb_instances;\n"
             "[[vk::binding(5)]] RWStructuredBuffer<float4> cb_skinned;\n"
             "[numthreads(64, 1, 1)]\n"
             "void main(uint3 id : SV_DispatchThreadID)\n"
             "{\n"
             "    uint s = id.x / cb_vertex_count, i = id.x - s * cb_vertex_count;\n"
             "    if (s >= cb_sample_count) return;\n"
             "    cb_test_vertex v = cb_vertices[i];\n"
             "    cb_conf_instance k = cb_instances[s];\n"
             "    float time = k.fade_time.z;\n"
             "    float fade = k.fade_time.y > 0.0 ? saturate((time - k.fade_time.x) / k.fade_time.y) : 1.0;\n"
             "    cb_skinned[id.x] = float4(cb_skin_position_crossfade(v.position.xyz, v.joints, v.weights, k.from_clip,\n"
             "                                                          k.clip, fade, time), 1.0);\n"
             "}\n",
             library);
    return src;
}

/* Every instance of every group of a case: the skinned positions, in the expected file's order. */
static float *gpu_case(const conformance *c, const conf_case *k, const char *library, void *ctx)
{
    (void)ctx;
    const conf_palette *p = &c->palettes[k->palette];
    const cb_primitive *prim = &p->model->primitives[0];
    size_t verts = prim->vertex_count, total = conf_positions(c, k), n = total / verts, at = 0;
    float *inst = calloc(n * 12, sizeof(float));
    for (int t = 0; t < CONF_TIMES; ++t)
        for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
            for (int i = 0; i < CONF_PER_CLIP; ++i, ++at) {
                float v[16];
                conf_instance(&p->view.clips[cl], conf_times[t], i, k->row_offset, v);
                memcpy(inst + at * 12, v + 4, 8 * sizeof(float)); /* the clip, the clip it fades from */
                inst[at * 12 + 8] = v[12], inst[at * 12 + 9] = v[13], inst[at * 12 + 10] = (float)conf_times[t];
            }
    cb_palette view = p->view; /* the view leaves the texels in the file */
    view.texels = (void *)p->pal.texels;
    size_t spv_bytes;
    char name[64];
    snprintf(name, sizeof name, "hlsl_conformance_%s", k->name);
    uint32_t *spv = compile_hlsl(case_source(&view, library), name, "", &spv_bytes);
    header_block h = header_of(&view, (uint32_t)verts, (uint32_t)n);
    vkc_resource r[6] = {upload_palette(&vk, &view, false, k->transpose), upload_bind_positions(&vk, &view),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &h, sizeof h), upload_vertices(&vk, prim),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, inst, n * 12 * sizeof(float)),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, NULL, total * 16)};
    vkc_pipeline pipe = vkc_compute(&vk, spv, spv_bytes, r, 6);
    VkCommandBuffer cmd = vkc_begin(&vk);
    vkc_dispatch(cmd, &pipe, (uint32_t)((total + 63) / 64));
    vkc_submit(&vk, cmd);
    float *out4 = malloc(total * 16), *out = malloc(total * 12);
    vkc_read(&vk, &r[5], out4);
    for (size_t i = 0; i < total; ++i) memcpy(out + i * 3, out4 + i * 4, 12);
    vkc_free_pipeline(&vk, &pipe);
    for (int i = 0; i < 6; ++i) vkc_free(&vk, &r[i]);
    free(spv), free(inst), free(out4);
    return out;
}

/* The cases of one kind with a line of the library broken (the line holding `marker` replaced by `line`): far off,
 * every one. Returns how many cases ran. */
static int check_broken_line(const conformance *c, const char *lib, const char *marker, const char *line, bool timed,
                             const char *what)
{
    char *broken = break_shader(lib, marker, line);
    int ran = 0;
    for (int i = 0; i < c->case_count; ++i) {
        const conf_case *k = &c->cases[i];
        if (timed ? !k->timed || k->broken : !k->local) continue;
        float *got = gpu_case(c, k, broken, NULL);
        double units, ratio = conformance_compare(c, k, got, &units);
        printf("  %-26s %s: %.0f tolerances off\n", k->name, what, ratio);
        assert_true(ratio > 10);
        free(got);
        ++ran;
    }
    free(broken);
    return ran;
}

static void test_conformance_cases(void **state)
{
    (void)state;
    if (!have_device) skip();
    conformance conf;
    conformance_make(&conf, TMP);
    char *lib = read_whole_file(LIBRARY, NULL);
    conformance_check_shader(&conf, lib, gpu_case, NULL); /* local cases too: the library knows CB_LOCAL_ROWS */
    /* Local rows with the compose line removed (each bone its local row alone): local_qpos_u16, local_qpos_float,
     * local_blocks, timed_local. */
    assert_int_equal(check_broken_line(&conf, lib, "cb:local-compose", "", false, "local rows, compose line removed"), 4);
    /* Timed rows (.pal version 7) with the map read replaced by the cell taken as a row (the map ignored, as a
     * runtime that knows no timed rows would play the cells). */
    assert_true(check_broken_line(&conf, lib, "cb:timed-map", "        float4 m = float4(f0, f0 + 1.0, 0.0, 1.0);", true,
                                  "timed rows, map read skipped") >= 7);
    free(lib);
    conformance_free(&conf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_conformance_cases),
    };
    return cmocka_run_group_tests_name("hlsl_conformance", tests, setup, teardown);
}
