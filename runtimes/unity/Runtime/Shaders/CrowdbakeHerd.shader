// Crowdbake/Herd - the built-in render pipeline's shader for CrowdbakeHerd: a Lambert surface
// shader whose vertex function skins each instance from the palette (position and normal in one
// pass, cross-fades included), with shadows (addshadow runs the same vertex function), tint per
// instance. The palette's encoding picks a variant; CrowdbakeHerd turns the keywords on (CB_BONE_TEXTURE when it
// takes the bone pass: the vertex function, shadow pass included, reads the pass's bone textures).
Shader "Crowdbake/Herd"
{
    Properties
    {
        _Color ("Colour", Color) = (0.85, 0.8, 0.7, 1)
        _MainTex ("Albedo", 2D) = "white" {}
    }
    SubShader
    {
        Tags { "RenderType" = "Opaque" }
        CGPROGRAM
        #pragma surface surf Lambert vertex:vert addshadow
        #pragma target 4.5
        #pragma multi_compile_instancing
        #pragma multi_compile_local CB_LAYOUT_MAT4 CB_LAYOUT_AFFINE CB_LAYOUT_QPOS
        #pragma multi_compile_local CB_PRECISION_FLOAT CB_PRECISION_HALF CB_PRECISION_U16
        #pragma multi_compile_local _ CB_POSITIONS_RELATIVE
        #pragma multi_compile_local _ CB_LOCAL_ROWS
        #pragma multi_compile_local _ CB_BONE_TEXTURE // the herd's bone pass: skin from its three textures
        #include "CrowdbakeUnity.hlsl"

        sampler2D _MainTex;
        fixed4 _Color;

        // The mesh's joints (palette bones: `crowdbake mesh` writes them so) and weights.
        struct appdata_crowd
        {
            float4 vertex : POSITION;
            float3 normal : NORMAL;
            float4 tangent : TANGENT;
            float4 texcoord : TEXCOORD0;
            float4 weights : BLENDWEIGHTS;
            uint4 joints : BLENDINDICES;
            UNITY_VERTEX_INPUT_INSTANCE_ID
        };

        struct Input
        {
            float2 uv_MainTex;
        };

        void vert(inout appdata_crowd v)
        {
            UNITY_SETUP_INSTANCE_ID(v);
            float3 p, n;
            CrowdbakeSkin(v.vertex.xyz, v.normal, int4(v.joints), v.weights, p, n);
            v.vertex.xyz = p;
            v.normal = n;
        }

        void surf(Input IN, inout SurfaceOutput o)
        {
            fixed4 c = tex2D(_MainTex, IN.uv_MainTex) * _Color * CrowdbakeTint();
            o.Albedo = c.rgb;
            o.Alpha = c.a;
        }
        ENDCG
    }
    FallBack "Diffuse"
}
