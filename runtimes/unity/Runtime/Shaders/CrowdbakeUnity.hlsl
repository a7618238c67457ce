// CrowdbakeUnity.hlsl - what the Crowdbake/Herd shaders (built-in and URP) and the Shader Graph
// Custom Function share: the HLSL runtime with Unity's bindings, CrowdbakeHerd's per-instance data
// and one call that skins a vertex. Include it after the pipeline's own includes (they define
// UNITY_INSTANCING_BUFFER_START and friends).
//
// CrowdbakeHerd sets, per draw (MaterialPropertyBlock): cb_palette, cb_bind_positions, cb_skin and
// the header numbers (cb_row_texels ...), _CbTime (the herd's clock, seconds); per instance:
// _CbInst (first row, frame count, rate, phase), _CbFrom (the clip it fades from), _CbFade (start,
// length, the instance's index in the herd, 0), _CbTint (colour).
// CB_BONE_TEXTURE (the herd's bone pass, CrowdbakeBonePass.compute): the vertex skins from cb_bones0..2 (the
// pass's three RGBA32F textures, bones blended once per instance and frame) at row _CbFade.z, and CrowdbakeHerd
// sets cb_bones0..2 and cb_bone_rows per draw; the palette itself is not read.
#ifndef CROWDBAKE_UNITY_HLSL
#define CROWDBAKE_UNITY_HLSL

#if defined(CB_PRECISION_U16)
#define CB_U16_UNORM 1 // Unity's RGBA64 texture: UNORM16, each texel read back to its exact integer
#endif
#include "CrowdbakePalette.hlsl"

float _CbTime;
float _CbMirrorX; // -1: the mesh came through a glTF importer that mirrors X (glTFast), the palette did not; 1: no mirror
Texture2D<float4> cb_skin; // joints and weights by vertex id (Shader Graph): built from the mesh by CrowdbakeHerd

UNITY_INSTANCING_BUFFER_START(Crowdbake)
    UNITY_DEFINE_INSTANCED_PROP(float4, _CbInst)
    UNITY_DEFINE_INSTANCED_PROP(float4, _CbFrom)
    UNITY_DEFINE_INSTANCED_PROP(float4, _CbFade)
    UNITY_DEFINE_INSTANCED_PROP(float4, _CbTint)
UNITY_INSTANCING_BUFFER_END(Crowdbake)

// The fade weight at the herd's clock: 0 at the fade's start, 1 once its length has passed.
float CrowdbakeFadeWeight(float4 fade)
{
    return fade.y > 0.0 ? saturate((_CbTime - fade.x) / fade.y) : 1.0;
}

// A vertex skinned for the instance being drawn: position and normal (object space, normalized).
// Without instancing (a plain draw of the material, the Scene view's preview) the mesh stays in its
// bind pose.
void CrowdbakeSkin(float3 v, float3 n, int4 joints, float4 weights, out float3 p, out float3 skinned_n)
{
#if defined(UNITY_INSTANCING_ENABLED) || defined(INSTANCING_ON)
    float3 mirror = float3(_CbMirrorX < 0.0 ? -1.0 : 1.0, 1.0, 1.0); // into the palette's (glTF's) space and back
#if defined(CB_BONE_TEXTURE)
    int instance = int(UNITY_ACCESS_INSTANCED_PROP(Crowdbake, _CbFade).z + 0.5); // its row in the bone pass (exact in a float)
    cb_skin_bone_pass(v * mirror, n * mirror, joints, weights, instance, p, skinned_n);
#else
    float4 inst = UNITY_ACCESS_INSTANCED_PROP(Crowdbake, _CbInst);
    float4 from = UNITY_ACCESS_INSTANCED_PROP(Crowdbake, _CbFrom);
    float fade = CrowdbakeFadeWeight(UNITY_ACCESS_INSTANCED_PROP(Crowdbake, _CbFade));
    cb_skin_position_normal_crossfade(v * mirror, n * mirror, joints, weights, from, inst, fade, _CbTime, p, skinned_n);
#endif
    p *= mirror;
    skinned_n *= mirror;
#else
    p = v;
    skinned_n = n;
#endif
}

// A vertex's joints and weights from cb_skin by its id: vertex i's four joints at (i % width,
// 2 (i / width)), its four weights one row below (the layout Unreal's Crowdbake.ush reads too).
void CrowdbakeVertexSkin(uint vertex_id, out int4 joints, out float4 weights)
{
    uint width, height;
    cb_skin.GetDimensions(width, height);
    int2 xy = int2(vertex_id % width, 2 * (vertex_id / width));
    joints = int4(cb_skin.Load(int3(xy, 0)) + 0.5);
    weights = cb_skin.Load(int3(xy + int2(0, 1), 0));
}

float4 CrowdbakeTint()
{
#if defined(UNITY_INSTANCING_ENABLED) || defined(INSTANCING_ON)
    return UNITY_ACCESS_INSTANCED_PROP(Crowdbake, _CbTint);
#else
    return float4(1.0, 1.0, 1.0, 1.0);
#endif
}

#endif
