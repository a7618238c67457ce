// crowdbake_palette.hlsl - skinning from a crowdbake bone-matrix palette, in HLSL (Shader Model 5).
// The HLSL twin of runtimes/glsl/crowdbake_palette.glsl: the same functions under the same names,
// the same math in the same order, the same defines. Unity (built-in pipeline, URP, Shader Graph
// Custom Function) and Unreal (runtimes/unreal/Crowdbake/Shaders/Private/Crowdbake.ush) include it.
//
// Defines, as in the GLSL (one of each pair):
//   #define CB_LAYOUT_MAT4 | CB_LAYOUT_AFFINE | CB_LAYOUT_QPOS        (the .pal header's layout)
//   #define CB_PRECISION_FLOAT | CB_PRECISION_HALF | CB_PRECISION_U16 (its precision)
//   #define CB_POSITIONS_RELATIVE   when the header's flags have bit 2 (4)
//   #define CB_INFLUENCES 1|2       for a mesh written with `crowdbake mesh --max-influences 1|2`
//   #define CB_BATCH K              a `crowdbake mesh --batch K` mesh (globals: cb_batch_instances[K])
//   #define CB_BONE_TEXTURE         skin from the bone pass's three textures (cb_skin_bone_pass)
//   #define CB_LOCAL_ROWS           the header's flags have bit 5 (.pal version 6, qpos, u16 or float): rows hold
//                                   each bone in its parent's frame; cb_bind_positions has 5 rows (see below)
// HLSL only:
//   #define CB_U16_UNORM            a u16 palette bound as RGBA16 UNORM (a float texture; engines whose
//                                   texture assets have no RGBA16UI: Unreal's PF_R16G16B16A16_UNORM,
//                                   Unity's RGBA64 / R16G16B16A16_UNorm) instead of RGBA16UI
//   #define CB_NO_GLOBALS           declare no globals: only the explicit forms below (Unreal's
//                                   Custom node passes textures and numbers as arguments)
//   #define CB_TEXTURES_DECLARED    you declared cb_palette, cb_bind_positions (and cb_bones0..2) yourself
//   #define CB_HEADER_DECLARED      you declared cb_row_texels ... cb_linear_range yourself (for example in
//                                   Unity's UnityPerMaterial cbuffer, for the SRP Batcher)
//
// Texture access goes through two macros, so an engine can change both:
//   CB_TEXTURE2D        the type of a float texture: Texture2D<float4>
//   CB_LOAD(tex, xy)    one texel by integer coordinates, mip 0: (tex).Load(int3(xy, 0))
// The u16 palette is a Texture2D<uint4> (RGBA16UI), or CB_TEXTURE2D with CB_U16_UNORM.
//
// Two forms of every skinning function, overloads of one name:
//   globals (as the GLSL):  cb_skin_position(v, joints, weights, inst, time)
//       textures cb_palette, cb_bind_positions; numbers cb_row_texels, cb_rows_per_block (floats here:
//       Unity and Unreal set material numbers as floats; exact below 2^24), cb_bounds_min,
//       cb_bounds_max, cb_linear_range
//   explicit (Unreal):      cb_skin_position(palette, bind_positions, header, v, joints, weights, inst, time)
//       header = cb_make_header(row_texels, rows_per_block, bounds_min, bounds_max, linear_range)
// bind_positions (RGBA32F, one texel per bone, two rows: the bone table's bind positions, then the
// bones' position offsets) is read by qpos and CB_POSITIONS_RELATIVE only; bind any texture otherwise.
// With CB_LOCAL_ROWS it has five rows: row 2 = (parent index, -1 for a root; 0; 0; 0), row 3 = the bone
// range table's (pos_min.xyz, scale_max), row 4 = (pos_max.xyz, 0). Each skinned bone then walks its
// chain to the root: its two rows and every ancestor's blended (cross-faded too) and composed
// (docs/pal-format.md, "local rows"); the bone pass does that walk once per bone instead of per vertex.
//
// Per-instance data, the roster manifest's four numbers: inst.x first row (negative for a clip whose
// rows are held, not blended - .pal version 4's clip flag bit 2: its first row is -inst.x - 1), inst.y frame count
// (negative: a one-shot, clamped instead of wrapped), inst.z rate in rows per second, inst.w phase
// in 0..1. A timed clip (.pal version 7, clip flag bit 3) has inst.y = +-cells and inst.z = -cell_rate x rate
// (negative marks it): cb_frame reads the cell's map texel from the palette itself (docs/pal-format.md).
// Time in seconds. Motion vectors: one more call at time - dt (see the GLSL's comment).
//
// GLSL -> HLSL: vec/ivec/uvec/mat3 -> float/int/uint/float3x3 (cb_affine.a holds the transform's
// ROWS: mul(a, v)); mix -> lerp; mod -> cb_mod (floored, as GLSL's; HLSL's fmod truncates);
// texelFetch -> CB_LOAD. Every other name is the GLSL's.

#ifndef CB_CROWDBAKE_PALETTE_HLSL
#define CB_CROWDBAKE_PALETTE_HLSL

#ifndef CB_INFLUENCES
#define CB_INFLUENCES 4
#endif

#if defined(CB_LOCAL_ROWS) && !defined(CB_LAYOUT_QPOS)
#error "CB_LOCAL_ROWS: local rows need layout qpos (and precision u16 or float)"
#endif
#if defined(CB_LOCAL_ROWS) && defined(CB_PRECISION_HALF)
#error "CB_LOCAL_ROWS: local rows need precision u16 or float, not half"
#endif
#ifndef CB_MAX_CHAIN
#define CB_MAX_CHAIN 256 // the longest chain walked: a bound, so a bad parent table cannot hang the GPU
#endif

#if defined(CB_LAYOUT_MAT4)
#define CB_TEXELS_PER_BONE 4
#elif defined(CB_LAYOUT_AFFINE)
#define CB_TEXELS_PER_BONE 3
#else
#define CB_TEXELS_PER_BONE 2
#endif

#ifndef CB_TEXTURE2D
#define CB_TEXTURE2D Texture2D<float4>
#endif
#ifndef CB_LOAD
#define CB_LOAD(tex, xy) (tex).Load(int3((xy), 0))
#endif

#if defined(CB_PRECISION_U16) && !defined(CB_U16_UNORM)
#define CB_PALETTE_TEXTURE Texture2D<uint4>
#define CB_LOAD_PALETTE(tex, xy) CB_LOAD(tex, xy)
#elif defined(CB_PRECISION_U16)
#define CB_PALETTE_TEXTURE CB_TEXTURE2D
#define CB_LOAD_PALETTE(tex, xy) uint4(round(CB_LOAD(tex, xy) * 65535.0)) // UNORM16: exactly u / 65535
#else
#define CB_PALETTE_TEXTURE CB_TEXTURE2D
#define CB_LOAD_PALETTE(tex, xy) CB_LOAD(tex, xy)
#endif

// The .pal header's numbers the shader needs.
struct cb_header {
    int row_texels;     // header: row_texels (bones x texels per bone)
    int rows_per_block; // header: height
    float3 bounds_min;  // u16: header bounds_min
    float3 bounds_max;  // u16: header bounds_max
    float linear_range; // u16: header linear_range
};

cb_header cb_make_header(int row_texels, int rows_per_block, float3 bounds_min, float3 bounds_max, float linear_range)
{
    cb_header h;
    h.row_texels = row_texels;
    h.rows_per_block = rows_per_block;
    h.bounds_min = bounds_min;
    h.bounds_max = bounds_max;
    h.linear_range = linear_range;
    return h;
}

// The parameters and arguments every function passes on: the palette, the bind positions, the header.
#define CB_PALETTE_PARAMS CB_PALETTE_TEXTURE palette, CB_TEXTURE2D bind_positions, cb_header h
#define CB_PALETTE_ARGS palette, bind_positions, h

// GLSL's mod: x - y * floor(x / y), never negative for y > 0.
float cb_mod(float x, float y)
{
    return x - y * floor(x / y); // cb:mod
}

#ifdef CB_PRECISION_U16
float4 cb_snorm(uint4 u)
{
    int4 s = int4(u) - int4(u >= 32768u) * 65536;
    return max(float4(s) / 32767.0, -1.0);
}

float3 cb_unorm_box(cb_header h, uint3 u)
{
    return h.bounds_min + (h.bounds_max - h.bounds_min) * (float3(u) / 65535.0);
}

// Texel k of a bone, decoded as crowdbake's u16 precision defines it (docs/pal-format.md).
float4 cb_decode(cb_header h, uint4 u, int k)
{
#if defined(CB_LAYOUT_QPOS)
    if (k == 0) return cb_snorm(u);
    return float4(cb_unorm_box(h, u.xyz), h.linear_range * float(u.w) / 65535.0);
#elif defined(CB_LAYOUT_AFFINE)
    float3 lin = cb_snorm(u).xyz * h.linear_range;
    return float4(lin, h.bounds_min[k] + (h.bounds_max[k] - h.bounds_min[k]) * (float(u.w) / 65535.0));
#else
    if (k == 3) return float4(cb_unorm_box(h, u.xyz), 1.0);
    return float4(cb_snorm(u).xyz * h.linear_range, 0.0);
#endif
}
#endif

#if defined(CB_PRECISION_U16) && defined(CB_LOCAL_ROWS)
// Texel k of a local row, u16: positions in this bone's own box and scale in its own range (rows 3 and
// 4 of bind_positions, the bone range table), not the header's.
float4 cb_decode_local(CB_TEXTURE2D bind_positions, uint4 u, int bone, int k)
{
    if (k == 0) return cb_snorm(u);
    float4 lo = CB_LOAD(bind_positions, int2(bone, 3)), hi = CB_LOAD(bind_positions, int2(bone, 4));
    return float4(lo.xyz + (hi.xyz - lo.xyz) * (float3(u.xyz) / 65535.0), lo.w * float(u.w) / 65535.0); // cb:local-ranges
}
#endif

// Where texel k of a row lies: rows wrap into column blocks of rows_per_block rows.
int2 cb_texel_xy(cb_header h, int row, int k)
{
    int block = row / h.rows_per_block;
    return int2(block * h.row_texels + k, row - block * h.rows_per_block);
}

// Texel k of a bone in a baked row.
float4 cb_texel(CB_PALETTE_PARAMS, int row, int bone, int k)
{
    int2 xy = cb_texel_xy(h, row, bone * CB_TEXELS_PER_BONE + k);
#if defined(CB_PRECISION_U16) && defined(CB_LOCAL_ROWS)
    return cb_decode_local(bind_positions, CB_LOAD_PALETTE(palette, xy), bone, k);
#elif defined(CB_PRECISION_U16)
    return cb_decode(h, CB_LOAD_PALETTE(palette, xy), k);
#else
    return CB_LOAD_PALETTE(palette, xy);
#endif
}

// A timed clip's map texel of `cell` (docs/pal-format.md, "Timed rows"): (r0, r1, f0, f1), the two rows
// blended in the cell relative to the clip's first row, and the weights at the cell's start and end. The map
// rows lie just before the clip's first row, one texel per cell, never decoded through a bone's range.
float4 cb_timed_map(CB_PALETTE_PARAMS, int first, int cells, int cell)
{
    int map_row = cell / h.row_texels;
    int2 xy = cb_texel_xy(h, first - (cells + h.row_texels - 1) / h.row_texels + map_row, cell - map_row * h.row_texels);
#if defined(CB_PRECISION_U16)
    uint4 m = CB_LOAD_PALETTE(palette, xy);
    return float4(float2(m.xy), float2(m.zw) / 65535.0); // u16: rows as integers, weights round(f x 65535)
#else
    return CB_LOAD_PALETTE(palette, xy);
#endif
}

// The two rows to blend at `time`, and the weight of the second. inst.y counts rows, or with inst.z < 0
// (a timed clip, .pal version 7) the cells of its grid, at -inst.z cells a second: the cell's map texel
// names the two rows and the weight runs linearly from its f0 to its f1 across the cell.
void cb_frame(CB_PALETTE_PARAMS, float4 inst, float time, out int row0, out int row1, out float fr)
{
    bool held = inst.x < 0.0; // a stepped clip: its row alone, no blend across a step
    bool timed = inst.z < 0.0;
    float first = held ? -inst.x - 1.0 : inst.x;
    float frames = abs(inst.y); // rows, or a timed clip's cells
    float fpos = time * abs(inst.z) + inst.w * frames;
    float f0, f1;
    if (inst.y > 0.0) {
        fpos = cb_mod(fpos, frames);
        f0 = min(floor(fpos), frames - 1.0); // a float mod's rounding onto `frames`: the last row's (cell's) end
        f1 = cb_mod(f0 + 1.0, frames); // cb:wrap - a loop's last row blends into its first
    } else {
        fpos = clamp(fpos, 0.0, timed ? frames : frames - 1.0); // a timed one-shot ends at its last cell's end
        f0 = min(floor(fpos), frames - 1.0);
        f1 = min(f0 + 1.0, frames - 1.0);
    }
    fr = fpos - f0;
    if (timed) { // the cell's two rows from the map, the weight across the cell
        float4 m = cb_timed_map(CB_PALETTE_ARGS, int(first), int(frames), int(f0)); // cb:timed-map
        f0 = m.x;
        f1 = m.y;
        fr = lerp(m.z, m.w, fr);
    }
    if (held) { f1 = f0; fr = 0.0; } // cb:held - no blend across a step
    row0 = int(first + f0);
    row1 = int(first + f1);
}

// The rotation matrix of a unit quaternion (x, y, z, w), by rows (the GLSL's mat3 transposed).
float3x3 cb_quat_matrix(float4 q)
{
    float3 q2 = 2.0 * q.xyz, w2 = q.w * q2;
    float3 d = q.xyz * q2;                        // 2xx, 2yy, 2zz
    float3 o = q.xyz * q2.yzx;                    // 2xy, 2yz, 2zx
    return float3x3(1.0 - d.y - d.z, o.x - w2.z, o.z + w2.y,
                    o.x + w2.z, 1.0 - d.x - d.z, o.y - w2.x,
                    o.z - w2.y, o.y + w2.x, 1.0 - d.x - d.y);
}

// A bone's transform: a point v goes to mul(a, v) + t, a direction n to mul(a, n).
struct cb_affine {
    float3x3 a;
    float3 t;
};

cb_affine cb_make_affine(float3x3 a, float3 t)
{
    cb_affine m;
    m.a = a;
    m.t = t;
    return m;
}

// A bone's transform blended between two rows. Each of its texels is fetched once, whatever is
// skinned with it (a position and a normal share it).
cb_affine cb_bone_affine(CB_PALETTE_PARAMS, int row0, int row1, float fr, int bone)
{
#if defined(CB_LAYOUT_QPOS)
    float4 q0 = cb_texel(CB_PALETTE_ARGS, row0, bone, 0), q1 = cb_texel(CB_PALETTE_ARGS, row1, bone, 0);
    if (dot(q0, q1) < 0.0) q1 = -q1; // cb:hemisphere - the shorter way between the rows
    float4 q = normalize(lerp(q0, q1, fr));
    float4 ps = lerp(cb_texel(CB_PALETTE_ARGS, row0, bone, 1), cb_texel(CB_PALETTE_ARGS, row1, bone, 1), fr); // position, scale
    float3 b = CB_LOAD(bind_positions, int2(bone, 0)).xyz;
#ifdef CB_POSITIONS_RELATIVE
    ps.xyz += CB_LOAD(bind_positions, int2(bone, 1)).xyz; // cb:offset - the texel holds p less the bone's offset
#endif
    float3x3 a = ps.w * cb_quat_matrix(q); // v -> p + s R (v - b)
    return cb_make_affine(a, ps.xyz - mul(a, b));
#else
    float4 c0 = lerp(cb_texel(CB_PALETTE_ARGS, row0, bone, 0), cb_texel(CB_PALETTE_ARGS, row1, bone, 0), fr);
    float4 c1 = lerp(cb_texel(CB_PALETTE_ARGS, row0, bone, 1), cb_texel(CB_PALETTE_ARGS, row1, bone, 1), fr);
    float4 c2 = lerp(cb_texel(CB_PALETTE_ARGS, row0, bone, 2), cb_texel(CB_PALETTE_ARGS, row1, bone, 2), fr);
#if defined(CB_LAYOUT_AFFINE)
    float3x3 a = float3x3(c0.xyz, c1.xyz, c2.xyz); // texel k = row k, its w the translation's k
    float3 t = float3(c0.w, c1.w, c2.w);
#else
    float4 c3 = lerp(cb_texel(CB_PALETTE_ARGS, row0, bone, 3), cb_texel(CB_PALETTE_ARGS, row1, bone, 3), fr);
    float3x3 a = transpose(float3x3(c0.xyz, c1.xyz, c2.xyz)); // texel k = column k
    float3 t = c3.xyz;
#endif
#ifdef CB_POSITIONS_RELATIVE
    // The translation holds the joint's position less the bone's offset: A (v - b) + p.
    float3 b = CB_LOAD(bind_positions, int2(bone, 0)).xyz;
    float3 p = t + CB_LOAD(bind_positions, int2(bone, 1)).xyz; // cb:offset-matrix
    return cb_make_affine(a, p - mul(a, b));
#else
    return cb_make_affine(a, t);
#endif
#endif
}

// A cross-fade of two transforms: from f (fade 0) to m (fade 1).
cb_affine cb_affine_mix(cb_affine f, cb_affine m, float fade)
{
    return cb_make_affine(m.a * fade + f.a * (1.0 - fade), lerp(f.t, m.t, fade));
}

#ifdef CB_LOCAL_ROWS
// ---- Local rows: each bone in its parent's frame, blended bone by bone, then composed ----
// A bone as qpos: v -> p + s rotate(q, v - b), b its bind position; q (x, y, z, w).
struct cb_qpos {
    float4 q;
    float3 p;
    float s;
};

cb_qpos cb_make_qpos(float4 q, float3 p, float s)
{
    cb_qpos m;
    m.q = q;
    m.p = p;
    m.s = s;
    return m;
}

float4 cb_quat_mul(float4 a, float4 b)
{
    return float4(a.w * b.xyz + b.w * a.xyz + cross(a.xyz, b.xyz), a.w * b.w - dot(a.xyz, b.xyz));
}

float3 cb_quat_rotate(float4 q, float3 v)
{
    float3 t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

// Two local bones blended as two rows are: the rotation the shorter way, renormalised; position and
// scale linearly (weight w on b).
cb_qpos cb_qpos_mix(cb_qpos a, cb_qpos b, float w)
{
    if (dot(a.q, b.q) < 0.0) b.q = -b.q; // cb:local-hemisphere
    return cb_make_qpos(normalize(lerp(a.q, b.q, w)), lerp(a.p, b.p, w), lerp(a.s, b.s, w));
}

// Bone a (its bind position b_a) in front of m, a bone in a's frame: q = q_a q, s = s_a s,
// p = p_a + s_a rotate(q_a, p - b_a). Associative, so a chain composes upwards with no stack.
cb_qpos cb_qpos_compose(cb_qpos a, float3 b_a, cb_qpos m)
{
    return cb_make_qpos(normalize(cb_quat_mul(a.q, m.q)), a.p + a.s * cb_quat_rotate(a.q, m.p - b_a), a.s * m.s);
}

// A bone's local row blended between its two rows, and cross-faded from the other clip's two
// (rows: row0, row1, from0, from1; frs: their weights).
cb_qpos cb_local_bone(CB_PALETTE_PARAMS, int4 rows, float2 frs, float fade, int bone)
{
    float4 ps0 = cb_texel(CB_PALETTE_ARGS, rows.x, bone, 1), ps1 = cb_texel(CB_PALETTE_ARGS, rows.y, bone, 1);
    cb_qpos m = cb_qpos_mix(cb_make_qpos(cb_texel(CB_PALETTE_ARGS, rows.x, bone, 0), ps0.xyz, ps0.w),
                            cb_make_qpos(cb_texel(CB_PALETTE_ARGS, rows.y, bone, 0), ps1.xyz, ps1.w), frs.x);
    if (fade < 1.0) {
        float4 fs0 = cb_texel(CB_PALETTE_ARGS, rows.z, bone, 1), fs1 = cb_texel(CB_PALETTE_ARGS, rows.w, bone, 1);
        cb_qpos f = cb_qpos_mix(cb_make_qpos(cb_texel(CB_PALETTE_ARGS, rows.z, bone, 0), fs0.xyz, fs0.w),
                                cb_make_qpos(cb_texel(CB_PALETTE_ARGS, rows.w, bone, 0), fs1.xyz, fs1.w), frs.y);
        m = cb_qpos_mix(f, m, fade); // cb:local-fade - cross-faded local rows, before composing
    }
    return m;
}

int cb_parent(CB_TEXTURE2D bind_positions, int bone)
{
    return int(floor(CB_LOAD(bind_positions, int2(bone, 2)).x + 0.5)); // -1: a root
}

// A bone's skinning transform from local rows: its blended local row, then each ancestor's blended
// and composed in front of it, up to the root.
cb_affine cb_composed_affine(CB_PALETTE_PARAMS, int4 rows, float2 frs, float fade, int bone)
{
    cb_qpos m = cb_local_bone(CB_PALETTE_ARGS, rows, frs, fade, bone);
    int a = cb_parent(bind_positions, bone);
    for (int depth = 0; a >= 0 && depth < CB_MAX_CHAIN; ++depth) { // cb:local-walk
        m = cb_qpos_compose(cb_local_bone(CB_PALETTE_ARGS, rows, frs, fade, a), CB_LOAD(bind_positions, int2(a, 0)).xyz, m); // cb:local-compose
        a = cb_parent(bind_positions, a);
    }
    float3x3 lin = m.s * cb_quat_matrix(m.q); // v -> p + s R (v - b)
    return cb_make_affine(lin, m.p - mul(lin, CB_LOAD(bind_positions, int2(bone, 0)).xyz));
}
#endif

// Skins a position v and a normal n (not normalized) in one pass over the influences, cross-faded
// from from_inst (fade 0 -> 1; 1: inst alone): each bone's texels are fetched once for both.
void cb_skin_both(CB_PALETTE_PARAMS, float3 v, float3 n, int4 joints, float4 weights, float4 from_inst, float4 inst,
                  float fade, float time, out float3 p, out float3 skinned_n)
{
    int row0, row1, from0, from1;
    float fr, from_fr;
    cb_frame(CB_PALETTE_ARGS, inst, time, row0, row1, fr);
    cb_frame(CB_PALETTE_ARGS, from_inst, time, from0, from1, from_fr);
    p = float3(0.0, 0.0, 0.0);
    skinned_n = float3(0.0, 0.0, 0.0);
    for (int i = 0; i < CB_INFLUENCES; ++i) // cb:influences - crowdbake mesh puts the largest weights first
        if (weights[i] != 0.0) {
#ifdef CB_LOCAL_ROWS
            cb_affine m = cb_composed_affine(CB_PALETTE_ARGS, int4(row0, row1, from0, from1), float2(fr, from_fr), fade, joints[i]);
#else
            cb_affine m = cb_bone_affine(CB_PALETTE_ARGS, row0, row1, fr, joints[i]);
            if (fade < 1.0) m = cb_affine_mix(cb_bone_affine(CB_PALETTE_ARGS, from0, from1, from_fr, joints[i]), m, fade);
#endif
            p += weights[i] * (mul(m.a, v) + m.t);
            skinned_n += weights[i] * mul(m.a, n);
        }
}

// ---- The explicit forms: palette, bind positions and header as arguments ----

float3 cb_skin_position(CB_PALETTE_PARAMS, float3 v, int4 joints, float4 weights, float4 inst, float time)
{
    float3 p, n;
    cb_skin_both(CB_PALETTE_ARGS, v, float3(0.0, 0.0, 0.0), joints, weights, inst, inst, 1.0, time, p, n);
    return p;
}

float3 cb_skin_normal(CB_PALETTE_PARAMS, float3 n, int4 joints, float4 weights, float4 inst, float time)
{
    float3 p, skinned_n;
    cb_skin_both(CB_PALETTE_ARGS, float3(0.0, 0.0, 0.0), n, joints, weights, inst, inst, 1.0, time, p, skinned_n);
    return normalize(skinned_n);
}

// The position and the normal together, for the price of one.
void cb_skin_position_normal(CB_PALETTE_PARAMS, float3 v, float3 n, int4 joints, float4 weights, float4 inst, float time,
                             out float3 p, out float3 skinned_n)
{
    cb_skin_both(CB_PALETTE_ARGS, v, n, joints, weights, inst, inst, 1.0, time, p, skinned_n);
    skinned_n = normalize(skinned_n);
}

// Cross-fade from a previous clip (from_inst) to the current one: fade goes 0 -> 1.
void cb_skin_position_normal_crossfade(CB_PALETTE_PARAMS, float3 v, float3 n, int4 joints, float4 weights, float4 from_inst,
                                       float4 inst, float fade, float time, out float3 p, out float3 skinned_n)
{
    cb_skin_both(CB_PALETTE_ARGS, v, n, joints, weights, from_inst, inst, fade, time, p, skinned_n);
    skinned_n = normalize(skinned_n);
}

float3 cb_skin_position_crossfade(CB_PALETTE_PARAMS, float3 v, int4 joints, float4 weights, float4 from_inst, float4 inst,
                                  float fade, float time)
{
    float3 p, n;
    cb_skin_both(CB_PALETTE_ARGS, v, float3(0.0, 0.0, 0.0), joints, weights, from_inst, inst, fade, time, p, n);
    return p;
}

float3 cb_skin_normal_crossfade(CB_PALETTE_PARAMS, float3 n, int4 joints, float4 weights, float4 from_inst, float4 inst,
                                float fade, float time)
{
    float3 p, skinned_n;
    cb_skin_both(CB_PALETTE_ARGS, float3(0.0, 0.0, 0.0), n, joints, weights, from_inst, inst, fade, time, p, skinned_n);
    return normalize(skinned_n);
}

// ---- The bone pass: each instance's bones blended once a frame instead of once a vertex ----
// One thread (compute) or fragment per (instance, bone) calls cb_bone_pass and stores its three
// texels in three RGBA32F textures (instance i's bone j at (block * bones + j, i - block * bone_rows),
// block = i / bone_rows); CB_BONE_TEXTURE's cb_skin_bone_pass then skins from them, three plain
// loads an influence, no decoding and no blending.

// Bone `bone` of an instance: the columns of its transform, translation in w (the GLSL's layout).
// CB_LOCAL_ROWS: the bone's chain composed here, once per bone, so skinning reads composed bones.
void cb_bone_pass(CB_PALETTE_PARAMS, int bone, float4 from_inst, float4 inst, float fade, float time,
                  out float4 c0, out float4 c1, out float4 c2)
{
    int row0, row1;
    float fr;
    cb_frame(CB_PALETTE_ARGS, inst, time, row0, row1, fr);
#ifdef CB_LOCAL_ROWS
    int from0, from1;
    float from_fr;
    cb_frame(CB_PALETTE_ARGS, from_inst, time, from0, from1, from_fr);
    cb_affine m = cb_composed_affine(CB_PALETTE_ARGS, int4(row0, row1, from0, from1), float2(fr, from_fr), fade, bone);
#else
    cb_affine m = cb_bone_affine(CB_PALETTE_ARGS, row0, row1, fr, bone);
    if (fade < 1.0) {
        cb_frame(CB_PALETTE_ARGS, from_inst, time, row0, row1, fr);
        m = cb_affine_mix(cb_bone_affine(CB_PALETTE_ARGS, row0, row1, fr, bone), m, fade);
    }
#endif
    float3x3 columns = transpose(m.a);
    c0 = float4(columns[0], m.t.x);
    c1 = float4(columns[1], m.t.y);
    c2 = float4(columns[2], m.t.z);
}

#ifdef CB_BONE_TEXTURE
// The bone pass's textures and layout. bones = header row_texels / texels per bone.
#define CB_BONES_PARAMS CB_TEXTURE2D bones0, CB_TEXTURE2D bones1, CB_TEXTURE2D bones2, int bone_count, int bone_rows
#define CB_BONES_ARGS bones0, bones1, bones2, bone_count, bone_rows

cb_affine cb_passed_bone(CB_BONES_PARAMS, int instance, int bone)
{
    int block = instance / bone_rows;
    int2 xy = int2(block * bone_count + bone, instance - block * bone_rows);
    float4 c0 = CB_LOAD(bones0, xy), c1 = CB_LOAD(bones1, xy), c2 = CB_LOAD(bones2, xy);
    return cb_make_affine(transpose(float3x3(c0.xyz, c1.xyz, c2.xyz)), float3(c0.w, c1.w, c2.w)); // cb:bone-columns
}

// The position and the normal (normalized) of a vertex of instance `instance`, from the bone pass.
void cb_skin_bone_pass(CB_BONES_PARAMS, float3 v, float3 n, int4 joints, float4 weights, int instance, out float3 p,
                       out float3 skinned_n)
{
    p = float3(0.0, 0.0, 0.0);
    skinned_n = float3(0.0, 0.0, 0.0);
    for (int i = 0; i < CB_INFLUENCES; ++i)
        if (weights[i] != 0.0) {
            cb_affine m = cb_passed_bone(CB_BONES_ARGS, instance, joints[i]);
            p += weights[i] * (mul(m.a, v) + m.t);
            skinned_n += weights[i] * mul(m.a, n);
        }
    skinned_n = normalize(skinned_n);
}
#endif

// ---- The globals forms: the GLSL's signatures, over globals named as the GLSL's uniforms ----
#ifndef CB_NO_GLOBALS
#ifndef CB_TEXTURES_DECLARED
CB_PALETTE_TEXTURE cb_palette;
CB_TEXTURE2D cb_bind_positions;
#ifdef CB_BONE_TEXTURE
CB_TEXTURE2D cb_bones0, cb_bones1, cb_bones2; // the bone pass's three textures
#endif
#endif
#ifndef CB_HEADER_DECLARED
float cb_row_texels;     // header: row_texels
float cb_rows_per_block; // header: height
float3 cb_bounds_min;    // header: bounds_min (u16)
float3 cb_bounds_max;    // header: bounds_max (u16)
float cb_linear_range;   // header: linear_range (u16)
#ifdef CB_BONE_TEXTURE
float cb_bone_rows;      // instances per column block of the bone textures
#endif
#endif
#ifdef CB_BATCH
float4 cb_batch_instances[CB_BATCH];

// The per-instance numbers of a batch's copy (its _INSTANCE_ID, exact in a float).
float4 cb_batch_instance(float instance_id)
{
    return cb_batch_instances[int(instance_id + 0.5)]; // cb:batch-id
}
#endif

cb_header cb_global_header()
{
    return cb_make_header(int(cb_row_texels + 0.5), int(cb_rows_per_block + 0.5), cb_bounds_min, cb_bounds_max,
                          cb_linear_range);
}

#define CB_GLOBAL_ARGS cb_palette, cb_bind_positions, cb_global_header()

void cb_frame(float4 inst, float time, out int row0, out int row1, out float fr)
{
    cb_frame(CB_GLOBAL_ARGS, inst, time, row0, row1, fr);
}

float3 cb_skin_position(float3 v, int4 joints, float4 weights, float4 inst, float time)
{
    return cb_skin_position(CB_GLOBAL_ARGS, v, joints, weights, inst, time);
}

float3 cb_skin_normal(float3 n, int4 joints, float4 weights, float4 inst, float time)
{
    return cb_skin_normal(CB_GLOBAL_ARGS, n, joints, weights, inst, time);
}

void cb_skin_position_normal(float3 v, float3 n, int4 joints, float4 weights, float4 inst, float time, out float3 p,
                             out float3 skinned_n)
{
    cb_skin_position_normal(CB_GLOBAL_ARGS, v, n, joints, weights, inst, time, p, skinned_n);
}

void cb_skin_position_normal_crossfade(float3 v, float3 n, int4 joints, float4 weights, float4 from_inst, float4 inst,
                                       float fade, float time, out float3 p, out float3 skinned_n)
{
    cb_skin_position_normal_crossfade(CB_GLOBAL_ARGS, v, n, joints, weights, from_inst, inst, fade, time, p, skinned_n);
}

float3 cb_skin_position_crossfade(float3 v, int4 joints, float4 weights, float4 from_inst, float4 inst, float fade, float time)
{
    return cb_skin_position_crossfade(CB_GLOBAL_ARGS, v, joints, weights, from_inst, inst, fade, time);
}

float3 cb_skin_normal_crossfade(float3 n, int4 joints, float4 weights, float4 from_inst, float4 inst, float fade, float time)
{
    return cb_skin_normal_crossfade(CB_GLOBAL_ARGS, n, joints, weights, from_inst, inst, fade, time);
}

void cb_bone_pass(int bone, float4 from_inst, float4 inst, float fade, float time, out float4 c0, out float4 c1, out float4 c2)
{
    cb_bone_pass(CB_GLOBAL_ARGS, bone, from_inst, inst, fade, time, c0, c1, c2);
}

#ifdef CB_BONE_TEXTURE
void cb_skin_bone_pass(float3 v, float3 n, int4 joints, float4 weights, int instance, out float3 p, out float3 skinned_n)
{
    cb_skin_bone_pass(cb_bones0, cb_bones1, cb_bones2, int(cb_row_texels + 0.5) / CB_TEXELS_PER_BONE, int(cb_bone_rows + 0.5),
                      v, n, joints, weights, instance, p, skinned_n);
}
#endif
#endif // CB_NO_GLOBALS

#endif // CB_CROWDBAKE_PALETTE_HLSL
