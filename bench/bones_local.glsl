// bones_local.glsl - the bone pass's fragment shader for local rows (issue 43 item 1's lever, weighed before the
// format has it): bench_gl --local-rows with BENCH_GL_PASS_GLSL=bench/bones_local.glsl draws it after the shipped
// runtimes/glsl/crowdbake_palette.glsl (qpos only), in place of its cb_bone_pass_placed main.
//
// A row of joint j holds L_j = M_p^-1 M_j (p: its nearest ancestor joint, the bone table's parent; -1: L_j = M_j),
// as qpos: v -> p_L + s_L R(q_L) (v - b_j). Each fragment (an instance's bone) blends its own two rows, then walks
// its chain to the root, blending each ancestor's two rows and composing it in front:
//   q = q_a q, s = s_a s, p = p_a + s_a rotate(q_a, p - b_a)
// (associative, so the walk goes upwards with no stack), and writes the composed bone as cb_bone_pass_placed does.
// Rows quantized per bone (bench_gl_local.h says why): the palette's box is the unit box and its range 1;
// cb_bind_positions row 2 = the bone's box min xyz and its parent in w (-1: none), row 3 = the box's extent xyz and
// the bone's scale range in w - the parent comes with the texel the decoding needs.
// #define CB_LEVEL_PROXY (timing only, wrong pixels): the work a bone does in a pass by depth levels instead - its
// own row blended, its parent's placed bone read (three float texels) and multiplied in front - no walk.

flat in vec4 v_place; flat in vec4 v_inst; flat in int v_x0; uniform float u_time;
layout(location = 0) out vec4 o_c0; layout(location = 1) out vec4 o_c1; layout(location = 2) out vec4 o_c2;

struct cb_local {
    vec4 q;
    vec3 p;
    float s;
};

// A bone's local row blended between row0 and row1, as cb_bone_affine blends a global one, and its parent.
cb_local cb_local_row(int row0, int row1, float fr, int bone, out int parent)
{
    vec4 lo = texelFetch(cb_bind_positions, ivec2(bone, 2), 0), extent = texelFetch(cb_bind_positions, ivec2(bone, 3), 0);
    parent = int(lo.w);
    vec4 q0 = cb_texel(row0, bone, 0), q1 = cb_texel(row1, bone, 0);
    if (dot(q0, q1) < 0.0) q1 = -q1;
    vec4 ps = mix(cb_texel(row0, bone, 1), cb_texel(row1, bone, 1), fr);
    return cb_local(normalize(mix(q0, q1, fr)), lo.xyz + extent.xyz * ps.xyz, extent.w * ps.w);
}

vec4 cb_quat_mul(vec4 a, vec4 b) { return vec4(a.w * b.xyz + b.w * a.xyz + cross(a.xyz, b.xyz), a.w * b.w - dot(a.xyz, b.xyz)); }

vec3 cb_quat_rotate(vec4 q, vec3 v)
{
    vec3 t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

void main()
{
    int bone = int(gl_FragCoord.x) - v_x0, row0, row1;
    float fr;
    cb_frame(v_inst, u_time, row0, row1, fr);
    int a;
    cb_local m = cb_local_row(row0, row1, fr, bone, a);
#ifndef CB_LEVEL_PROXY
    while (a >= 0) {
        int above;
        cb_local up = cb_local_row(row0, row1, fr, a, above);
        vec3 b = texelFetch(cb_bind_positions, ivec2(a, 0), 0).xyz;
        m = cb_local(cb_quat_mul(up.q, m.q), up.p + up.s * cb_quat_rotate(up.q, m.p - b), up.s * m.s);
        a = above;
    }
#endif
    mat3 lin = m.s * cb_quat_matrix(m.q); // v -> p + s R (v - b), as cb_bone_affine
    vec3 t = m.p - lin * texelFetch(cb_bind_positions, ivec2(bone, 0), 0).xyz;
    float c = cos(v_place.w), s = sin(v_place.w); // placed in the world, as cb_bone_pass_placed
    mat3 r = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c), world = r * lin;
    t = r * t + v_place.xyz;
#ifdef CB_LEVEL_PROXY
    if (a >= 0) { // the parent's placed bone, three float texels (cb_bind_positions rows 0-2 stand in for them)
        vec4 p0 = texelFetch(cb_bind_positions, ivec2(a, 0), 0), p1 = texelFetch(cb_bind_positions, ivec2(a, 1), 0),
             p2 = texelFetch(cb_bind_positions, ivec2(a, 2), 0);
        mat3 above = mat3(p0.xyz, p1.xyz, p2.xyz);
        world = above * lin, t = above * (t - v_place.xyz) + vec3(p0.w, p1.w, p2.w);
    }
#endif
    o_c0 = vec4(world[0], t.x), o_c1 = vec4(world[1], t.y), o_c2 = vec4(world[2], t.z);
}
