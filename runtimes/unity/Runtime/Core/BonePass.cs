// BonePass.cs - when CrowdbakeHerd takes the bone pass, and how its textures and dispatch are laid out, without the
// engine (tested under mono: tests/runtimes/unity/CrowdbakeCheck.cs "bonepass").
//
// Per-vertex skinning decodes and blends every influence's bone from the palette's two rows at every vertex (local
// rows: and walks its chain to the root). The bone pass does that once per instance and bone: a compute kernel
// (Runtime/Shaders/CrowdbakeBonePass.compute, the shared HLSL runtime's cb_bone_pass) writes each bone's blended
// transform, cross-fade included, to three RGBA32F textures, and the draw skins from them (CB_BONE_TEXTURE:
// cb_skin_bone_pass, three loads an influence). The rule and its numbers are the WebGL2 runtime's
// (runtimes/web/crowdbake_bones.mjs, autoBonePassVertices and Crowd.choice): the same herd takes the same path.
using System;

namespace Crowdbake
{
    public enum BonePassMode { Auto, On, Off }

    // The path a herd is drawn with, and why (a sentence, like the web's crowd.choice(n).reason).
    public struct BonePassChoice
    {
        public bool bonePass;
        public int threshold; // skinned vertices a frame from which Auto takes the pass (0: On, int.MaxValue: Off)
        public string reason;
    }

    public static class BonePassRule
    {
        // Auto takes the bone pass from this many skinned vertices a frame (instances x mesh vertices): the web's
        // AUTO_BONE_PASS_VERTICES. Measured on WebGL2 (bench/run.py's crowd benchmark): the pass is ahead from
        // 100 Cows, 500 k vertices; 50,000 keeps it for herds where its fixed cost is already paid back.
        public const int AutoVertices = 50000;
        // The same for local rows (.pal version 6): per vertex they walk each influence's chain to the root, so the
        // pass pays back far sooner. The web's AUTO_BONE_PASS_VERTICES_LOCAL, measured on WebGL2 over SwiftShader
        // (web43, bench_crowd.mjs, local palettes, medians of interleaved frames): 1 fish (336 vertices) per vertex
        // 4.1 ms, bone pass 8.9; 3 fish (1,008) 5.0 and 5.1; 10 fish (3,360) 7.8 and 5.6; 1 Cow (4,970) 40.4 and 9.5.
        // Neither number was measured in Unity (no Editor here): bonePassVertices overrides them.
        public const int AutoVerticesLocal = 3000;

        // Auto's threshold for a palette: `given` when positive, else the rule's; `why` says why it is not the usual
        // one (local rows), empty otherwise. autoBonePassVertices(header, given) of the web, with 0 for "not given".
        public static int AutoThreshold(bool localRows, int given, out string why)
        {
            why = "";
            if (given > 0) return given;
            if (!localRows) return AutoVertices;
            why = " (local rows: the per-vertex path walks each influence's chain, so Auto takes the pass from " +
                  AutoVerticesLocal + ", not " + AutoVertices + ")";
            return AutoVerticesLocal;
        }

        // The choice for a herd of `instances` of a mesh of `meshVertices`: `unavailable` (null when the pass can run
        // here) names what this machine lacks; then the web's rule, skinned vertices >= the threshold.
        public static BonePassChoice Choose(BonePassMode mode, int givenThreshold, bool localRows, int instances, int meshVertices,
                                            string unavailable)
        {
            string why;
            int auto = AutoThreshold(localRows, givenThreshold, out why);
            long vertices = (long)instances * meshVertices;
            var c = new BonePassChoice { threshold = mode == BonePassMode.On ? 0 : mode == BonePassMode.Off ? int.MaxValue : auto };
            if (mode == BonePassMode.Off) {
                c.reason = "bonePass Off: every vertex blends its bones";
            } else if (unavailable != null) {
                c.reason = "no bone pass here: " + unavailable + "; every vertex blends its bones";
            } else if (mode == BonePassMode.On) {
                c.bonePass = true;
                c.reason = "bonePass On";
            } else if (vertices >= auto) {
                c.bonePass = true;
                c.reason = vertices + " skinned vertices a frame >= " + auto + ": each bone blended once per instance " +
                           "(bonePass Off draws per vertex)" + why;
            } else {
                c.reason = vertices + " skinned vertices a frame < " + auto + ": the bone pass would not pay for its extra " +
                           "dispatch (bonePass On forces it)" + why;
            }
            return c;
        }
    }

    // The bone textures and the kernel's dispatch for `instances` instances of `bones` bones: instance i's bone j at
    // texel (block * bones + j, i - block * rows), block = i / rows (runtimes/hlsl/README.md, the bone pass: blocks of
    // `rows` instances side by side, bones across). rows = min(instances, maxTextureSize): one block while the herd
    // fits a column, as the web's BonePass. One thread per texel, ThreadGroupSize x ThreadGroupSize threads a group
    // (the kernel's [numthreads]); threads past the texture or the herd write nothing.
    public struct BonePassLayout
    {
        public const int ThreadGroupSize = 8; // CrowdbakeBonePass.compute's [numthreads(8, 8, 1)]
        public const int BytesPerTexel = 16;  // RGBA32F
        public const int InstanceFloats = 12; // the kernel's per-instance data: inst, from, fade (start, length, 0, 0)

        public int instances, bones, rows, blocks, width;

        public static BonePassLayout For(int instances, int bones, int maxTextureSize)
        {
            if (instances < 1 || bones < 1 || maxTextureSize < 1)
                throw new ArgumentException("bone pass: " + instances + " instances, " + bones + " bones, " + maxTextureSize + "-texel textures");
            var l = new BonePassLayout { instances = instances, bones = bones, rows = Math.Min(instances, maxTextureSize) };
            l.blocks = (instances + l.rows - 1) / l.rows;
            long width = (long)l.blocks * bones;
            if (width > maxTextureSize)
                throw new ArgumentException("bone pass: " + instances + " instances of " + bones + " bones exceed this GPU's " +
                                            maxTextureSize + "-texel textures");
            l.width = (int)width;
            return l;
        }

        public int ThreadGroupsX { get { return (width + ThreadGroupSize - 1) / ThreadGroupSize; } }
        public int ThreadGroupsY { get { return (rows + ThreadGroupSize - 1) / ThreadGroupSize; } }

        // The three textures' bytes, and per instance (bones x 3 texels; the last block's unused rows shared out).
        public long TextureBytes { get { return (long)width * rows * BytesPerTexel * 3; } }
        public static long BytesPerInstance(int bones) { return (long)bones * 3 * BytesPerTexel + InstanceFloats * 4; }

        // Where instance i's bone j is (cb_passed_bone's arithmetic).
        public void Texel(int instance, int bone, out int x, out int y)
        {
            int block = instance / rows;
            x = block * bones + bone;
            y = instance - block * rows;
        }

        // The (instance, bone) thread (x, y) blends, or false for a thread with nothing to write (the kernel's test).
        public bool ThreadTexel(int x, int y, out int instance, out int bone)
        {
            int block = x / bones;
            bone = x - block * bones;
            instance = block * rows + y;
            return x < width && y < rows && instance < instances;
        }
    }
}
