// crowdbake_palette.glsl - skinning from a crowdbake bone-matrix palette in a vertex shader.
// GLSL 330 core and GLSL ES 3.00. Put it after your #version line and one define of each pair:
//
//   #define CB_LAYOUT_MAT4 | CB_LAYOUT_AFFINE | CB_LAYOUT_QPOS        (the .pal header's layout)
//   #define CB_PRECISION_FLOAT | CB_PRECISION_HALF | CB_PRECISION_U16 (its precision)
//   #define CB_POSITIONS_RELATIVE   when the header's flags have bit 2 (4: a half palette, version 2 or 3)
//   #define CB_INFLUENCES 1|2       optional, for a mesh written with `crowdbake mesh --max-influences 1|2`:
//                                   only that many bones per vertex are read (a far LOD's cheaper shader)
//
// Textures: cb_palette is the .pal payload as is - RGBA32F, RGBA16F, or RGBA16UI (u16, read as
// usampler2D) - width x height from the header. For qpos and CB_POSITIONS_RELATIVE,
// cb_bind_positions is an RGBA32F texture of one texel per bone and two rows: row 0 xyz = the
// bone table's bind position, row 1 xyz = the bone's position offset (cbpal_bone.position_offset:
// version 3's offset table, the bind position in version 2), which CB_POSITIONS_RELATIVE adds to
// the stored position (qpos texel 1; mat4 and affine: the translation, which then holds the
// joint's position p = M b, skinned as A (v - b) + p).
//
// Per-instance data, the roster manifest's four numbers: inst.x first row, inst.y frame count
// (negative for a one-shot: it clamps instead of wrapping), inst.z rate in rows per second,
// inst.w phase in 0..1. Time in seconds.
//
//   vec3 p = cb_skin_position(a_position, a_joints, a_weights, inst, time);
//   vec3 n = cb_skin_normal(a_normal, a_joints, a_weights, inst, time);
//   vec3 p = cb_skin_position_crossfade(a_position, a_joints, a_weights, from_inst, inst, fade, time);
//
// Motion vectors (TAA, motion blur): the time is a parameter, so the previous frame's position is
// one more call at time - dt with the same instance numbers (in a cross-fade, with the fade
// weight at time - dt), projected by the previous frame's view-projection; pass both clip
// positions to the fragment shader and divide there:
//
//   vec3 before = cb_skin_position(a_position, a_joints, a_weights, inst, time - dt);
//   v_clip_now = gl_Position; v_clip_before = u_previous_view_projection * (u_model * vec4(before, 1.0));
//   velocity = 0.5 * (v_clip_now.xy / v_clip_now.w - v_clip_before.xy / v_clip_before.w); // fragment: screen units
//
// Batches, for runtimes without instancing: `crowdbake mesh --batch K` writes one mesh of K copies
// whose attribute _INSTANCE_ID (float) is the copy, 0..K-1. With #define CB_BATCH K, the uniform
// array cb_batch_instances[K] holds each copy's four numbers, and cb_batch_instance picks them:
//
//   vec4 inst = cb_batch_instance(a_instance_id);   // then skin as above
//
// (GLSL ES 3.00 guarantees 256 vertex uniform vectors: keep K well under that, or batch fewer.)

#ifdef GL_ES
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp usampler2D;
#endif

#ifndef CB_INFLUENCES
#define CB_INFLUENCES 4
#endif

#if defined(CB_LAYOUT_MAT4)
#define CB_TEXELS_PER_BONE 4
#elif defined(CB_LAYOUT_AFFINE)
#define CB_TEXELS_PER_BONE 3
#else
#define CB_TEXELS_PER_BONE 2
#endif

#ifdef CB_PRECISION_U16
uniform usampler2D cb_palette;
uniform vec3 cb_bounds_min;   // header: bounds_min
uniform vec3 cb_bounds_max;   // header: bounds_max
uniform float cb_linear_range; // header: linear_range
#else
uniform sampler2D cb_palette;
#endif
uniform int cb_row_texels;     // header: row_texels (bones x texels per bone)
uniform int cb_rows_per_block; // header: height
#if defined(CB_LAYOUT_QPOS) || defined(CB_POSITIONS_RELATIVE)
uniform sampler2D cb_bind_positions;
#endif

#ifdef CB_BATCH
uniform vec4 cb_batch_instances[CB_BATCH];

// The per-instance numbers of a batch's copy (its _INSTANCE_ID, exact in a float).
vec4 cb_batch_instance(float instance_id)
{
    return cb_batch_instances[int(instance_id + 0.5)]; // cb:batch-id
}
#endif

#ifdef CB_PRECISION_U16
vec4 cb_snorm(uvec4 u)
{
    ivec4 s = ivec4(u) - ivec4(greaterThanEqual(u, uvec4(32768u))) * 65536;
    return max(vec4(s) / 32767.0, vec4(-1.0));
}

vec3 cb_unorm_box(uvec3 u)
{
    return cb_bounds_min + (cb_bounds_max - cb_bounds_min) * (vec3(u) / 65535.0);
}

// Texel k of a bone, decoded as crowdbake's u16 precision defines it (docs/pal-format.md).
vec4 cb_decode(uvec4 u, int k)
{
#if defined(CB_LAYOUT_QPOS)
    if (k == 0) return cb_snorm(u);
    return vec4(cb_unorm_box(u.xyz), cb_linear_range * float(u.w) / 65535.0);
#elif defined(CB_LAYOUT_AFFINE)
    vec3 lin = cb_snorm(u).xyz * cb_linear_range;
    return vec4(lin, cb_bounds_min[k] + (cb_bounds_max[k] - cb_bounds_min[k]) * (float(u.w) / 65535.0));
#else
    if (k == 3) return vec4(cb_unorm_box(u.xyz), 1.0);
    return vec4(cb_snorm(u).xyz * cb_linear_range, 0.0);
#endif
}
#endif

// Texel k of a bone in a baked row: rows wrap into column blocks of cb_rows_per_block rows.
vec4 cb_texel(int row, int bone, int k)
{
    int block = row / cb_rows_per_block;
    ivec2 xy = ivec2(block * cb_row_texels + bone * CB_TEXELS_PER_BONE + k, row - block * cb_rows_per_block);
#ifdef CB_PRECISION_U16
    return cb_decode(texelFetch(cb_palette, xy, 0), k);
#else
    return texelFetch(cb_palette, xy, 0);
#endif
}

// The two rows to blend at `time`, and the weight of the second.
void cb_frame(vec4 inst, float time, out int row0, out int row1, out float fr)
{
    float frames = abs(inst.y);
    float fpos = time * inst.z + inst.w * frames;
    float f0, f1;
    if (inst.y > 0.0) {
        fpos = mod(fpos, frames);
        f0 = floor(fpos);
        f1 = mod(f0 + 1.0, frames); // cb:wrap - a loop's last row blends into its first
    } else {
        fpos = clamp(fpos, 0.0, frames - 1.0);
        f0 = floor(fpos);
        f1 = min(f0 + 1.0, frames - 1.0);
    }
    fr = fpos - f0;
    row0 = int(inst.x + f0);
    row1 = int(inst.x + f1);
}

vec3 cb_rotate(vec4 q, vec3 v)
{
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// A bone's transform of a point (w = 1) or a direction (w = 0), blended between two rows.
vec3 cb_bone_transform(int row0, int row1, float fr, int bone, vec3 v, float w)
{
#if defined(CB_LAYOUT_QPOS)
    vec4 q0 = cb_texel(row0, bone, 0), q1 = cb_texel(row1, bone, 0);
    if (dot(q0, q1) < 0.0) q1 = -q1; // cb:hemisphere - the shorter way between the rows
    vec4 q = normalize(mix(q0, q1, fr));
    vec4 ps = mix(cb_texel(row0, bone, 1), cb_texel(row1, bone, 1), fr); // position, scale
    vec3 b = texelFetch(cb_bind_positions, ivec2(bone, 0), 0).xyz;
#ifdef CB_POSITIONS_RELATIVE
    ps.xyz += texelFetch(cb_bind_positions, ivec2(bone, 1), 0).xyz; // cb:offset - the texel holds p less the bone's offset
#endif
    return w * ps.xyz + ps.w * cb_rotate(q, v - w * b);
#else
#if defined(CB_LAYOUT_AFFINE)
    mat3x4 rows = mat3x4(mix(cb_texel(row0, bone, 0), cb_texel(row1, bone, 0), fr),
                         mix(cb_texel(row0, bone, 1), cb_texel(row1, bone, 1), fr),
                         mix(cb_texel(row0, bone, 2), cb_texel(row1, bone, 2), fr)); // texel k = row k
    mat4 m = transpose(mat4(rows[0], rows[1], rows[2], vec4(0.0, 0.0, 0.0, 1.0)));
#else
    mat4 m = mat4(mix(cb_texel(row0, bone, 0), cb_texel(row1, bone, 0), fr),
                  mix(cb_texel(row0, bone, 1), cb_texel(row1, bone, 1), fr),
                  mix(cb_texel(row0, bone, 2), cb_texel(row1, bone, 2), fr),
                  mix(cb_texel(row0, bone, 3), cb_texel(row1, bone, 3), fr)); // texel k = column k
#endif
#ifdef CB_POSITIONS_RELATIVE
    // The translation holds the joint's position less the bone's offset: A (v - b) + p.
    vec3 b = texelFetch(cb_bind_positions, ivec2(bone, 0), 0).xyz;
    vec3 p = m[3].xyz + texelFetch(cb_bind_positions, ivec2(bone, 1), 0).xyz; // cb:offset-matrix
    return mat3(m) * (v - w * b) + w * p;
#else
    return (m * vec4(v, w)).xyz;
#endif
#endif
}

vec3 cb_skin(vec3 v, float w, ivec4 joints, vec4 weights, vec4 inst, float time)
{
    int row0, row1;
    float fr;
    cb_frame(inst, time, row0, row1, fr);
    vec3 r = vec3(0.0);
    for (int i = 0; i < CB_INFLUENCES; ++i) // cb:influences - crowdbake mesh puts the largest weights first
        if (weights[i] != 0.0) r += weights[i] * cb_bone_transform(row0, row1, fr, joints[i], v, w);
    return r;
}

vec3 cb_skin_position(vec3 v, ivec4 joints, vec4 weights, vec4 inst, float time)
{
    return cb_skin(v, 1.0, joints, weights, inst, time);
}

vec3 cb_skin_normal(vec3 n, ivec4 joints, vec4 weights, vec4 inst, float time)
{
    return normalize(cb_skin(n, 0.0, joints, weights, inst, time));
}

// Cross-fade from a previous clip (from_inst) to the current one: fade goes 0 -> 1.
vec3 cb_skin_position_crossfade(vec3 v, ivec4 joints, vec4 weights, vec4 from_inst, vec4 inst, float fade, float time)
{
    return mix(cb_skin(v, 1.0, joints, weights, from_inst, time), cb_skin(v, 1.0, joints, weights, inst, time), fade);
}

vec3 cb_skin_normal_crossfade(vec3 n, ivec4 joints, vec4 weights, vec4 from_inst, vec4 inst, float fade, float time)
{
    return normalize(mix(cb_skin(n, 0.0, joints, weights, from_inst, time), cb_skin(n, 0.0, joints, weights, inst, time), fade));
}
