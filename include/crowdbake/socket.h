/* socket.h - where a game attaches a mesh to an animated instance: the nodes that hang under a
 * joint of the skin without being joints themselves (props, rigid meshes, exporters' empties
 * such as Blender's "_end" tips), each with its bone and its frame in bind space. The posed
 * socket is the bone's skinning matrix (what the palette stores, cbpal_bone_matrix) times the
 * socket's bind transform: posed = J(t) B = G_joint(t) IBM B, and B = J_rest^-1 G_socket_rest S^-1,
 * so in the rest pose it is the node's own global transform without its scale S (the lengths of
 * its axes: a prop keeps its own size in the model's units even where an ancestor, such as an
 * armature exported with scale 100, scales the node) and it follows the joint rigidly. */
#ifndef CB_SOCKET_H
#define CB_SOCKET_H

#include "export.h"
#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_socket {
    char name[64];             /* the node's name (cut at 63 bytes) */
    int32_t node;
    uint32_t bone;             /* the nearest joint above it: its palette bone */
    double bind_transform[16]; /* column-major: the socket's frame in bind space */
} cb_socket;

/* The sampler's skin's sockets, in node order: their count, and in *out an array to free()
 * (NULL when there are none or memory ran out). Skinned mesh nodes of the skin are not sockets,
 * nor are rig helpers (cb_socket_is_rig_helper). */
CROWDBAKE_API uint32_t cb_find_sockets(cb_sampler *sampler, cb_socket **out);

/* Whether a node under a joint is a rig helper, not a socket: its joint moves no vertex and it or
 * its joint is named as a control (an IK target, a pole target such as "PoleTarget.L_end", a
 * "_ctrl"): a prop hung there would float beside the body. */
CROWDBAKE_API bool cb_socket_is_rig_helper(cb_sampler *sampler, int32_t node);

#ifdef __cplusplus
}
#endif

#endif
