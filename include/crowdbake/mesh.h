/* mesh.h - a runtime-ready mesh for a palette: joint indices as palette bones (a LOD's remap
 * applied), fewer influences per vertex, quantized attributes, K copies for runtimes without
 * instancing; and the vertex error each of those costs against the model's own 4-influence
 * skinning. gltf_mesh_write.h writes it as a .glb. */
#ifndef CB_MESH_H
#define CB_MESH_H

#include "export.h"

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_mesh_options {
    uint32_t max_influences; /* 1, 2 or 4 */
    bool quantize;           /* weights as u8 (or u16), normals as i8, texcoords as u16 where they lie in 0..1 */
    bool weights_u16;        /* quantize: weights as u16 instead of u8 (cb_mesh_build_measured picks) */
    uint32_t batch;          /* copies in one mesh (1: a plain mesh) */
    const uint32_t *remap;   /* the model skin's joint i is palette bone remap[i]; NULL: the same order */
    uint32_t bone_count;     /* palette bones */
} cb_mesh_options;

/* One primitive, `batch` copies one after another. Every array holds what the runtime reads:
 * quantized values are also given dequantized (weights, normals, texcoords), which is what the
 * error is measured on. */
typedef struct cb_mesh_part {
    uint32_t vertex_count;    /* all copies */
    uint32_t index_count;     /* all copies; a source without indices gets 0..n-1 */
    float *positions;         /* 3 per vertex */
    float *normals;           /* 3 per vertex or NULL */
    float *texcoords;         /* 2 per vertex or NULL */
    uint16_t *joints;         /* 4 per vertex: palette bones, largest weight first; unused slots 0 */
    float *weights;           /* 4 per vertex, summing to 1 (after reduction) */
    uint16_t *weights_q;      /* quantize: 4 per vertex, summing to exactly cb_mesh.weight_scale */
    int8_t *normals_i8;       /* quantize: 3 per vertex */
    uint16_t *texcoords_u16;  /* quantize, texcoords within 0..1: 2 per vertex */
    uint32_t *indices;
    float *instance_ids;      /* batch > 1: the copy (0..batch-1) of each vertex */
    /* API 3.0: what the part looks like, as the model's primitive has it. */
    const cb_material *material; /* the model's (valid while the model lives); NULL: glTF's default */
    float *colors;               /* COLOR_0, linear RGBA, 4 per vertex, or NULL */
} cb_mesh_part;

typedef struct cb_mesh {
    uint32_t part_count;
    cb_mesh_part *parts;
    uint32_t batch, max_influences, bone_count;
    bool quantized;
    uint32_t weight_scale;    /* quantize: 255 (u8 weights) or 65535 (u16) */
    double normal_error_deg;  /* quantize: the largest angle between a normal and its i8 form */
    double texcoord_error;    /* quantize: the largest change of a texcoord (u16 steps) */
} cb_mesh;

/* The primitives of `skin` in `model` as a runtime mesh. Fails on a joint outside the skin or
 * a batch whose vertices overflow 32-bit indices. */
CROWDBAKE_API cb_status cb_mesh_build(const cb_model *model, int32_t skin, const cb_mesh_options *o, cb_mesh *out,
                                      cb_error *err);
CROWDBAKE_API void cb_mesh_free(cb_mesh *mesh);

/* The bytes a runtime uploads for the mesh in the types the .glb writer gives it, each
 * attribute padded to 4 bytes: positions f32x3; normals i8x3 quantized, else f32x3; texcoords
 * u16x2 quantized (within 0..1), else f32x2; joints u8x4 for palettes of at most 256 bones (no
 * loss), else u16x4; weights u8x4 quantized, else f32x4; the instance id f32; colours f32x4. Indices u16 below
 * 65536 vertices per part (65535 is primitive restart), else u32. */
CROWDBAKE_API void cb_mesh_bytes(const cb_mesh *mesh, uint64_t *vertex_bytes, uint64_t *index_bytes);

/* The same for `copies` copies of a plain mesh (batch 1) in one batch: every vertex gains the
 * 4-byte instance id, and the indices widen to u32 once the copies pass 65535 vertices. */
CROWDBAKE_API void cb_mesh_batch_bytes(const cb_mesh *mesh, uint32_t copies, uint64_t *vertex_bytes,
                                       uint64_t *index_bytes);

/* Keeps a vertex's `max` largest weights (the first on a tie), largest first, renormalized to
 * sum 1; the other slots get joint 0 and weight 0. */
CROWDBAKE_API void cb_reduce_influences(const uint16_t joints[4], const float weights[4], uint32_t max,
                                        uint16_t out_joints[4], float out_weights[4]);
/* Weights summing to 1 as integers summing to exactly `scale` (255 or 65535; largest remainders
 * round up), as glTF's normalized UNSIGNED_BYTE / UNSIGNED_SHORT weights must. */
CROWDBAKE_API void cb_quantize_weights(const float weights[4], uint32_t scale, uint16_t out[4]);

/* The extra vertex error of a mesh: its first copy skinned with its joints and weights against
 * the model's own skinning (4 influences, the weights as stored, joints through the remap),
 * both with the palette skin's joint matrices at every frame of every clip at `fps`. */
typedef struct cb_mesh_error {
    double max;              /* model units */
    double max_mm_per_m;     /* per metre of the mesh's rest height */
    double height;
    uint64_t worst_vertex;   /* over the parts' first copies, in order */
    int32_t worst_animation; /* the palette model's clip, -1 when no frame differs */
    double worst_time;       /* clip time */
    uint32_t frames;         /* frames measured */
} cb_mesh_error;

/* With o->quantize: builds the mesh with u8 weights and keeps them when they add at most
 * max_extra_mm (mm per metre of height) to the error the same mesh has with float weights;
 * else rebuilds it with u16 weights. Measures the mesh it returns into *error. */
CROWDBAKE_API cb_status cb_mesh_build_measured(cb_sampler *palette_sampler, const cb_model *model, int32_t skin,
                                               const cb_mesh_options *o, double fps, double max_extra_mm,
                                               cb_mesh *out, cb_mesh_error *error, cb_error *err);

CROWDBAKE_API cb_status cb_mesh_measure(cb_sampler *palette_sampler, const cb_model *model, int32_t skin,
                                        const cb_mesh *mesh, const uint32_t *remap, double fps, cb_mesh_error *out,
                                        cb_error *err);

/* The animation LOD's cost (src/core/lod_error.c): how far a vertex moves when skinned with its 2
 * largest weights, or its largest alone (renormalized, as cb_reduce_influences keeps them and the
 * runtimes' LOD skins a far instance), instead of all of them, at its worst over every frame at `fps`
 * of the listed animations (count 0: every animation of the sampler's model), the frames cb_mesh_measure
 * skins. A runtime drawing an
 * instance whose size on screen is P pixels for S model units may skin it with k influences where
 * error_k / S x P is within its pixel budget. */
typedef struct cb_lod_error {
    double two, one;          /* model units */
    double height;            /* the skin's rest height (cb_skin_rest_bounds) */
    uint32_t frames;          /* frames measured */
    int32_t worst_animation;  /* where `one` is reached: the animation, -1 the rest pose */
    double worst_time;
} cb_lod_error;

CROWDBAKE_API cb_status cb_measure_lod_error(cb_sampler *sampler, double fps, const int32_t *animations, uint32_t count,
                                             cb_lod_error *out, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
