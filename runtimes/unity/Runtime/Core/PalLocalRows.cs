// PalLocalRows.cs - .pal version 6's local rows (header flag bit 5): each row holds a bone in its
// parent's frame, L_j = M_p^-1 M_j, as qpos. The reader checks the bone range table as the C reader
// does; a bone's matrix blends its own two rows and every ancestor's (cross-fades too), then composes
// them from the root down (q_j = q_p q_L, s_j = s_p s_L, p_j = p_p + s_p rotate(q_p, p_L - b_p)),
// walking each bone's chain: a parent may come after its child in the bone table.
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

        // The bone range table: inside the file, 4-byte aligned; each range finite, min <= max,
        // scale_max > 0, reserved 0. Local rows need qpos and u16 or float.
        static void ValidateLocalRows(PalHeader h, byte[] d)
        {
            if (h.BoneRangeTableOffset == 0) return;
            if (h.Layout != (uint)PalLayout.Qpos || h.Precision == (uint)PalPrecision.Half)
                throw Fail("local rows need qpos and u16 or float");
            ulong at = h.BoneRangeTableOffset;
            if (at % 4 != 0 || !Fits(at, h.BoneCount, BoneRangeBytes, (ulong)d.Length) || at < HeaderBytes)
                throw Fail("bone range table (offset " + at + ", " + h.BoneCount + " bones) lies outside the file");
            for (uint i = 0; i < h.BoneCount; ++i) {
                ulong r = at + (ulong)i * BoneRangeBytes;
                bool good = Finite(F32(d, r + 12)) && F32(d, r + 12) > 0 && U32(d, r + 28) == 0;
                for (uint k = 0; k < 3; ++k) {
                    float lo = F32(d, r + 4 * k), hi = F32(d, r + 16 + 4 * k);
                    good = good && Finite(lo) && Finite(hi) && lo <= hi;
                }
                if (!good) throw Fail("bone " + i + " has a bad range (not finite, min above max, scale not above 0 or reserved not 0)");
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

        // A local bone as qpos: q (x, y, z, w) 0-3, p 4-6, s 7.
        static void QposMix(float[] a, float[] b, float w, float[] o)
        {
            bool flip = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0; // the shorter way
            for (int i = 0; i < 8; ++i) o[i] = a[i] + ((flip && i < 4 ? -b[i] : b[i]) - a[i]) * w;
            float n = (float)Math.Sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2] + o[3] * o[3]);
            for (int i = 0; i < 4; ++i) o[i] /= n;
        }

        // Bone j's local row blended between rows r0 and r1, as the shaders blend a qpos row.
        void LocalRow(uint r0, uint r1, float fr, uint bone, float[] o)
        {
            var a = new float[8];
            var b = new float[8];
            var t = new float[4];
            Texel(r0, bone, 0, t); Array.Copy(t, 0, a, 0, 4);
            Texel(r0, bone, 1, t); Array.Copy(t, 0, a, 4, 4);
            Texel(r1, bone, 0, t); Array.Copy(t, 0, b, 0, 4);
            Texel(r1, bone, 1, t); Array.Copy(t, 0, b, 4, 4);
            QposMix(a, b, fr, o);
        }

        // Parent p's composed qpos in front of its child's local one: the child's composed qpos.
        void Compose(float[] p, uint parent, float[] local, float[] o)
        {
            float[] b = Bones[parent].BindPosition;
            float qx = p[0], qy = p[1], qz = p[2], qw = p[3];
            float lx = local[0], ly = local[1], lz = local[2], lw = local[3];
            float[] q = { qw * lx + lw * qx + qy * lz - qz * ly, qw * ly + lw * qy + qz * lx - qx * lz,
                          qw * lz + lw * qz + qx * ly - qy * lx, qw * lw - qx * lx - qy * ly - qz * lz };
            float n = (float)Math.Sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            float vx = local[4] - b[0], vy = local[5] - b[1], vz = local[6] - b[2];
            float tx = 2 * (qy * vz - qz * vy), ty = 2 * (qz * vx - qx * vz), tz = 2 * (qx * vy - qy * vx); // rotate(q_p, v)
            float rx = vx + qw * tx + (qy * tz - qz * ty), ry = vy + qw * ty + (qz * tx - qx * tz), rz = vz + qw * tz + (qx * ty - qy * tx);
            o[4] = p[4] + p[7] * rx; o[5] = p[5] + p[7] * ry; o[6] = p[6] + p[7] * rz;
            o[7] = p[7] * local[7];
            for (int i = 0; i < 4; ++i) o[i] = q[i] / n;
        }

        // Bone `bone`'s composed qpos: rows (r0, r1, fr) of the clip, cross-faded from (f0, f1, ffr)
        // by `fade` (1: the clip alone). False for a chain longer than the bone count (a loop).
        bool ComposedBone(uint[] rows, float[] frs, float fade, uint bone, float[] o)
        {
            var chain = new uint[Bones.Length];
            int n = 0;
            for (int j = (int)bone; j >= 0; j = Bones[j].Parent) {
                if (n == chain.Length) return false;
                chain[n++] = (uint)j;
            }
            var local = new float[8];
            var from = new float[8];
            var composed = new float[8];
            for (int k = n - 1; k >= 0; --k) { // the root first
                LocalRow(rows[0], rows[1], frs[0], chain[k], local);
                if (fade < 1) {
                    LocalRow(rows[2], rows[3], frs[1], chain[k], from);
                    QposMix((float[])from.Clone(), (float[])local.Clone(), fade, local);
                }
                if (k == n - 1) Array.Copy(local, composed, 8);
                else Compose((float[])composed.Clone(), chain[k + 1], local, composed);
            }
            Array.Copy(composed, o, 8);
            return true;
        }

        // The composed bone as the joint matrix: s R(q) about the bind position, column-major.
        void LocalMatrix(uint[] rows, float[] frs, float fade, uint bone, float[] m)
        {
            var c = new float[8];
            Array.Clear(m, 0, 16);
            m[15] = 1.0f;
            if (!ComposedBone(rows, frs, fade, bone, c)) return;
            float x = c[0], y = c[1], z = c[2], w = c[3];
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
