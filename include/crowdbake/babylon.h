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

/* in_place: the palette was baked with root motion in place (a loop's closing row then moves
 * by the root's vertical travel alone). */
CROWDBAKE_API cb_status cb_babylon_write(const char *path, const cb_palette *p, const cb_model *model, int32_t skin,
                                         float speed_reference, bool in_place, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
