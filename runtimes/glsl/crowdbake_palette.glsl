// crowdbake_palette.glsl - skinning from a crowdbake bone-matrix palette in a vertex shader.
// GLSL 330 core and GLSL ES 3.00. Put it after your #version line and one define of each pair:
//
//   #define CB_LAYOUT_MAT4 | CB_LAYOUT_AFFINE | CB_LAYOUT_QPOS        (the .pal header's layout)
//   #define CB_PRECISION_FLOAT | CB_PRECISION_HALF | CB_PRECISION_U16 (its precision)
//   #define CB_POSITIONS_RELATIVE   when the header's flags have bit 2 (4: a half palette, version 2 or 3)
//   #define CB_LOCAL_ROWS           when the header's flags have bit 5 (32: local rows, .pal version 6; qpos and
//                                   u16 or float): each row holds a bone in its parent's frame, and every bone
//                                   read is composed by walking its chain to the root (below)
//   #define CB_INFLUENCES 1|2       optional, for a mesh written with `crowdbake mesh --max-influences 1|2`:
//                                   only that many bones per vertex are read (a far LOD's cheaper shader);
//                                   with CB_BONE_TEXTURE also the animation LOD's far tiers drawn apart
//                                   (the kept weights then scaled to sum to 1, as the run-time tier does)
//
// Textures: cb_palette is the .pal payload as is - RGBA32F, RGBA16F, or RGBA16UI (u16, read as
// usampler2D) - width x height from the header. For qpos and CB_POSITIONS_RELATIVE,
// cb_bind_positions is an RGBA32F texture of one texel per bone and two rows: row 0 xyz = the
// bone table's bind position, row 1 xyz = the bone's position offset (cbpal_bone.position_offset:
// version 3's offset table, the bind position in version 2), which CB_POSITIONS_RELATIVE adds to
// the stored position (qpos texel 1; mat4 and affine: the translation, which then holds the
// joint's position p = M b, skinned as A (v - b) + p).
//
// Local rows (CB_LOCAL_ROWS): cb_bind_positions has 5 rows: row 2 x = the bone's parent (the bone table's
// `parent`, a float, -1 for a root), row 3 = (pos_min.xyz, scale_max) and row 4 = (pos_max.xyz, 0) from the
// file's bone range table (u16 positions and scales decode with the bone's own ranges; float files ignore them).
// A bone's two rows are blended in its parent's frame, then composed with each ancestor's, blended alike, up to
// the root - in the direct path per influence and vertex, in the bone pass once per instance and bone.
//
// Per-instance data, the roster manifest's four numbers: inst.x first row (negative for a clip
// whose rows are held, not blended - .pal clip flag bit 2, a STEP-keyed clip: its first row is
// -inst.x - 1), inst.y frame count (negative for a one-shot: it clamps instead of wrapping),
// inst.z rate in rows per second, inst.w phase in 0..1. Time in seconds. A timed clip (.pal version 7, clip flag
// bit 3) has inst.y its cells (negative for a one-shot) and inst.z = -(cells per second x rate): negative marks it,
// and cb_frame reads which two rows to blend, and their weight, from the clip's map rows in cb_palette itself (the
// texel of its cell in the rows just before its first; docs/pal-format.md "Timed rows").
//
//   vec3 p, n;
//   cb_skin_position_normal(a_position, a_normal, a_joints, a_weights, inst, time, p, n);  // both, each texel read once
//   vec3 p = cb_skin_position(a_position, a_joints, a_weights, inst, time);                // or one of them
//   vec3 n = cb_skin_normal(a_normal, a_joints, a_weights, inst, time);
//   cb_skin_position_normal_crossfade(a_position, a_normal, a_joints, a_weights, from_inst, inst, fade, time, p, n);
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

#if defined(CB_LOCAL_ROWS) && (!defined(CB_LAYOUT_QPOS) || defined(CB_PRECISION_HALF) || defined(CB_POSITIONS_RELATIVE))
#error "CB_LOCAL_ROWS: local rows need CB_LAYOUT_QPOS and CB_PRECISION_U16 or CB_PRECISION_FLOAT (.pal flag bit 5)"
#endif
#ifndef CB_MAX_CHAIN
#define CB_MAX_CHAIN 64 // ancestors a local bone's walk visits at most (the shared models' deepest chain: 11)
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

// Where texel x of a row lies (x < cb_row_texels): rows wrap into column blocks of cb_rows_per_block rows.
ivec2 cb_texel_xy(int row, int x)
{
    int block = row / cb_rows_per_block;
    return ivec2(block * cb_row_texels + x, row - block * cb_rows_per_block);
}

// Texel k of a bone in a baked row.
vec4 cb_texel(int row, int bone, int k)
{
    ivec2 xy = cb_texel_xy(row, bone * CB_TEXELS_PER_BONE + k);
#ifdef CB_PRECISION_U16
    return cb_decode(texelFetch(cb_palette, xy, 0), k);
#else
    return texelFetch(cb_palette, xy, 0);
#endif
}

// A timed clip's map texel of cell `cell`: (r0, r1, f0, f1), the two rows blended in the cell (relative to the clip's
// first row) and the second's weight at the cell's start and end. The map's ceil(cells / cb_row_texels) rows lie just
// before the first row, one texel a cell; u16 holds the rows as integers and the weights as f x 65535, never decoded
// through a bone's range (docs/pal-format.md "Timed rows").
vec4 cb_timed_map(int first, int cells, int cell)
{
    int map_rows = (cells + cb_row_texels - 1) / cb_row_texels, line = cell / cb_row_texels;
    ivec2 xy = cb_texel_xy(first - map_rows + line, cell - line * cb_row_texels);
#ifdef CB_PRECISION_U16
    uvec4 u = texelFetch(cb_palette, xy, 0);
    return vec4(vec2(u.xy), vec2(u.zw) / 65535.0);
#else
    return texelFetch(cb_palette, xy, 0);
#endif
}

// The two rows to blend at `time`, and the weight of the second: the rows either side of time x rate (a loop's last
// blending into its first), or for a timed clip (inst.z < 0) the two its map names for the cell at time x |rate|.
void cb_frame(vec4 inst, float time, out int row0, out int row1, out float fr)
{
    bool held = inst.x < 0.0; // a stepped clip: its row alone, no blend across a step
    float first = held ? -inst.x - 1.0 : inst.x;
    float frames = abs(inst.y); // rows; a timed clip's cells
    float fpos = time * abs(inst.z) + inst.w * frames;
    float f0, f1;
    if (inst.z < 0.0) { // a timed clip: its cell's map texel
        fpos = inst.y > 0.0 ? mod(fpos, frames) : clamp(fpos, 0.0, frames);
        float cell = min(floor(fpos), frames - 1.0); // a one-shot's end (and a loop's rounding onto n): the last cell's end
        vec4 m = cb_timed_map(int(first), int(frames), int(cell)); // cb:timed-map
        f0 = m.x, f1 = m.y;
        fr = m.z + (m.w - m.z) * (fpos - cell); // linear in the cell, so exact between rows
    } else {
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
    }
    if (held) { f1 = f0; fr = 0.0; } // cb:held - no blend across a step
    row0 = int(first + f0);
    row1 = int(first + f1);
}

// The rotation matrix of a unit quaternion (x, y, z, w).
mat3 cb_quat_matrix(vec4 q)
{
    vec3 q2 = 2.0 * q.xyz, w2 = q.w * q2;
    vec3 d = q.xyz * q2;                          // 2xx, 2yy, 2zz
    vec3 o = q.xyz * q2.yzx;                      // 2xy, 2yz, 2zx
    return mat3(1.0 - d.y - d.z, o.x + w2.z, o.z - w2.y,
                o.x - w2.z, 1.0 - d.x - d.z, o.y + w2.x,
                o.z + w2.y, o.y - w2.x, 1.0 - d.x - d.y);
}

// A bone's transform: a point v goes to a * v + t, a direction n to a * n.
struct cb_affine {
    mat3 a;
    vec3 t;
};

// A bone's transform blended between two rows. Each of its texels is fetched once, whatever is
// skinned with it (a position and a normal share it).
cb_affine cb_bone_affine(int row0, int row1, float fr, int bone)
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
    mat3 a = ps.w * cb_quat_matrix(q); // v -> p + s R (v - b)
    return cb_affine(a, ps.xyz - a * b);
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
    return cb_affine(mat3(m), p - mat3(m) * b);
#else
    return cb_affine(mat3(m), m[3].xyz);
#endif
#endif
}

// A cross-fade of two transforms: from f (fade 0) to m (fade 1).
cb_affine cb_affine_mix(cb_affine f, cb_affine m, float fade)
{
    return cb_affine(m.a * fade + f.a * (1.0 - fade), mix(f.t, m.t, fade));
}

#ifdef CB_LOCAL_ROWS
// ---- Local rows: a bone in its parent's frame (q, p, s: v -> p + s R(q) (v - b_bone)), composed up its chain ----

struct cb_local {
    vec4 q;
    vec3 p;
    float s;
};

// Texel 1 (position, scale) of a local bone between two rows. u16: blended as stored, then scaled once into the
// bone's own ranges (cb_bind_positions rows 3 and 4; linear, so the same as decoding each row first).
vec4 cb_local_position_scale(int row0, int row1, float fr, int bone)
{
    int x = bone * CB_TEXELS_PER_BONE + 1;
    ivec2 xy0 = cb_texel_xy(row0, x), xy1 = cb_texel_xy(row1, x);
#ifdef CB_PRECISION_U16
    vec4 u = mix(vec4(texelFetch(cb_palette, xy0, 0)), vec4(texelFetch(cb_palette, xy1, 0)), fr) / 65535.0;
    vec4 lo = texelFetch(cb_bind_positions, ivec2(bone, 3), 0), hi = texelFetch(cb_bind_positions, ivec2(bone, 4), 0);
    return vec4(lo.xyz + (hi.xyz - lo.xyz) * u.xyz, lo.w * u.w); // cb:local-ranges - pos_min..pos_max, 0..scale_max
#else
    return mix(texelFetch(cb_palette, xy0, 0), texelFetch(cb_palette, xy1, 0), fr);
#endif
}

// A bone's local row blended between row0 and row1, as cb_bone_affine blends a global qpos row.
cb_local cb_local_blend(int row0, int row1, float fr, int bone)
{
    vec4 q0 = cb_texel(row0, bone, 0), q1 = cb_texel(row1, bone, 0);
    if (dot(q0, q1) < 0.0) q1 = -q1; // the shorter way between the rows
    vec4 ps = cb_local_position_scale(row0, row1, fr, bone);
    return cb_local(normalize(mix(q0, q1, fr)), ps.xyz, ps.w);
}

// A cross-fade of two blended local rows, from f (fade 0) to m (fade 1), blended as two rows are.
cb_local cb_local_mix(cb_local f, cb_local m, float fade)
{
    if (dot(f.q, m.q) < 0.0) m.q = -m.q;
    return cb_local(normalize(mix(f.q, m.q, fade)), mix(f.p, m.p, fade), mix(f.s, m.s, fade));
}

// A bone's local transform at this moment: its rows blended, and cross-faded from the other clip's (fade < 1).
cb_local cb_local_at(ivec2 rows, float fr, ivec2 from_rows, float from_fr, float fade, int bone)
{
    cb_local m = cb_local_blend(rows.x, rows.y, fr, bone);
    if (fade < 1.0) m = cb_local_mix(cb_local_blend(from_rows.x, from_rows.y, from_fr, bone), m, fade); // cb:local-fade
    return m;
}

int cb_parent(int bone) { return int(texelFetch(cb_bind_positions, ivec2(bone, 2), 0).x); }

vec4 cb_quat_mul(vec4 a, vec4 b) { return vec4(a.w * b.xyz + b.w * a.xyz + cross(a.xyz, b.xyz), a.w * b.w - dot(a.xyz, b.xyz)); }

vec3 cb_quat_rotate(vec4 q, vec3 v)
{
    vec3 t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

// The composed (skinning) transform of a bone of local rows: its own local transform, then each ancestor's put in
// front, q = q_a q, s = s_a s, p = p_a + s_a rotate(q_a, p - b_a) - associative, so the walk goes up the chain
// with no stack and no parent-first order (a parent may come after its child in the bone table).
cb_affine cb_bone_local(ivec2 rows, float fr, ivec2 from_rows, float from_fr, float fade, int bone)
{
    cb_local m = cb_local_at(rows, fr, from_rows, from_fr, fade, bone);
    int a = cb_parent(bone);
    for (int depth = 0; a >= 0 && depth < CB_MAX_CHAIN; ++depth) { // cb:local-walk (the bound: a loader checked the table)
        cb_local up = cb_local_at(rows, fr, from_rows, from_fr, fade, a);
        vec3 b = texelFetch(cb_bind_positions, ivec2(a, 0), 0).xyz;
        m = cb_local(cb_quat_mul(up.q, m.q), up.p + up.s * cb_quat_rotate(up.q, m.p - b), up.s * m.s); // cb:local-compose
        a = cb_parent(a);
    }
    mat3 lin = m.s * cb_quat_matrix(normalize(m.q)); // v -> p + s R (v - b), as cb_bone_affine
    return cb_affine(lin, m.p - lin * texelFetch(cb_bind_positions, ivec2(bone, 0), 0).xyz);
}
#endif

// How many of a vertex's influences to read: up to its last nonzero weight, at most CB_INFLUENCES.
// CPU rasterisers (SwiftShader, llvmpipe) shade several vertices at once and run a masked-off `if`
// all the same, but leave a loop once none of their vertices goes on: a loop this long reads
// 2.5 bones a vertex on Cow, not 4.
int cb_influence_count(vec4 weights)
{
    return min(CB_INFLUENCES, weights.w != 0.0 ? 4 : weights.z != 0.0 ? 3 : weights.y != 0.0 ? 2 : 1);
}

// Skins a position v and a normal n (not normalized) in one pass over the influences, cross-faded
// from from_inst (fade 0 -> 1; 1: inst alone): each bone's texels are fetched once for both.
// Blending the bones' transforms is blending what they skin: both are linear in them.
void cb_skin_both(vec3 v, vec3 n, ivec4 joints, vec4 weights, vec4 from_inst, vec4 inst, float fade, float time,
                  out vec3 p, out vec3 skinned_n)
{
    int row0, row1, from0, from1;
    float fr, from_fr;
    cb_frame(inst, time, row0, row1, fr);
    cb_frame(from_inst, time, from0, from1, from_fr);
    p = vec3(0.0);
    skinned_n = vec3(0.0);
    // cb:influences - up to the last nonzero weight (crowdbake mesh puts the largest first), a loop and
    // not an `if` per influence, which a CPU rasteriser's vertex lanes would all pay for.
    for (int i = 0; i < cb_influence_count(weights); ++i) {
#ifdef CB_LOCAL_ROWS
        cb_affine m = cb_bone_local(ivec2(row0, row1), fr, ivec2(from0, from1), from_fr, fade, joints[i]);
#else
        cb_affine m = cb_bone_affine(row0, row1, fr, joints[i]);
        if (fade < 1.0) m = cb_affine_mix(cb_bone_affine(from0, from1, from_fr, joints[i]), m, fade);
#endif
        p += weights[i] * (m.a * v + m.t);
        skinned_n += weights[i] * (m.a * n);
    }
}

vec3 cb_skin_position(vec3 v, ivec4 joints, vec4 weights, vec4 inst, float time)
{
    vec3 p, n;
    cb_skin_both(v, vec3(0.0), joints, weights, inst, inst, 1.0, time, p, n);
    return p;
}

vec3 cb_skin_normal(vec3 n, ivec4 joints, vec4 weights, vec4 inst, float time)
{
    vec3 p, skinned_n;
    cb_skin_both(vec3(0.0), n, joints, weights, inst, inst, 1.0, time, p, skinned_n);
    return normalize(skinned_n);
}

// The position and the normal together, for the price of one (the runtimes' vertex shaders use it).
void cb_skin_position_normal(vec3 v, vec3 n, ivec4 joints, vec4 weights, vec4 inst, float time, out vec3 p, out vec3 skinned_n)
{
    cb_skin_both(v, n, joints, weights, inst, inst, 1.0, time, p, skinned_n);
    skinned_n = normalize(skinned_n);
}

// Cross-fade from a previous clip (from_inst) to the current one: fade goes 0 -> 1.
void cb_skin_position_normal_crossfade(vec3 v, vec3 n, ivec4 joints, vec4 weights, vec4 from_inst, vec4 inst, float fade,
                                       float time, out vec3 p, out vec3 skinned_n)
{
    cb_skin_both(v, n, joints, weights, from_inst, inst, fade, time, p, skinned_n);
    skinned_n = normalize(skinned_n);
}

vec3 cb_skin_position_crossfade(vec3 v, ivec4 joints, vec4 weights, vec4 from_inst, vec4 inst, float fade, float time)
{
    vec3 p, n;
    cb_skin_both(v, vec3(0.0), joints, weights, from_inst, inst, fade, time, p, n);
    return p;
}

vec3 cb_skin_normal_crossfade(vec3 n, ivec4 joints, vec4 weights, vec4 from_inst, vec4 inst, float fade, float time)
{
    vec3 p, skinned_n;
    cb_skin_both(vec3(0.0), n, joints, weights, from_inst, inst, fade, time, p, skinned_n);
    return normalize(skinned_n);
}

// Animation LOD: how many influences an instance `pixels` tall on screen reads - its largest alone under
// `one` pixels, its 2 largest under `two`, else every one (a tier of 0 never applies) - as a far LOD mesh
// of crowdbake mesh --max-influences 1|2 would (cb_skin_bone_pass_influences reads that many).
int cb_lod_influences(float pixels, float two, float one)
{
    return pixels < one ? 1 : pixels < two ? 2 : CB_INFLUENCES;
}

// ---- The bone pass: each instance's bones blended once a frame instead of once a vertex ----
// A fragment shader, one fragment per (instance, bone), writes cb_bone_pass's three texels to three
// RGBA32F render targets (bone textures: instance i's bone j at (block * bones + j, i - block *
// cb_bone_rows), block = i / cb_bone_rows); a vertex shader compiled with #define CB_BONE_TEXTURE
// then skins from them, three plain texel fetches an influence, no decoding and no blending:
//
//   cb_bone_pass(int(gl_FragCoord.x) - first_bone_x, from_inst, inst, fade, time, out0, out1, out2); // fragment
//   cb_skin_bone_pass(a_position, a_normal, a_joints, a_weights, gl_InstanceID, p, n);                 // vertex
//
// (runtimes/web/crowdbake_crowd.mjs's bonePass option runs both.)

// Bone `bone` of an instance: the columns of its transform, translation in w.
void cb_bone_pass(int bone, vec4 from_inst, vec4 inst, float fade, float time, out vec4 c0, out vec4 c1, out vec4 c2)
{
    int row0, row1;
    float fr;
    cb_frame(inst, time, row0, row1, fr);
#ifdef CB_LOCAL_ROWS
    int from0, from1;
    float from_fr;
    cb_frame(from_inst, time, from0, from1, from_fr);
    cb_affine m = cb_bone_local(ivec2(row0, row1), fr, ivec2(from0, from1), from_fr, fade, bone); // its chain composed
#else
    cb_affine m = cb_bone_affine(row0, row1, fr, bone);
    if (fade < 1.0) {
        cb_frame(from_inst, time, row0, row1, fr);
        m = cb_affine_mix(cb_bone_affine(row0, row1, fr, bone), m, fade);
    }
#endif
    c0 = vec4(m.a[0], m.t.x), c1 = vec4(m.a[1], m.t.y), c2 = vec4(m.a[2], m.t.z);
}

// The same bone already placed in the world: the instance's yaw (place.w, about +y), uniform scale and
// position (place.xyz) applied once per bone, so the draw skins straight to world space and no
// vertex pays for a sine, a cosine and a yaw matrix (cb_skin_bone_pass then gives world p and n).
void cb_bone_pass_placed(int bone, vec4 from_inst, vec4 inst, float fade, float time, vec4 place, float scale,
                         out vec4 c0, out vec4 c1, out vec4 c2)
{
    cb_bone_pass(bone, from_inst, inst, fade, time, c0, c1, c2);
    float c = cos(place.w), s = sin(place.w);
    mat3 r = scale * mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
    mat3 a = r * mat3(c0.xyz, c1.xyz, c2.xyz);
    vec3 t = r * vec3(c0.w, c1.w, c2.w) + place.xyz;
    c0 = vec4(a[0], t.x), c1 = vec4(a[1], t.y), c2 = vec4(a[2], t.z);
}

#ifdef CB_BONE_TEXTURE
uniform sampler2D cb_bones0, cb_bones1, cb_bones2; // the bone pass's three targets
uniform int cb_bone_rows;                          // instances per column block of them

// The position and the normal (normalized) of a vertex of instance `instance`, from the bone pass,
// reading its first `influences` bones (animation LOD: fewer for a far instance; fewer than 4 are
// scaled to sum to 1, so the influences must come largest first, as crowdbake mesh writes them
// and the runtimes sort them). The influences' transforms are blended first and applied once
// (12 multiply-adds an influence, not 24, and the instance's column block found once a vertex).
// At most CB_INFLUENCES are read: a program compiled with CB_INFLUENCES 1 or 2 draws the LOD's far
// tiers apart (cb_skin_bone_pass, the instances sorted by tier on the CPU by cb_lod_influences's rule), the same
// pixels as the run-time tier without paying for it per vertex.
void cb_skin_bone_pass_influences(vec3 v, vec3 n, ivec4 joints, vec4 weights, int instance, int influences,
                                  out vec3 p, out vec3 skinned_n)
{
    // cb:bone-block - the column block by a float division (a CPU rasteriser divides integers lane by lane),
    // (i + 0.5) / rows, half a row from any integer; the remainder then corrects a quotient off by one.
    int block = int((float(instance) + 0.5) / float(cb_bone_rows)), y = instance - block * cb_bone_rows;
    block += y < 0 ? -1 : y >= cb_bone_rows ? 1 : 0;
    y = instance - block * cb_bone_rows;
    int x0 = block * (cb_row_texels / CB_TEXELS_PER_BONE);
    vec4 c0, c1, c2;
#if CB_INFLUENCES == 1
    // cb:tier-one - one influence compiled in (a far LOD tier drawn apart, or a mesh of one influence): its bone
    // alone, its weight taken as 1 - no count, no loop, no test a vertex (what the run-time tier pays for).
    ivec2 xy = ivec2(x0 + joints[0], y);
    c0 = texelFetch(cb_bones0, xy, 0), c1 = texelFetch(cb_bones1, xy, 0), c2 = texelFetch(cb_bones2, xy, 0);
#else
    int count = min(influences, cb_influence_count(weights)); // cb_influence_count says why a loop
    if (count == 1) { // the largest bone alone (a far instance's LOD, or a vertex of one bone): no blend
        ivec2 xy = ivec2(x0 + joints[0], y);
        float w = influences < 4 ? 1.0 : weights[0]; // the kept weight scaled to 1
        c0 = w * texelFetch(cb_bones0, xy, 0), c1 = w * texelFetch(cb_bones1, xy, 0), c2 = w * texelFetch(cb_bones2, xy, 0);
    } else {
        c0 = vec4(0.0), c1 = vec4(0.0), c2 = vec4(0.0);
        float sum = 0.0;
        for (int i = 0; i < count; ++i) {
            ivec2 xy = ivec2(x0 + joints[i], y);
            c0 += weights[i] * texelFetch(cb_bones0, xy, 0);
            c1 += weights[i] * texelFetch(cb_bones1, xy, 0);
            c2 += weights[i] * texelFetch(cb_bones2, xy, 0);
            sum += weights[i];
        }
        if (influences < 4) { // cb:lod-weights - the kept weights sum to 1 (one division, not twelve)
            float r = 1.0 / sum;
            c0 *= r, c1 *= r, c2 *= r;
        }
    }
#endif
    mat3 a = mat3(c0.xyz, c1.xyz, c2.xyz); // cb:bone-columns
    p = a * v + vec3(c0.w, c1.w, c2.w);
    skinned_n = normalize(a * n);
}

void cb_skin_bone_pass(vec3 v, vec3 n, ivec4 joints, vec4 weights, int instance, out vec3 p, out vec3 skinned_n)
{
    cb_skin_bone_pass_influences(v, n, joints, weights, instance, CB_INFLUENCES, p, skinned_n);
}
#endif
