// CrowdbakeCustomNode.hlsl - the code of the material Custom node that skins an ISM/HISM instance
// from a crowdbake palette (paste it into the node's Code). The node's settings:
//   Output Type           CMOT Float 3: the offset, local space -> TransformVector (Local to World)
//                         -> World Position Offset
//   Additional Outputs    SkinnedNormal (CMOT Float 3, local space) -> TransformVector (Local to
//                         World) -> a Vertex Interpolator -> Normal, with the material's Tangent
//                         Space Normal off
//   Include File Paths    /Plugin/Crowdbake/Private/Crowdbake.ush
//   Additional Defines    CB_LAYOUT_QPOS = 1, CB_PRECISION_U16 = 1 (the palette's; the palette asset
//                         says which), CB_POSITIONS_RELATIVE = 1 and CB_LOCAL_ROWS = 1 when it says so
//   Inputs                Palette, BindPositions, Skin (Texture Object parameters from the palette
//                         asset); Header (float3: row texels, rows per block, linear range),
//                         BoundsMin, BoundsMax (float3); VertexIdUV (TexCoord[N]: the UV channel
//                         holding the vertex id); LocalPosition (LocalPosition node, Local space);
//                         LocalNormal (VertexNormalWS -> TransformVector World to Local); Clip
//                         (PerInstanceCustomData 0-3 appended to a float4), FromClip (4-7), Fade (8-9);
//                         Time (the Time node)
// For motion vectors, a second Custom node with the same inputs plus DeltaTime returns
// CrowdbakeMaterialPreviousOffset(...) into the Previous Frame Switch's previous input.
float3 Offset;
float3 Normal;
CrowdbakeMaterialSkin(Palette, BindPositions, Skin, Header, BoundsMin, BoundsMax, VertexIdUV.x, LocalPosition, LocalNormal,
                      Clip, FromClip, Fade, Time, Offset, Normal);
SkinnedNormal = Normal;
return Offset;
