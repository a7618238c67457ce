/* babylon.h - a palette as Babylon.js's baked vertex animation data: the JSON that
 * VertexAnimationBaker.loadBakedVertexDataFromJSON reads ({vertexData, width, height}, vertexData
 * the base64 of little-endian Float32 values) plus the clip table a scene plays it with
 * (docs/babylon.md). The matrices follow Babylon's conventions for the same glTF loaded by
 * @babylonjs/loaders, so that the file equals what Babylon's own VertexAnimationBaker bakes:
 *  - a row holds (B + 1) matrices, B the bones of Babylon's skeleton: the skin's joints (in the
 *    glTF skin's order) and the non-joint ancestors the loader makes bones of (zeros), then an
 *    identity (Babylon's extra matrix);
 *  - each joint's matrix is relative to the parent of the top of its bone chain (the skin's
 *    skeleton node, or a scene root): the loader parents the skinned mesh there, under its
 *    __root__ node whose handedness flip therefore reaches the mesh through its world matrix,
 *    never through the bones;
 *  - a loop's rows end on a closing row, the pose at its end (Babylon plays from..to once, then
 *    from + 1..to).
 * Any layout and precision decode to float matrices; float mat4 palettes hold them exactly. */
#ifndef CB_BABYLON_WRITE_H
#define CB_BABYLON_WRITE_H

#include "export.h"
#include "palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The bones of the skeleton @babylonjs/loaders builds for `skin` (joints and the non-joint
 * nodes on their chains); 0 when out of memory. */
CROWDBAKE_API uint32_t cb_babylon_bone_count(const cb_model *model, int32_t skin);

/* The rows a clip takes in the file: its palette rows, and for a loop its closing row. */
CROWDBAKE_API uint32_t cb_babylon_clip_rows(uint32_t frames, bool loops);

/* A catalog state: its name and the palette clip it plays (an index into p->clips). */
typedef struct cb_babylon_state {
    const char *name;
    uint32_t clip;
} cb_babylon_state;

typedef struct cb_babylon_write_options {
    float speed_reference;
    bool in_place;          /* baked with root motion in place (a loop's closing row then moves by
                             * the root's vertical travel alone) */
    uint64_t input_hash;    /* recorded as crowdbake.input_hash: what an up-to-date check compares */
    const cb_babylon_state *states; /* a catalog type's states (crowdbake.states), or NULL */
    uint32_t state_count;
} cb_babylon_write_options;

CROWDBAKE_API cb_status cb_babylon_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                         const cb_babylon_write_options *options, cb_error *err);

/* What an up-to-date check reads of a .bvat.json without decoding its rows: its size, its
 * rows and its input hash. Fails on a file that is not whole (its base64 not the length that
 * width x height Float32 values take). */
typedef struct cb_babylon_facts {
    uint32_t width, height;
    uint64_t input_hash;
} cb_babylon_facts;

CROWDBAKE_API cb_status cb_babylon_read_facts(const char *path, cb_babylon_facts *out, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
