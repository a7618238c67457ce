// PalLocalRows.cs - .pal version 6's local rows (header flag bit 5): each row holds a bone in its
// parent's frame, L_j = M_p^-1 M_j, as qpos. The reader checks the bone range table as the C reader
// does; a bone's matrix blends its own two rows and every ancestor's (cross-fades too), then composes
// them (q_j = q_p q_L, s_j = s_p s_L, p_j = p_p + s_p rotate(q_p, p_L - b_p)) walking each bone's chain
// upwards as the C reader does (associative, so the same as from the root down): a parent may come
// after its child in the bone table.
using System;

namespace Crowdbake
{
    public sealed partial class PalFile
    {
        public const uint BoneRangeBytes = 32;

        // True for a file whose rows are local (version 6, flag bit 5): BoneMatrix composes them.
        public bool LocalRows { get { return Header.BoneRangeTableOffset != 0; } }

        // The bind-position texture's texels (RGBA32F, one texel per bone, row by row): bind positions,
        // position offsets and, for local rows, parents, (pos_min, scale_max) and (pos_max, 0): 2 or 5 rows.
        public float[] BindTexels()
        {
            int bones = Bones.Length, rows = LocalRows ? 5 : 2;
            var texels = new float[bones * rows * 4];
            for (int j = 0; j < bones; ++j) {
                PalBone b = Bones[j];
                for (int k = 0; k < 3; ++k) {
                    texels[j * 4 + k] = b.BindPosition[k];
                    texels[(bones + j) * 4 + k] = b.PositionOffset[k];
                    if (!LocalRows) continue;
                    texels[(3 * bones + j) * 4 + k] = b.RangeMin[k];
                    texels[(4 * bones + j) * 4 + k] = b.RangeMax[k];
                }
                if (!LocalRows) continue;
                texels[(2 * bones + j) * 4] = b.Parent;
                texels[(3 * bones + j) * 4 + 3] = b.ScaleMax;
            }
            return texels;
        }

        static bool Finite(float v) { return !float.IsNaN(v) && !float.IsInfinity(v); }

        // Local rows (flag bit 5, cbpal__validate_local): version 6, qpos with u16 or float, no relative
        // positions, and a bone range table inside the file whose every entry is finite, min <= max,
        // scale_max > 0, reserved 0.
        static void ValidateLocalRows(PalHeader h, byte[] d)
        {
            if ((h.Flags & FlagLocalRows) == 0) return;
            if (h.Version < 6) throw Fail("flag bit 5 (local rows) in a version " + h.Version + " file; local rows are v6");
            if (h.Layout != (uint)PalLayout.Qpos || h.Precision == (uint)PalPrecision.Half || (h.Flags & FlagPositionsRelative) != 0)
                throw Fail("local rows need qpos and u16 or float (layout " + h.Layout + ", precision " + h.Precision + ", flags 0x" +
                           h.Flags.ToString("x") + ")");
            ulong at = h.BoneRangeTableOffset;
            if (!Fits(at, h.BoneCount, BoneRangeBytes, (ulong)d.Length) || at < HeaderBytes || at % 4 != 0)
                throw Fail("bone range table (offset " + at + ", " + h.BoneCount + " bones) lies outside the file");
            for (uint i = 0; i < h.BoneCount; ++i) {
                ulong e = at + (ulong)i * BoneRangeBytes;
                var v = new float[7];
                bool ok = U32(d, e + 28) == 0;
                for (uint k = 0; k < 7; ++k) {
                    v[k] = F32(d, e + 4 * k);
                    ok = ok && Finite(v[k]);
                }
                for (int k = 0; k < 3; ++k) ok = ok && v[k] <= v[4 + k];
                if (!ok || !(v[3] > 0))
                    throw Fail("bone " + i + "'s range (at " + e + "): not finite, min > max, scale_max <= 0 or reserved not 0");
            }
        }

        // Local rows compose along the parents: a cycle is refused (cbpal__parent_cycle: each chain
        // walked at most bone_count steps).
        static void ValidateParents(PalHeader h, byte[] d)
        {
            if ((h.Flags & FlagLocalRows) == 0) return;
            for (uint i = 0; i < h.BoneCount; ++i) {
                int a = (int)i;
                for (uint steps = 0; a >= 0; ++steps) {
                    if (steps > h.BoneCount)
                        throw Fail("local rows: bone " + i + " is its own ancestor (the bone table's parents form a cycle)");
                    a = (int)U32(d, h.BoneTableOffset + (ulong)a * BoneBytes + 8);
                }
            }
        }

        void ReadBoneRange(uint i, ref PalBone bone)
        {
            if (Header.BoneRangeTableOffset == 0) return;
            ulong r = Header.BoneRangeTableOffset + (ulong)i * BoneRangeBytes;
            for (uint k = 0; k < 3; ++k) {
                bone.RangeMin[k] = F32(data, r + 4 * k);
                bone.RangeMax[k] = F32(data, r + 16 + 4 * k);
            }
            bone.ScaleMax = F32(data, r + 12);
        }

        // A local bone as qpos: q (x, y, z, w) 0-3, p 4-6, s 7. a and b mixed with weight w on b: the
        // rotation the shorter way, normalised (nlerp), position and scale linearly.
        static void QposMix(float[] a, float[] b, float w, float[] o)
        {
            bool flip = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0;
            for (int i = 0; i < 8; ++i) o[i] = a[i] + ((flip && i < 4 ? -b[i] : b[i]) - a[i]) * w;
            float n = (float)Math.Sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2] + o[3] * o[3]);
            for (int i = 0; i < 4; ++i) o[i] = n > 0 ? o[i] / n : (i == 3 ? 1.0f : 0.0f);
        }

        // Bone j's local row blended between rows r0 and r1 (cbpal__local), cross-faded from rows
        // (f0, f1, ffr) by `fade` (1: the clip alone), as the shaders blend local rows.
        void LocalRow(uint[] rows, float[] frs, float fade, uint bone, float[] o)
        {
            var a = new float[8];
            var t = new float[4];
            Mix(rows[0], rows[1], frs[0], bone, 0, t); Array.Copy(t, 0, a, 0, 4);
            Mix(rows[0], rows[1], frs[0], bone, 1, t); Array.Copy(t, 0, a, 4, 4);
            QposMix(a, a, 0, o); // normalises q
            if (fade >= 1) return;
            var f = new float[8];
            Mix(rows[2], rows[3], frs[1], bone, 0, t); Array.Copy(t, 0, a, 0, 4);
            Mix(rows[2], rows[3], frs[1], bone, 1, t); Array.Copy(t, 0, a, 4, 4);
            QposMix(a, a, 0, f);
            QposMix(f, (float[])o.Clone(), fade, o);
        }

        // Bone `bone`'s composed qpos: its blended local row, then each ancestor's in front of it up to
        // the root (cbpal__composed: composition is associative; q = q_a q, s = s_a s,
        // p = p_a + s_a rotate(q_a, p - b_a)), q normalised by the caller. At most BoneCount steps
        // (the reader refused cycles).
        void ComposedBone(uint[] rows, float[] frs, float fade, uint bone, float[] t)
        {
            var a = new float[8];
            LocalRow(rows, frs, fade, bone, t);
            int parent = Bones[bone].Parent;
            for (uint steps = 0; parent >= 0 && steps < Header.BoneCount; ++steps) {
                uint up = (uint)parent;
                LocalRow(rows, frs, fade, up, a);
                float[] b = Bones[up].BindPosition;
                parent = Bones[up].Parent;
                float[] v = { t[4] - b[0], t[5] - b[1], t[6] - b[2] };
                float[] u = { a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0] }; // q.xyz x v
                float[] uu = { a[1] * u[2] - a[2] * u[1], a[2] * u[0] - a[0] * u[2], a[0] * u[1] - a[1] * u[0] };
                float x = t[0], y = t[1], z = t[2], w = t[3];
                for (int i = 0; i < 3; ++i) t[4 + i] = a[4 + i] + a[7] * (v[i] + 2 * (a[3] * u[i] + uu[i]));
                t[7] *= a[7];
                t[0] = a[3] * x + a[0] * w + a[1] * z - a[2] * y;
                t[1] = a[3] * y - a[0] * z + a[1] * w + a[2] * x;
                t[2] = a[3] * z + a[0] * y - a[1] * x + a[2] * w;
                t[3] = a[3] * w - a[0] * x - a[1] * y - a[2] * z;
            }
        }

        // The composed bone as the joint matrix: s R(q) about the bind position, column-major.
        void LocalMatrix(uint[] rows, float[] frs, float fade, uint bone, float[] m)
        {
            var c = new float[8];
            Array.Clear(m, 0, 16);
            m[15] = 1.0f;
            ComposedBone(rows, frs, fade, bone, c);
            float n = (float)Math.Sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2] + c[3] * c[3]);
            float x = c[0] / n, y = c[1] / n, z = c[2] / n, w = c[3] / n;
            float[] r = { 1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),
                          2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
                          2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y) };
            for (int k = 0; k < 9; ++k) m[k / 3 * 4 + k % 3] = c[7] * r[k];
            float[] b = Bones[bone].BindPosition;
            for (int k = 0; k < 3; ++k) m[12 + k] = c[4 + k] - (m[k] * b[0] + m[4 + k] * b[1] + m[8 + k] * b[2]);
        }

        // An instance's bone matrix cross-faded from `from` by `fade` (0: from alone, 1: inst alone).
        // Local rows blend the two clips' local rows before composing; global rows blend the matrices.
        public bool InstanceBoneMatrix(float[] inst, float[] from, float fade, double time, uint bone, float[] m)
        {
            if (fade >= 1 || !LocalRows) {
                if (!InstanceBoneMatrix(inst, time, bone, m)) return false;
                if (fade >= 1) return true;
                var f = new float[16];
                if (!InstanceBoneMatrix(from, time, bone, f)) return false;
                for (int k = 0; k < 16; ++k) m[k] = f[k] + (m[k] - f[k]) * fade; // mixing the positions = mixing the matrices
                return true;
            }
            uint r0, r1, f0, f1;
            float fr, ffr;
            if (bone >= Bones.Length || !InstanceFrame(inst, time, out r0, out r1, out fr) || !InstanceFrame(from, time, out f0, out f1, out ffr) ||
                Math.Max(Math.Max(r0, r1), Math.Max(f0, f1)) >= Header.Rows)
                return false;
            LocalMatrix(new[] { r0, r1, f0, f1 }, new[] { fr, ffr }, fade, bone, m);
            return true;
        }
    }
}
