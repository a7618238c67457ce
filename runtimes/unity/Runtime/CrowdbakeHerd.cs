// CrowdbakeHerd.cs - a herd of N palette-skinned instances of one mesh, drawn with
// Graphics.RenderMeshInstanced in batches of up to 1023, each instance's clip, rate, phase,
// cross-fade and tint as per-instance shader data (the Crowdbake/Herd shaders). The state logic is
// HerdState's (Runtime/Core, tested under mono): the herd of runtimes/web/crowdbake_three.mjs, in Unity.
// Large herds take the bone pass (as the WebGL2 runtime's Crowd does, by the same rule: Core/BonePass.cs): each frame a
// compute kernel (CrowdbakeBonePass.compute) blends every instance's bones once into three RGBA32F textures, and the
// draw skins from them (the shaders' CB_BONE_TEXTURE variant) instead of blending the palette's rows at every vertex.
// BonePassReason says which path the herd took and why.
//
//     herd.SetState(7, "flee", 0.3f);      // cross-fade into a roster state over 0.3 s
//     herd.SetSpeed(7, 9.9f);              // locomotion plays at the speed, feet planted, no pop
//     herd.Place(7, new Vector3(4, 0, 2), yawDegrees: 90, scale: 1.2f);
//     herd.Footstep += (e) => dust.transform.position = herd.BonePosition(e.instance, e.bone);
//     Matrix4x4 hat = herd.SocketMatrixAt(7, herd.Socket("Head_end"));
using System;
using System.Collections.Generic;
using UnityEngine;
using UnityEngine.Rendering;

namespace Crowdbake
{
    public sealed class CrowdbakeHerd : MonoBehaviour
    {
        public Mesh mesh;                      // `crowdbake mesh` output: joints are palette bones
        public Material material;              // a Crowdbake/Herd (built-in) or Crowdbake/Herd URP material
        public CrowdbakePaletteAsset palette;
        public CrowdbakeRosterAsset roster;    // optional: states, speeds, sockets, footsteps
        public string type;                    // the roster type (default: the roster's first)
        public int count = 100;
        public float fadeSeconds = 0.25f;
        public ShadowCastingMode shadows = ShadowCastingMode.On;
        // The palette is in the glTF's right-handed space; glTF importers (glTFast) bring the mesh into Unity's
        // left-handed one by mirroring X. True: the shader and BoneMatrixAt mirror X around the palette, so
        // the herd matches the mesh. False for a mesh kept in glTF space.
        public bool meshMirroredX = true;
        // The bone pass: Auto takes it from bonePassVertices skinned vertices a frame (count x mesh vertices; 0: the
        // WebGL2 runtime's rule, 50,000, or 3,000 for local rows, BonePassRule), On always, Off never. It needs compute
        // shaders, RGBA32F random-write textures and bonePassShader; without them the herd skins per vertex and says why.
        public BonePassMode bonePass = BonePassMode.Auto;
        public int bonePassVertices = 0;
        public ComputeShader bonePassShader; // Runtime/Shaders/CrowdbakeBonePass.compute (set by Reset in the Editor)

        const int BatchSize = 1023; // instanced property arrays hold up to 1023 per draw
        HerdState state;
        RosterType rosterType;
        Matrix4x4[] placement; // each instance in the herd's space
        Color[] tint;
        Material drawMaterial;
        Texture2D skin;
        Batch[] batches;
        bool boundsDirty = true;
        float clockStart;
        BonePassChoice bonePassChoice;
        BonePassLayout boneLayout;
        RenderTexture[] boneTextures;  // the pass's three targets: each bone's columns, translation in w
        ComputeBuffer boneInstances;   // 3 float4 an instance: inst, from, fade (start, length, 0, 0)
        float[] boneInstanceData;
        int boneKernel;
        const string BonePassShaderPath = "Packages/com.crowdbake.palette/Runtime/Shaders/CrowdbakeBonePass.compute";

        sealed class Batch
        {
            public Matrix4x4[] matrices;
            public Vector4[] inst, from, fade, tint;
            public MaterialPropertyBlock block;
            public Bounds bounds;
        }

        public HerdState State { get { return state; } }
        public int Count { get { return state != null ? state.Count : 0; } }
        // Whether the herd skins from the bone pass, and why it does or does not (like the web's crowd.choice().reason).
        public bool UsesBonePass { get { Ready(); return bonePassChoice.bonePass; } }
        public string BonePassReason { get { Ready(); return bonePassChoice.reason; } }

#if UNITY_EDITOR
        // When the component is added in the Editor: the package's bone pass kernel.
        void Reset() { bonePassShader = UnityEditor.AssetDatabase.LoadAssetAtPath<ComputeShader>(BonePassShaderPath); }
#endif

        // Footsteps (the roster's contacts) crossed since the last frame, in order.
        public event Action<Footstep> Footstep
        {
            add { Ready().OnFootstep += value; }
            remove { Ready().OnFootstep -= value; }
        }

        void OnEnable() { Ready(); }

        HerdState Ready()
        {
            if (state != null) return state;
            if (palette == null || mesh == null || material == null)
                throw new InvalidOperationException("CrowdbakeHerd '" + name + "': set mesh, material and palette before enabling it");
            if (roster != null) {
                rosterType = string.IsNullOrEmpty(type) ? roster.Roster.types[0] : roster.Type(type);
                if (rosterType == null)
                    throw new ArgumentException("CrowdbakeHerd '" + name + "': the roster has no type '" + type + "' (have " +
                                                string.Join(", ", roster.typeNames) + ")");
            }
            state = new HerdState(palette.Pal, rosterType, Math.Max(count, 0)) { DefaultFade = fadeSeconds };
            placement = new Matrix4x4[state.Count];
            tint = new Color[state.Count];
            for (int i = 0; i < state.Count; ++i) {
                placement[i] = Matrix4x4.identity;
                tint[i] = Color.white;
            }
            bonePassChoice = ChooseBonePass();
            if (bonePass == BonePassMode.On && !bonePassChoice.bonePass)
                Debug.LogWarning("CrowdbakeHerd '" + name + "': " + bonePassChoice.reason);
            drawMaterial = palette.MaterialFor(material);
            if (bonePassChoice.bonePass) drawMaterial.EnableKeyword("CB_BONE_TEXTURE");
            skin = SkinTexture(mesh);
            batches = new Batch[(state.Count + BatchSize - 1) / BatchSize];
            for (int b = 0; b < batches.Length; ++b) {
                int n = Math.Min(BatchSize, state.Count - b * BatchSize);
                batches[b] = new Batch { matrices = new Matrix4x4[n], inst = new Vector4[n], from = new Vector4[n], fade = new Vector4[n],
                                         tint = new Vector4[n], block = new MaterialPropertyBlock() };
                palette.SetProperties(batches[b].block);
                batches[b].block.SetTexture("cb_skin", skin);
                if (bonePassChoice.bonePass) {
                    for (int k = 0; k < 3; ++k) batches[b].block.SetTexture("cb_bones" + k, boneTextures[k]);
                    batches[b].block.SetFloat("cb_bone_rows", boneLayout.rows);
                }
            }
            clockStart = Time.time;
            return state;
        }

        // Instance i plays `stateName` (a roster state, or a clip name without a roster), cross-fading
        // over `fade` seconds (negative: fadeSeconds).
        public void SetState(int i, string stateName, float fade = -1)
        {
            Ready().SetState(i, stateName, float.NaN, float.NaN, fade < 0 ? float.NaN : fade);
        }

        // World units per second: locomotion states follow it (feet planted), on the frame they are on.
        public void SetSpeed(int i, float speed) { Ready().SetSpeed(i, speed); }

        public void SetPhase(int i, float phase) { Ready().SetPhase(i, phase); }

        // Puts instance i at `position` (herd space), turned `yawDegrees` about +Y, scaled uniformly.
        public void Place(int i, Vector3 position, float yawDegrees = 0, float scale = 1)
        {
            Ready();
            placement[i] = Matrix4x4.TRS(position, Quaternion.Euler(0, yawDegrees, 0), new Vector3(scale, scale, scale));
            state.SetScale(i, scale);
            boundsDirty = true;
        }

        public void SetTint(int i, Color color)
        {
            Ready();
            tint[i] = color;
        }

        // The bone's skinning matrix for instance i now (bind space to its posed model, before its
        // placement): its clip, time and cross-fade, as the shader blends them.
        public Matrix4x4 BoneMatrixAt(int i, int bone)
        {
            var m = new float[16];
            if (!Ready().BoneMatrixAt(i, bone, m))
                throw new ArgumentOutOfRangeException("bone", "bone " + bone + " is not one of the palette's " + palette.Pal.Bones.Length + " bones");
            return Mirrored(m);
        }

        // A column-major glTF-space matrix in the mesh's space: S M S with S the X mirror when the mesh is mirrored.
        Matrix4x4 Mirrored(float[] m)
        {
            var out4 = new Matrix4x4();
            for (int k = 0; k < 16; ++k) {
                int row = k % 4, column = k / 4;
                bool flip = meshMirroredX && (row == 0) != (column == 0);
                out4[row, column] = flip ? -m[k] : m[k];
            }
            return out4;
        }

        public RosterSocket Socket(string socketName)
        {
            if (rosterType != null)
                foreach (RosterSocket s in rosterType.sockets)
                    if (s.name == socketName) return s;
            throw new ArgumentException("CrowdbakeHerd '" + name + "': no socket '" + socketName + "' (the roster type's sockets)");
        }

        // Where a prop on `socket` of instance i is in the world: herd x placement x bone x socket.
        public Matrix4x4 SocketMatrixAt(int i, RosterSocket socket)
        {
            Matrix4x4 bind = Mirrored(socket.bindTransform);
            return transform.localToWorldMatrix * placement[i] * BoneMatrixAt(i, socket.bone) * bind;
        }

        // A bone's origin in the world (a footstep's foot, say).
        public Vector3 BonePosition(int i, int bone)
        {
            return (transform.localToWorldMatrix * placement[i] * BoneMatrixAt(i, bone)).MultiplyPoint3x4(Vector3.zero);
        }

        void Update()
        {
            if (state == null) return;
            float now = Time.time - clockStart;
            state.Update(now);
            if (bonePassChoice.bonePass) RunBonePass(now);
            Draw(now);
        }

        // The rule (BonePassRule, the web's) on what this machine can do; the pass's textures made when it is taken.
        BonePassChoice ChooseBonePass()
        {
            string unavailable = !SystemInfo.supportsComputeShaders ? "this graphics API has no compute shaders (SystemInfo.supportsComputeShaders)"
                : !SystemInfo.SupportsRenderTextureFormat(RenderTextureFormat.ARGBFloat) ? "no RGBA32F render textures (RenderTextureFormat.ARGBFloat)"
                : bonePassShader == null ? "bonePassShader is not set (" + BonePassShaderPath + ")" : null;
            BonePassChoice c = BonePassRule.Choose(bonePass, bonePassVertices, palette.localRows, state.Count, mesh.vertexCount, unavailable);
            if (!c.bonePass) return c;
            try {
                boneLayout = BonePassLayout.For(state.Count, palette.Pal.Bones.Length, SystemInfo.maxTextureSize);
            } catch (ArgumentException e) {
                return BonePassRule.Choose(bonePass, bonePassVertices, palette.localRows, state.Count, mesh.vertexCount, e.Message);
            }
            boneTextures = new RenderTexture[3];
            for (int k = 0; k < 3; ++k) {
                boneTextures[k] = new RenderTexture(boneLayout.width, boneLayout.rows, 0, RenderTextureFormat.ARGBFloat, RenderTextureReadWrite.Linear);
                boneTextures[k].name = name + " bones" + k;
                boneTextures[k].enableRandomWrite = true; // before Create: the kernel writes it
                boneTextures[k].filterMode = FilterMode.Point;
                boneTextures[k].wrapMode = TextureWrapMode.Clamp;
                if (!boneTextures[k].Create()) {
                    ReleaseBonePass();
                    return BonePassRule.Choose(bonePass, bonePassVertices, palette.localRows, state.Count, mesh.vertexCount,
                                               "the bone textures (" + boneLayout.width + " x " + boneLayout.rows + " RGBA32F) could not be created");
                }
            }
            boneInstanceData = new float[state.Count * BonePassLayout.InstanceFloats];
            boneInstances = new ComputeBuffer(state.Count * 3, 16);
            boneKernel = bonePassShader.FindKernel("CrowdbakeBonePass");
            return c;
        }

        void ReleaseBonePass()
        {
            if (boneTextures != null)
                foreach (RenderTexture t in boneTextures)
                    if (t != null) {
                        t.Release();
                        Destroy(t);
                    }
            if (boneInstances != null) boneInstances.Release();
            boneTextures = null;
            boneInstances = null;
        }

        // Every instance's bones blended at the herd's clock, before this frame's draws read them.
        void RunBonePass(float now)
        {
            for (int i = 0; i < state.Count; ++i) {
                int o = i * BonePassLayout.InstanceFloats;
                Array.Copy(state.Inst, i * 4, boneInstanceData, o, 4);
                Array.Copy(state.From, i * 4, boneInstanceData, o + 4, 4);
                boneInstanceData[o + 8] = state.Fade[i * 2];
                boneInstanceData[o + 9] = state.Fade[i * 2 + 1];
            }
            boneInstances.SetData(boneInstanceData);
            ComputeShader cs = bonePassShader;
            palette.SetComputeProperties(cs, boneKernel); // keywords too: the kernel asset is shared by every herd
            cs.SetBuffer(boneKernel, "_CbInstances", boneInstances);
            for (int k = 0; k < 3; ++k) cs.SetTexture(boneKernel, "_CbBonesOut" + k, boneTextures[k]);
            cs.SetFloat("_CbTime", now);
            cs.SetInt("_CbCount", state.Count);
            cs.SetInt("_CbBoneRows", boneLayout.rows);
            cs.Dispatch(boneKernel, boneLayout.ThreadGroupsX, boneLayout.ThreadGroupsY, 1);
        }

        void Draw(float now)
        {
            Matrix4x4 herd = transform.localToWorldMatrix;
            var travel = new float[3];
            for (int b = 0; b < batches.Length; ++b) {
                Batch batch = batches[b];
                for (int k = 0; k < batch.matrices.Length; ++k) {
                    int i = b * BatchSize + k;
                    // The body's per-row travel (a gallop's), in the model's frame, mirrored as the mesh is.
                    state.TravelOffsetAt(i, travel);
                    var offset = new Vector3(meshMirroredX ? -travel[0] : travel[0], travel[1], travel[2]);
                    batch.matrices[k] = herd * placement[i] * Matrix4x4.Translate(offset);
                    batch.inst[k] = new Vector4(state.Inst[i * 4], state.Inst[i * 4 + 1], state.Inst[i * 4 + 2], state.Inst[i * 4 + 3]);
                    batch.from[k] = new Vector4(state.From[i * 4], state.From[i * 4 + 1], state.From[i * 4 + 2], state.From[i * 4 + 3]);
                    batch.fade[k] = new Vector4(state.Fade[i * 2], state.Fade[i * 2 + 1], i, 0); // z: its index, the bone pass instance it skins from
                    batch.tint[k] = tint[i];
                }
                if (boundsDirty || transform.hasChanged) batch.bounds = BatchBounds(batch);
                batch.block.SetVectorArray("_CbInst", batch.inst);
                batch.block.SetVectorArray("_CbFrom", batch.from);
                batch.block.SetVectorArray("_CbFade", batch.fade);
                batch.block.SetVectorArray("_CbTint", batch.tint);
                batch.block.SetFloat("_CbTime", now);
                batch.block.SetFloat("_CbMirrorX", meshMirroredX ? -1 : 1);
                var rp = new RenderParams(drawMaterial) { worldBounds = batch.bounds, matProps = batch.block, shadowCastingMode = shadows,
                                                          receiveShadows = true, layer = gameObject.layer };
                Graphics.RenderMeshInstanced(rp, mesh, 0, batch.matrices, batch.matrices.Length);
            }
            boundsDirty = false;
            transform.hasChanged = false;
        }

        // The world box holding every instance of a batch in any baked pose (the clips' animated
        // bounds at each instance): what the camera culls against.
        Bounds BatchBounds(Batch batch)
        {
            Bounds pose = palette.animatedBounds, all = new Bounds();
            for (int k = 0; k < batch.matrices.Length; ++k) {
                Matrix4x4 m = batch.matrices[k];
                for (int c = 0; c < 8; ++c) {
                    var corner = new Vector3((c & 1) != 0 ? pose.max.x : pose.min.x, (c & 2) != 0 ? pose.max.y : pose.min.y,
                                             (c & 4) != 0 ? pose.max.z : pose.min.z);
                    Vector3 p = m.MultiplyPoint3x4(corner);
                    if (k == 0 && c == 0) all = new Bounds(p, Vector3.zero);
                    else all.Encapsulate(p);
                }
            }
            return all;
        }

        // The mesh's joints and weights by vertex id, for Shader Graph (which has no node for them):
        // vertex i's four joints at (i % width, 2 (i / width)), its four weights one row below.
        static Texture2D SkinTexture(Mesh mesh)
        {
            BoneWeight[] bw = mesh.boneWeights;
            int n = Math.Max(bw.Length, 1), width = Math.Min(n, 4096), rows = (n + width - 1) / width;
            var texels = new float[width * rows * 8];
            for (int v = 0; v < bw.Length; ++v) {
                int j = ((v / width) * 2 * width + v % width) * 4, w = j + width * 4;
                texels[j] = bw[v].boneIndex0; texels[j + 1] = bw[v].boneIndex1; texels[j + 2] = bw[v].boneIndex2; texels[j + 3] = bw[v].boneIndex3;
                texels[w] = bw[v].weight0; texels[w + 1] = bw[v].weight1; texels[w + 2] = bw[v].weight2; texels[w + 3] = bw[v].weight3;
            }
            var t = new Texture2D(width, rows * 2, TextureFormat.RGBAFloat, false, true);
            t.name = mesh.name + " skin";
            t.filterMode = FilterMode.Point;
            t.wrapMode = TextureWrapMode.Clamp;
            t.SetPixelData(texels, 0);
            t.Apply(false, true);
            return t;
        }

        void OnDisable()
        {
            if (drawMaterial != null) Destroy(drawMaterial);
            if (skin != null) Destroy(skin);
            ReleaseBonePass();
            drawMaterial = null;
            skin = null;
            bonePassChoice = new BonePassChoice();
            state = null;
        }
    }
}
