/* socket.c - the nodes a game attaches props to (socket.h). */
#include "crowdbake/socket.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"
#include "foot_sole.h" /* rig_name_is_control, rig_deforming_joints */

/* The inverse of an affine matrix (column-major; last row 0 0 0 1) by cofactors; false when singular. */
static bool affine_inverse(const double *a, double out[16])
{
    double c[9] = {a[5] * a[10] - a[9] * a[6], a[9] * a[2] - a[1] * a[10], a[1] * a[6] - a[5] * a[2],
                   a[8] * a[6] - a[4] * a[10], a[0] * a[10] - a[8] * a[2], a[4] * a[2] - a[0] * a[6],
                   a[4] * a[9] - a[8] * a[5], a[8] * a[1] - a[0] * a[9], a[0] * a[5] - a[4] * a[1]};
    double det = a[0] * c[0] + a[4] * c[1] + a[8] * c[2];
    if (det == 0) return false;
    memset(out, 0, 16 * sizeof *out);
    for (int col = 0; col < 3; ++col) /* the adjugate's column col is cofactor column col, transposed */
        for (int row = 0; row < 3; ++row) out[col * 4 + row] = c[col * 3 + row] / det;
    for (int row = 0; row < 3; ++row)
        out[12 + row] = -(out[row] * a[12] + out[4 + row] * a[13] + out[8 + row] * a[14]);
    out[15] = 1;
    return true;
}

/* Divides the first three columns of `m` by the lengths of those of `frame`: the socket keeps the
 * node's orientation and position but not the scale its ancestors give it. Exporters put a unit
 * scale on the armature (Quaternius' FBX exports: 100, undone by the skinned mesh node's own 100,
 * which glTF ignores for a skinned mesh), so the node's own axes are 100 model units long and a
 * prop hung on them would be drawn 100 times its size; a unit frame keeps the prop's own scale. */
static void drop_frame_scale(double m[16], const double frame[16])
{
    for (int col = 0; col < 3; ++col) {
        const double *a = frame + col * 4;
        double length = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (length > 0)
            for (int row = 0; row < 3; ++row) m[col * 4 + row] /= length;
    }
}

/* The skin joint index of the nearest joint above node n (not n itself), or -1. */
static int32_t joint_above(const cb_model *m, const int32_t *joint_of, int32_t n)
{
    for (int32_t p = m->nodes[n].parent; p >= 0; p = m->nodes[p].parent)
        if (joint_of[p] >= 0) return joint_of[p];
    return -1;
}

/* Whether node i, hanging under joint `bone`, is a rig helper rather than a place to hang a prop:
 * its joint moves no vertex and it or its joint is named as a control (a pole target's tip,
 * "PoleTarget.L_end", is where an IK solver aims a knee; a prop hung there floats beside the leg). */
static bool rig_helper(const cb_model *m, const cb_skin *sk, const bool *deforms, uint32_t i, int32_t bone)
{
    return !deforms[bone] && (rig_name_is_control(m->nodes[i].name) || rig_name_is_control(m->nodes[sk->joints[bone]].name));
}

bool cb_socket_is_rig_helper(cb_sampler *s, int32_t node)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    const cb_skin *sk = &m->skins[skin];
    if (node < 0 || (uint32_t)node >= m->node_count) return false;
    for (uint32_t j = 0; j < sk->joint_count; ++j)
        if (sk->joints[j] == node) return false; /* a joint is no socket candidate */
    int32_t bone = -1;
    for (int32_t p = m->nodes[node].parent; p >= 0 && bone < 0; p = m->nodes[p].parent)
        for (uint32_t j = 0; j < sk->joint_count && bone < 0; ++j)
            if (sk->joints[j] == p) bone = (int32_t)j;
    bool *deforms = malloc(sk->joint_count * sizeof *deforms), helper = false;
    if (bone >= 0 && deforms) rig_deforming_joints(m, skin, deforms), helper = rig_helper(m, sk, deforms, (uint32_t)node, bone);
    free(deforms);
    return helper;
}

uint32_t cb_find_sockets(cb_sampler *s, cb_socket **out)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_skin *sk = &m->skins[cb_sampler_skin(s)];
    *out = NULL;
    int32_t *joint_of = malloc(sizeof *joint_of * (m->node_count ? m->node_count : 1));
    double *rest = malloc(sizeof *rest * 16 * sk->joint_count);
    cb_socket *list = calloc(m->node_count ? m->node_count : 1, sizeof *list);
    bool *deforms = malloc(sizeof *deforms * (sk->joint_count ? sk->joint_count : 1));
    uint32_t n = 0;
    if (joint_of && rest && list && deforms) {
        rig_deforming_joints(m, cb_sampler_skin(s), deforms);
        for (uint32_t i = 0; i < m->node_count; ++i) joint_of[i] = -1;
        for (uint32_t j = 0; j < sk->joint_count; ++j) joint_of[sk->joints[j]] = (int32_t)j;
        for (uint32_t p = 0; p < m->primitive_count; ++p) /* the skin's own meshes are skinned, not attached */
            if (m->primitives[p].skin == cb_sampler_skin(s) && joint_of[m->primitives[p].node] < 0)
                joint_of[m->primitives[p].node] = -2;
        cb_sample_joint_matrices(s, -1, 0, rest);
        const double *globals = cb_sample_globals(s, -1, 0);
        for (uint32_t i = 0; i < m->node_count; ++i) {
            int32_t bone = joint_of[i] == -1 ? joint_above(m, joint_of, (int32_t)i) : -1;
            double inverse[16];
            if (bone < 0 || rig_helper(m, sk, deforms, i, bone) || !affine_inverse(rest + (size_t)bone * 16, inverse)) continue;
            cb_socket *k = &list[n++];
            snprintf(k->name, sizeof k->name, "%s", m->nodes[i].name);
            k->node = (int32_t)i;
            k->bone = (uint32_t)bone;
            cb_mat4_mul(k->bind_transform, inverse, globals + (size_t)i * 16);
            drop_frame_scale(k->bind_transform, globals + (size_t)i * 16);
        }
    }
    free(joint_of), free(rest), free(deforms);
    if (n) *out = list;
    else free(list);
    return n;
}
