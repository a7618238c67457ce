/* fuzz_gltf.c - libFuzzer target: the glTF/GLB loader as crowdbake calls it (Draco, meshopt,
 * quantization, sparse accessors), then sampling and a small bake of whatever loads. */
#include <stdint.h>
#include <stdlib.h>

#include "crowdbake/gltf.h"
#include "crowdbake/palette.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cb_limits limits = cb_default_limits();
    limits.max_accessor_count = 1u << 16; /* keep each run small; the checks are the same */
    limits.max_joints = 256;
    limits.max_frames = 2048;
    limits.max_file_bytes = 1u << 24;
    cb_error err = {0};
    const char *name = size && data[0] == '{' ? "fuzz.gltf" : "fuzz.glb";
    cb_model *m = cb_gltf_load_memory(data, size, name, NULL, &limits, &err);
    if (!m) return 0;
    for (uint32_t s = 0; s < m->skin_count && s < 2; ++s) {
        cb_sampler *sampler = cb_sampler_create(m, (int32_t)s, &err);
        if (!sampler) break;
        cb_bake_options o = cb_default_bake_options();
        o.fps = 8;
        o.limits = limits;
        o.max_texture_size = 1024;
        uint64_t work = cb_model_skin_vertex_count(m, (int32_t)s) * 64;
        cb_palette p;
        if (work < (1u << 20) && cb_palette_bake(sampler, &o, NULL, 0, &p, &err) == CB_OK) cb_palette_free(&p);
        cb_sampler_free(sampler);
        err.status = CB_OK;
    }
    cb_model_free(m);
    return 0;
}
