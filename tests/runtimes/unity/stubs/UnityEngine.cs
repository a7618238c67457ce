// UnityEngine.cs - stubs of exactly the UnityEngine API the Crowdbake package calls, each member
// declared as the Unity Scripting Reference (2022.3 / Unity 6) documents it, so that mcs type-checks
// the package's Unity-facing code without the Editor (tests/runtimes/test_unity_cs.c). Bodies do nothing:
// nothing here runs.
using System;

namespace UnityEngine
{
    public class Object
    {
        public string name { get; set; }
        public static void Destroy(Object obj) { }
    }

    public class ScriptableObject : Object
    {
        public static T CreateInstance<T>() where T : ScriptableObject { return default(T); }
    }

    public class Component : Object
    {
        public Transform transform { get { return null; } }
        public GameObject gameObject { get { return null; } }
    }

    public class Behaviour : Component { }
    public class MonoBehaviour : Behaviour { }

    public sealed class GameObject : Object
    {
        public int layer { get; set; }
    }

    public class Transform : Component
    {
        public Matrix4x4 localToWorldMatrix { get { return default(Matrix4x4); } }
        public bool hasChanged { get; set; }
        public void SetPositionAndRotation(Vector3 position, Quaternion rotation) { }
    }

    public sealed class Mesh : Object
    {
        public BoneWeight[] boneWeights { get { return null; } set { } }
        public int vertexCount { get { return 0; } }
    }

    public struct BoneWeight
    {
        public int boneIndex0 { get; set; }
        public int boneIndex1 { get; set; }
        public int boneIndex2 { get; set; }
        public int boneIndex3 { get; set; }
        public float weight0 { get; set; }
        public float weight1 { get; set; }
        public float weight2 { get; set; }
        public float weight3 { get; set; }
    }

    public class Texture : Object
    {
        public FilterMode filterMode { get; set; }
        public TextureWrapMode wrapMode { get; set; }
    }

    public sealed class Texture2D : Texture
    {
        public Texture2D(int width, int height, TextureFormat textureFormat, bool mipChain, bool linear) { }
        public void SetPixelData<T>(T[] data, int mipLevel, int sourceDataStartIndex = 0) { }
        public void Apply(bool updateMipmaps, bool makeNoLongerReadable) { }
    }

    public class RenderTexture : Texture
    {
        public RenderTexture(int width, int height, int depth, RenderTextureFormat format, RenderTextureReadWrite readWrite) { }
        public bool enableRandomWrite { get; set; }
        public bool Create() { return true; }
        public void Release() { }
    }

    public enum RenderTextureFormat { ARGBFloat = 11 }
    public enum RenderTextureReadWrite { Default = 0, Linear = 1, sRGB = 2 }

    public sealed class ComputeBuffer : IDisposable
    {
        public ComputeBuffer(int count, int stride) { }
        public void SetData(Array data) { }
        public void Release() { }
        public void Dispose() { }
    }

    public sealed class ComputeShader : Object
    {
        public int FindKernel(string name) { return 0; }
        public void SetTexture(int kernelIndex, string name, Texture texture) { }
        public void SetBuffer(int kernelIndex, string name, ComputeBuffer buffer) { }
        public void SetFloat(string name, float val) { }
        public void SetInt(string name, int val) { }
        public void SetVector(string name, Vector4 val) { }
        public void EnableKeyword(string keyword) { }
        public void DisableKeyword(string keyword) { }
        public void Dispatch(int kernelIndex, int threadGroupsX, int threadGroupsY, int threadGroupsZ) { }
    }

    public static class SystemInfo
    {
        public static bool supportsComputeShaders { get { return false; } }
        public static int maxTextureSize { get { return 0; } }
        public static bool SupportsRenderTextureFormat(RenderTextureFormat format) { return false; }
    }

    public enum TextureFormat { RGBAFloat = 20, RGBAHalf = 17, RGBA64 = 74 }
    public enum FilterMode { Point = 0, Bilinear = 1, Trilinear = 2 }
    public enum TextureWrapMode { Repeat = 0, Clamp = 1, Mirror = 2, MirrorOnce = 3 }

    public class Material : Object
    {
        public Material(Material source) { }
        public bool enableInstancing { get; set; }
        public void EnableKeyword(string keyword) { }
    }

    public sealed class MaterialPropertyBlock
    {
        public void SetTexture(string name, Texture value) { }
        public void SetFloat(string name, float value) { }
        public void SetVector(string name, Vector4 value) { }
        public void SetVectorArray(string name, Vector4[] values) { }
    }

    public struct RenderParams
    {
        public RenderParams(Material mat) : this() { material = mat; }
        public Material material { get; set; }
        public Bounds worldBounds { get; set; }
        public MaterialPropertyBlock matProps { get; set; }
        public Rendering.ShadowCastingMode shadowCastingMode { get; set; }
        public bool receiveShadows { get; set; }
        public int layer { get; set; }
    }

    // Unity: `where T : unmanaged` (C# 7.3), which mcs (C# 7.2) lacks; `struct` is the nearest it
    // checks (Matrix4x4[], what the herd passes, satisfies both).
    public static class Graphics
    {
        public static void RenderMeshInstanced<T>(in RenderParams rparams, Mesh mesh, int submeshIndex, T[] instanceData,
                                                  int instanceCount = -1, int startInstance = 0) where T : struct { }
    }

    public struct Vector3
    {
        public float x, y, z;
        public Vector3(float x, float y, float z) { this.x = x; this.y = y; this.z = z; }
        public static Vector3 zero { get { return new Vector3(0, 0, 0); } }
        public static implicit operator Vector4(Vector3 v) { return new Vector4(v.x, v.y, v.z, 0); }
    }

    public struct Vector4
    {
        public float x, y, z, w;
        public Vector4(float x, float y, float z, float w) { this.x = x; this.y = y; this.z = z; this.w = w; }
    }

    public struct Color
    {
        public float r, g, b, a;
        public static Color white { get { return default(Color); } }
        public static implicit operator Vector4(Color c) { return new Vector4(c.r, c.g, c.b, c.a); }
    }

    public struct Quaternion
    {
        public static Quaternion Euler(float x, float y, float z) { return default(Quaternion); }
    }

    public struct Matrix4x4
    {
        public static Matrix4x4 identity { get { return default(Matrix4x4); } }
        public static Matrix4x4 TRS(Vector3 pos, Quaternion q, Vector3 s) { return default(Matrix4x4); }
        public static Matrix4x4 Translate(Vector3 vector) { return default(Matrix4x4); }
        public float this[int row, int column] { get { return 0; } set { } }
        public Quaternion rotation { get { return default(Quaternion); } }
        public Vector3 MultiplyPoint3x4(Vector3 point) { return point; }
        public static Matrix4x4 operator *(Matrix4x4 lhs, Matrix4x4 rhs) { return lhs; }
    }

    public struct Bounds
    {
        public Bounds(Vector3 center, Vector3 size) : this() { }
        public Vector3 min { get { return default(Vector3); } set { } }
        public Vector3 max { get { return default(Vector3); } set { } }
        public void SetMinMax(Vector3 min, Vector3 max) { }
        public void Encapsulate(Vector3 point) { }
        public void Encapsulate(Bounds bounds) { }
    }

    public static class Time
    {
        public static float time { get { return 0; } }
    }

    public static class Mathf
    {
        public static float Sqrt(float f) { return f; }
        public static int CeilToInt(float f) { return 0; }
    }

    public static class Debug
    {
        public static void Log(object message) { }
        public static void LogWarning(object message) { }
    }

    [AttributeUsage(AttributeTargets.Field)]
    public sealed class SerializeField : Attribute { }

    [AttributeUsage(AttributeTargets.Field)]
    public sealed class HideInInspector : Attribute { }
}

namespace UnityEngine.Rendering
{
    public enum ShadowCastingMode { Off = 0, On = 1, TwoSided = 2, ShadowsOnly = 3 }
}
