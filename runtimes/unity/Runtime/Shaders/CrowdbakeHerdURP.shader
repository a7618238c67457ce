// Crowdbake/Herd URP - the Universal Render Pipeline's shader for CrowdbakeHerd: Lambert lighting
// from the main light (with its shadows) and ambient, a shadow caster and a depth pass, each skinning
// the instance from the palette in its vertex function (or, CB_BONE_TEXTURE, from the herd's bone
// pass: the keywords are in HLSLINCLUDE, so every pass has the variant). Same keywords and per-instance
// data as Crowdbake/Herd (CrowdbakeUnity.hlsl).
Shader "Crowdbake/Herd URP"
{
    Properties
    {
        _BaseColor ("Colour", Color) = (0.85, 0.8, 0.7, 1)
        _BaseMap ("Albedo", 2D) = "white" {}
    }
    SubShader
    {
        Tags { "RenderType" = "Opaque" "RenderPipeline" = "UniversalPipeline" }

        HLSLINCLUDE
        #pragma target 4.5
        #pragma multi_compile_instancing
        #pragma multi_compile_local CB_LAYOUT_MAT4 CB_LAYOUT_AFFINE CB_LAYOUT_QPOS
        #pragma multi_compile_local CB_PRECISION_FLOAT CB_PRECISION_HALF CB_PRECISION_U16
        #pragma multi_compile_local _ CB_POSITIONS_RELATIVE
        #pragma multi_compile_local _ CB_LOCAL_ROWS
        #pragma multi_compile_local _ CB_BONE_TEXTURE // the herd's bone pass: skin from its three textures
        #include "Packages/com.unity.render-pipelines.universal/ShaderLibrary/Core.hlsl"
        #include "CrowdbakeUnity.hlsl"

        TEXTURE2D(_BaseMap);
        SAMPLER(sampler_BaseMap);
        CBUFFER_START(UnityPerMaterial)
            float4 _BaseMap_ST;
            float4 _BaseColor;
        CBUFFER_END

        struct Attributes
        {
            float4 positionOS : POSITION;
            float3 normalOS : NORMAL;
            float2 uv : TEXCOORD0;
            float4 weights : BLENDWEIGHTS;
            uint4 joints : BLENDINDICES;
            UNITY_VERTEX_INPUT_INSTANCE_ID
        };

        // The instance's skinned vertex in world space.
        void SkinnedWorld(Attributes a, out float3 positionWS, out float3 normalWS)
        {
            float3 p, n;
            CrowdbakeSkin(a.positionOS.xyz, a.normalOS, int4(a.joints), a.weights, p, n);
            positionWS = TransformObjectToWorld(p);
            normalWS = TransformObjectToWorldNormal(n);
        }
        ENDHLSL

        Pass
        {
            Name "ForwardLit"
            Tags { "LightMode" = "UniversalForward" }
            HLSLPROGRAM
            #pragma vertex vert
            #pragma fragment frag
            #pragma multi_compile _ _MAIN_LIGHT_SHADOWS _MAIN_LIGHT_SHADOWS_CASCADE
            #include "Packages/com.unity.render-pipelines.universal/ShaderLibrary/Lighting.hlsl"

            struct Varyings
            {
                float4 positionCS : SV_POSITION;
                float3 positionWS : TEXCOORD0;
                float3 normalWS : TEXCOORD1;
                float2 uv : TEXCOORD2;
                float4 tint : TEXCOORD3;
            };

            Varyings vert(Attributes a)
            {
                UNITY_SETUP_INSTANCE_ID(a);
                Varyings o;
                SkinnedWorld(a, o.positionWS, o.normalWS);
                o.positionCS = TransformWorldToHClip(o.positionWS);
                o.uv = TRANSFORM_TEX(a.uv, _BaseMap);
                o.tint = CrowdbakeTint();
                return o;
            }

            half4 frag(Varyings i) : SV_Target
            {
                Light light = GetMainLight(TransformWorldToShadowCoord(i.positionWS));
                float3 n = normalize(i.normalWS);
                half3 albedo = (SAMPLE_TEXTURE2D(_BaseMap, sampler_BaseMap, i.uv) * _BaseColor * i.tint).rgb;
                half3 lit = light.color * (saturate(dot(n, light.direction)) * light.shadowAttenuation) + SampleSH(n);
                return half4(albedo * lit, 1.0);
            }
            ENDHLSL
        }

        Pass
        {
            Name "ShadowCaster"
            Tags { "LightMode" = "ShadowCaster" }
            ColorMask 0
            HLSLPROGRAM
            #pragma vertex vert
            #pragma fragment frag
            #include "Packages/com.unity.render-pipelines.universal/ShaderLibrary/Shadows.hlsl"
            float3 _LightDirection; // URP sets it for the shadow-casting light

            float4 vert(Attributes a) : SV_POSITION
            {
                UNITY_SETUP_INSTANCE_ID(a);
                float3 positionWS, normalWS;
                SkinnedWorld(a, positionWS, normalWS);
                return TransformWorldToHClip(ApplyShadowBias(positionWS, normalWS, _LightDirection));
            }

            half4 frag() : SV_Target { return 0; }
            ENDHLSL
        }

        Pass
        {
            Name "DepthOnly"
            Tags { "LightMode" = "DepthOnly" }
            ColorMask R
            HLSLPROGRAM
            #pragma vertex vert
            #pragma fragment frag

            float4 vert(Attributes a) : SV_POSITION
            {
                UNITY_SETUP_INSTANCE_ID(a);
                float3 positionWS, normalWS;
                SkinnedWorld(a, positionWS, normalWS);
                return TransformWorldToHClip(positionWS);
            }

            half4 frag() : SV_Target { return 0; }
            ENDHLSL
        }
    }
}
