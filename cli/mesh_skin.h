/* mesh_skin.h - `crowdbake mesh --skin-texture FILE.cbskin`: the mesh's joints and weights by
 * vertex id, for engines whose instanced meshes carry no skin (Unreal's static meshes): the
 * Crowdbake.ush material code reads them by the vertex id `--vertex-id-uv` writes.
 *
 * The file (little-endian): "CBSKIN\r\n", u32 version (1), u32 vertex count, u32 width, u32
 * height, then width x height RGBA32F texels, rows from y = 0: vertex v's four joints (palette
 * bones) at (v % width, 2 (v / width)), its four weights (as the runtime reads them, summing to 1)
 * one row below. Vertex ids run over all parts in order, as the .glb's vertex-id channel. */
#ifndef CB_CLI_MESH_SKIN_H
#define CB_CLI_MESH_SKIN_H

#include "crowdbake/mesh.h"

#define CB_SKIN_MAGIC "CBSKIN\r\n"
#define CB_SKIN_HEADER_BYTES 24
#define CB_SKIN_MAX_WIDTH 4096 /* a texture width every target takes */

cb_status cli_write_skin_texture(const char *path, const cb_mesh *mesh, cb_error *err);

#endif
