// CrowdbakeShaderGraph.hlsl - a Shader Graph Custom Function (Type: File, this file; Name:
// CrowdbakeSkin) for a graph drawn by CrowdbakeHerd. In the graph's Vertex stage:
//   inputs  VertexId  (Vertex ID node), Position (Position node, Object), Normal (Normal Vector, Object)
//   outputs OutPosition -> Vertex Position, OutNormal -> Vertex Normal, Tint -> multiply your colour
// Shader Graph has no node for a mesh's blend indices and weights, so they come from cb_skin by the
// vertex id (CrowdbakeHerd builds it from the mesh's own bone weights, in Unity's vertex order).
// Add the palette's encoding as the graph's keywords (Boolean or Enum, Shader Feature Local or
// Multi Compile Local, exactly these references): CB_LAYOUT_MAT4 / CB_LAYOUT_AFFINE / CB_LAYOUT_QPOS,
// CB_PRECISION_FLOAT / CB_PRECISION_HALF / CB_PRECISION_U16, CB_POSITIONS_RELATIVE, CB_LOCAL_ROWS (a .pal
// version 6 palette of local rows: the asset's Keywords say which), CB_BONE_TEXTURE (the herd's bone pass:
// CrowdbakeHerd.bonePassReason says whether it took it; a graph without the keyword skins per vertex all the same,
// so set bonePass Off there to skip the dispatch); and tick the
// material's Enable GPU Instancing. Set the node's Precision to Float (a palette needs float math).
#ifndef CROWDBAKE_SHADER_GRAPH_HLSL
#define CROWDBAKE_SHADER_GRAPH_HLSL
#include "CrowdbakeUnity.hlsl"

void CrowdbakeSkin_float(float VertexId, float3 Position, float3 Normal, out float3 OutPosition, out float3 OutNormal, out float4 Tint)
{
    int4 joints;
    float4 weights;
    CrowdbakeVertexSkin((uint)(VertexId + 0.5), joints, weights);
    CrowdbakeSkin(Position, Normal, joints, weights, OutPosition, OutNormal);
    Tint = CrowdbakeTint();
}

#endif
