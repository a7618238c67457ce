/* gltf_mesh_write.h - writes a runtime-ready mesh (mesh.h) as a .glb through tinygltf's
 * writer (C API over a C++ adapter), atomically.
 *
 * The file holds one skinned mesh whose JOINTS_0 are palette bones, a skin whose joints are
 * the palette's bones in palette order (flat nodes under one root, each at its bind pose, with
 * the palette model's inverse bind matrices), so any glTF viewer shows it in its bind pose and
 * a palette runtime reads joint k as bone k. Quantized attributes use KHR_mesh_quantization
 * (normals as normalized BYTE); a batch adds `_INSTANCE_ID`, SCALAR FLOAT, the copy 0..K-1 of
 * each vertex. Each part keeps its material (cb_mesh_part.material: base colour, metallic and
 * roughness, the base colour texture with its sampler, alpha mode, sides) and COLOR_0; materials,
 * textures and images are written once each, in the order the parts first use them, the images'
 * encoded bytes embedded in the binary chunk (API 3.0). asset.extras.crowdbake records the options
 * and the measured error. */
#ifndef CB_GLTF_MESH_WRITE_H
#define CB_GLTF_MESH_WRITE_H

#include "export.h"

#include "mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The custom attribute of a batch's copy index (glTF wants custom names to start with '_'). */
#define CB_INSTANCE_ID_ATTRIBUTE "_INSTANCE_ID"

CROWDBAKE_API cb_status cb_gltf_mesh_write(const char *path, const cb_mesh *mesh, const cb_model *palette_model,
                                           int32_t palette_skin, const cb_mesh_error *error, cb_error *err);

/* The same, plus TEXCOORD_<vertex_id_set> = (vertex id, 0) in every primitive: each vertex's index over
 * all parts, exact in a float, for engines that reorder vertices on import and carry no skin on
 * instanced meshes (Unreal's static meshes). Sets below it a primitive lacks are written as zeros
 * (glTF numbers sets without gaps); the caller keeps the model's own TEXCOORD_0 out of the way
 * (vertex_id_set >= 1 when the mesh has texture coordinates). asset.extras.crowdbake records
 * vertex_id_texcoord. (API 1.4) */
CROWDBAKE_API cb_status cb_gltf_mesh_write_vertex_ids(const char *path, const cb_mesh *mesh, const cb_model *palette_model,
                                                      int32_t palette_skin, const cb_mesh_error *error, uint32_t vertex_id_set,
                                                      cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
