/* gltf.h - loads a .glb or .gltf file into a cb_model (C API over a C++ adapter).
 *
 * Handles KHR_draco_mesh_compression, KHR_mesh_quantization, EXT_meshopt_compression,
 * sparse accessors, embedded data URIs and external buffers. Images are never decoded.
 * The returned model is validated (cb_model_validate) and owned by the caller.
 */
#ifndef CB_GLTF_LOAD_H
#define CB_GLTF_LOAD_H

#include "export.h"

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* NULL on failure, with err filled ("FILE: what is wrong"). limits may be NULL. */
CROWDBAKE_API cb_model *cb_gltf_load(const char *path, const cb_limits *limits, cb_error *err);
/* Same, from bytes in memory (a GLB, or glTF JSON with embedded data); base_dir resolves
 * external URIs (NULL forbids them). Used by the fuzzers. */
CROWDBAKE_API cb_model *cb_gltf_load_memory(const unsigned char *data, size_t size, const char *name,
                                            const char *base_dir, const cb_limits *limits, cb_error *err);
/* Whether these bytes (a GLB) load on the fast path: RapidJSON reads the JSON and the BIN
 * chunk's accessors are used where they lie. Every other file loads through tinygltf, with the
 * same result. For tests and benchmarks, which must know which path they ran. */
CROWDBAKE_API bool cb_gltf_fast_path_applies(const unsigned char *data, size_t size);

#ifdef __cplusplus
}
#endif

#endif
