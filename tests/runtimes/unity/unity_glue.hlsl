// unity_glue.hlsl - the Unity package's shader glue (CrowdbakeUnity.hlsl, CrowdbakeShaderGraph.hlsl)
// as a vertex shader for glslang's HLSL front end, Unity's instancing macros stubbed as Unity's
// UnityInstancing.hlsl defines them in spirit (an array per property, indexed by the instance):
// tests/runtimes/test_unity_cs.c compiles it for every layout x precision and validates the SPIR-V.
#define UNITY_INSTANCING_ENABLED 1
#define UNITY_INSTANCING_BUFFER_START(name) cbuffer UnityInstancing_##name {
#define UNITY_DEFINE_INSTANCED_PROP(type, var) type var[128];
#define UNITY_INSTANCING_BUFFER_END(name) }
static uint unity_InstanceID;
#define UNITY_ACCESS_INSTANCED_PROP(buffer, var) var[unity_InstanceID]
#include "../../../runtimes/unity/Runtime/Shaders/CrowdbakeShaderGraph.hlsl"

struct VertexIn
{
    float3 position : POSITION;
    float3 normal : NORMAL;
    float4 weights : BLENDWEIGHTS;
    uint4 joints : BLENDINDICES;
    uint instance : SV_InstanceID;
    uint vertex_id : SV_VertexID;
};

struct VertexOut
{
    float4 position : SV_Position;
    float3 normal : NORMAL;
    float4 tint : COLOR0;
};

VertexOut main(VertexIn v)
{
    unity_InstanceID = v.instance;
    VertexOut o;
    float3 p, n, p2, n2;
    float4 tint;
    CrowdbakeSkin(v.position, v.normal, int4(v.joints), v.weights, p, n); // the .shader files' path
    CrowdbakeSkin_float(float(v.vertex_id), v.position, v.normal, p2, n2, tint); // Shader Graph's
    o.position = float4(p + p2, 1.0);
    o.normal = n + n2;
    o.tint = tint;
    return o;
}
