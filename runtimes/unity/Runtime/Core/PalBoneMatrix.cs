// PalBoneMatrix.cs - a bone's skinning matrix at a time, decoded and blended as the shipped shaders
// blend two rows: the numbers of cbpal_bone_matrix (include/crowdbake_pal.h), statement for
// statement in the same float arithmetic, so C# and C agree to the last bit or within a rounding.
using System;

namespace Crowdbake
{
    public sealed partial class PalFile
    {
        // A half float's bits as a float: the exponent rebiased; zero and subnormals are m 2^-24.
        public static float HalfToFloat(ushort h)
        {
            uint e = (uint)(h >> 10) & 0x1fu, m = h & 0x3ffu, bits = (uint)(h & 0x8000u) << 16 | m << 13;
            bits |= e == 31 ? 0x7f800000u : (e + 112) << 23;
            float f = BitConverter.ToSingle(BitConverter.GetBytes(bits), 0);
            return e != 0 ? f : ((h & 0x8000u) != 0 ? -1.0f : 1.0f) * (float)m / 16777216.0f;
        }

        public static float Snorm(ushort u)
        {
            return Math.Max((float)((int)u - (u >= 32768u ? 65536 : 0)) / 32767.0f, -1.0f);
        }

        // Texel k of a bone in a row, as the shaders' cb_texel decodes it (t: 4 floats).
        public void Texel(uint row, uint bone, uint k, float[] t)
        {
            PalHeader h = Header;
            uint x, y;
            TexelXY(row, bone, out x, out y);
            int p = TexelOffset + (int)(((ulong)y * h.Width + x + k) * h.TexelBytes);
            if (h.Precision == (uint)PalPrecision.Float) {
                for (int i = 0; i < 4; ++i) t[i] = BitConverter.ToSingle(data, p + 4 * i);
                return;
            }
            var u = new ushort[4];
            for (int i = 0; i < 4; ++i) u[i] = U16(data, p + 2 * i);
            if (h.Precision == (uint)PalPrecision.Half) {
                for (int i = 0; i < 4; ++i) t[i] = HalfToFloat(u[i]);
                return;
            }
            float[] lo = h.BoundsMin, hi = h.BoundsMax;
            float range = h.LinearRange;
            if (LocalRows) { // local rows: positions in the bone's own box, scale in its own range
                lo = Bones[bone].RangeMin;
                hi = Bones[bone].RangeMax;
                range = Bones[bone].ScaleMax;
            }
            bool qpos = h.Layout == (uint)PalLayout.Qpos;
            bool box = (qpos && k == 1) || (h.Layout == (uint)PalLayout.Mat4 && k == 3);
            float scale = qpos ? 1.0f : range; // quaternions are plain snorm
            for (int i = 0; i < 3; ++i)
                t[i] = box ? lo[i] + (hi[i] - lo[i]) * ((float)u[i] / 65535.0f) : Snorm(u[i]) * scale;
            if (qpos) t[3] = k == 0 ? Snorm(u[3]) : range * (float)u[3] / 65535.0f;
            else if (h.Layout == (uint)PalLayout.Affine) t[3] = lo[k] + (hi[k] - lo[k]) * ((float)u[3] / 65535.0f);
            else t[3] = k == 3 ? 1.0f : 0.0f;
        }

        // Texel k mixed between two rows with weight fr on the second (qpos: the rotation the shorter way).
        void Mix(uint r0, uint r1, float fr, uint bone, uint k, float[] t)
        {
            float[] a = new float[4], b = new float[4];
            Texel(r0, bone, k, a);
            Texel(r1, bone, k, b);
            bool flip = Header.Layout == (uint)PalLayout.Qpos && k == 0 && a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0;
            for (int i = 0; i < 4; ++i) t[i] = a[i] + ((flip ? -b[i] : b[i]) - a[i]) * fr;
        }

        // The rows at `time` seconds into a clip and the weight of the second: its instance numbers' frame.
        public bool ClipFrame(PalClip c, double time, out uint r0, out uint r1, out float fr)
        {
            return InstanceFrame(InstanceOf(c), time, out r0, out r1, out fr);
        }

        // The rows for the four per-instance numbers at `time` (docs/roster.md; the herd's clock), as the
        // shaders' cb_frame and the C runtime's cb_runtime_frame_in: inst[1] counts rows, or with inst[2] < 0 (a
        // timed clip) the cells of its grid at -inst[2] cells a second, whose map texel names the two rows and
        // the weight at the cell's ends (linear between). Held rows (inst[0] < 0) take the first row alone.
        public bool InstanceFrame(float[] inst, double time, out uint r0, out uint r1, out float fr)
        {
            bool timed = inst[2] < 0, held = inst[0] < 0, loops = inst[1] > 0;
            double n = Math.Abs((double)inst[1]), u = time * Math.Abs((double)inst[2]) + inst[3] * n, f0, f1;
            r0 = r1 = 0;
            fr = 0;
            if (double.IsNaN(u) || double.IsInfinity(u) || n < 1) return false;
            if (loops) {
                u -= n * Math.Floor(u / n);
                if (!(u >= 0 && u < n)) u = 0; // rounding at the wrap
            } else {
                u = Math.Min(Math.Max(u, 0), timed ? n : n - 1); // a timed one-shot ends at its last cell's end
            }
            f0 = Math.Min(Math.Floor(u), n - 1);
            f1 = loops ? (f0 + 1 < n ? f0 + 1 : 0) : Math.Min(f0 + 1, n - 1); // a loop's last row blends into its first
            double w = u - f0, first = held ? -(double)inst[0] - 1 : inst[0];
            if (timed) { // the cell's map texel: its two rows, the weight across the cell
                var m = new double[4];
                if (!MapTexel((uint)first, (uint)n, (uint)f0, m)) return false;
                f0 = m[0];
                f1 = m[1];
                w = m[2] + (m[3] - m[2]) * w;
            }
            if (held) { f1 = f0; w = 0; } // a stepped clip: its row alone, no blend across a step
            fr = (float)w;
            r0 = (uint)first + (uint)f0;
            r1 = (uint)first + (uint)f1;
            return true;
        }

        // The bone's skinning matrix (column-major 4x4, bind space to the posed model) `time` seconds
        // into clip `clip`: loops wrap, one-shots clamp. False for a clip or bone that does not
        // exist or a time that is not finite.
        public bool BoneMatrix(uint clip, double time, uint bone, float[] m)
        {
            uint r0, r1;
            float fr;
            if (clip >= Clips.Length || bone >= Bones.Length || !ClipFrame(Clips[clip], time, out r0, out r1, out fr)) return false;
            RowsMatrix(r0, r1, fr, bone, m);
            return true;
        }

        // The same for an instance's four numbers (first row, frame count, rate, phase) at `time`.
        public bool InstanceBoneMatrix(float[] inst, double time, uint bone, float[] m)
        {
            uint r0, r1;
            float fr;
            if (bone >= Bones.Length || !InstanceFrame(inst, time, out r0, out r1, out fr) || r0 >= Header.Rows || r1 >= Header.Rows)
                return false;
            RowsMatrix(r0, r1, fr, bone, m);
            return true;
        }

        // A row's travel offset along its clip's heading, model units (0 in files without the table).
        public float RowTravel(uint row)
        {
            return Header.TravelTableOffset != 0 && row < Header.Rows ? F32(data, Header.TravelTableOffset + (ulong)row * 4) : 0;
        }

        // The body's travel offset `time` seconds into clip `clip`, model units in the model's frame:
        // the rows' offsets blended as the shaders blend the rows, along the clip's heading
        // (cbpal_travel_offset). False for a clip that does not exist or a time that is not finite.
        public bool TravelOffset(uint clip, double time, float[] o)
        {
            uint r0, r1;
            float fr;
            Array.Clear(o, 0, 3);
            if (clip >= Clips.Length || !ClipFrame(Clips[clip], time, out r0, out r1, out fr)) return false;
            AlongHeading(Clips[clip], r0, r1, fr, o);
            return true;
        }

        // The same for an instance's four numbers at `time`, its clip found by its first row.
        public bool InstanceTravelOffset(float[] inst, double time, float[] o)
        {
            uint r0, r1;
            float fr;
            Array.Clear(o, 0, 3);
            if (!InstanceFrame(inst, time, out r0, out r1, out fr)) return false;
            double first = inst[0] < 0 ? -(double)inst[0] - 1 : inst[0];
            foreach (PalClip c in Clips)
                if (c.FirstRow == first) AlongHeading(c, r0, r1, fr, o);
            return true;
        }

        void AlongHeading(PalClip c, uint r0, uint r1, float fr, float[] o)
        {
            float a = RowTravel(r0), v = a + (RowTravel(r1) - a) * fr;
            for (int k = 0; k < 3; ++k) o[k] = v * c.TravelHeading[k];
        }

        // Two rows blended into the joint matrix M (cbpal_bone_matrix's body).
        public void RowsMatrix(uint r0, uint r1, float fr, uint bone, float[] m)
        {
            PalHeader h = Header;
            if (LocalRows) { // the bone's chain blended and composed (PalLocalRows.cs)
                LocalMatrix(new[] { r0, r1, r0, r1 }, new[] { fr, fr }, 1, bone, m);
                return;
            }
            var t = new float[4][];
            for (uint k = 0; k < 4; ++k) t[k] = new float[4];
            for (uint k = 0; k < h.TexelsPerBone; ++k) Mix(r0, r1, fr, bone, k, t[k]);
            Array.Clear(m, 0, 16);
            m[15] = 1.0f;
            var p = new float[3];
            if (h.Layout == (uint)PalLayout.Qpos) {
                float n = (float)Math.Sqrt(t[0][0] * t[0][0] + t[0][1] * t[0][1] + t[0][2] * t[0][2] + t[0][3] * t[0][3]);
                float x = t[0][0] / n, y = t[0][1] / n, z = t[0][2] / n, w = t[0][3] / n;
                float[] r = { 1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),  // column 0
                              2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),  // column 1
                              2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y) }; // column 2
                for (int k = 0; k < 9; ++k) m[k / 3 * 4 + k % 3] = t[1][3] * r[k]; // scale
                for (int k = 0; k < 3; ++k) p[k] = t[1][k];
            } else {
                bool affine = h.Layout == (uint)PalLayout.Affine; // affine: texel k is row k; mat4: texel k is column k
                for (int k = 0; k < 12; ++k) m[k / 3 * 4 + k % 3] = affine ? t[k % 3][k / 3] : t[k / 3][k % 3];
                for (int k = 0; k < 3; ++k) p[k] = affine ? t[k][3] : t[3][k];
            }
            // qpos and relative positions: A (v - b) + p, with p stored less the bone's position offset.
            PalBone b = Bones[bone];
            bool aboutBind = h.Layout == (uint)PalLayout.Qpos || (h.Flags & FlagPositionsRelative) != 0;
            for (int k = 0; k < 3; ++k) {
                m[12 + k] = p[k] + b.PositionOffset[k];
                if (aboutBind)
                    m[12 + k] -= m[k] * b.BindPosition[0] + m[4 + k] * b.BindPosition[1] + m[8 + k] * b.BindPosition[2];
            }
        }
    }

    // XXH64 (seed 0), streaming: the format's checksum (from the algorithm's specification).
    public sealed class Xxh64
    {
        const ulong P1 = 0x9E3779B185EBCA87UL, P2 = 0xC2B2AE3D27D4EB4FUL, P3 = 0x165667B19E3779F9UL;
        const ulong P4 = 0x85EBCA77C2B2AE63UL, P5 = 0x27D4EB2F165667C5UL;
        readonly ulong[] v = { unchecked(P1 + P2), P2, 0, unchecked(0UL - P1) };
        readonly byte[] buf = new byte[32];
        ulong total;
        int buffered;

        static ulong Rotl(ulong x, int r) { return (x << r) | (x >> (64 - r)); }
        static ulong Read64(byte[] p, int at) { return BitConverter.ToUInt64(p, at); }
        static ulong Round(ulong acc, ulong input) { return unchecked(Rotl(acc + input * P2, 31) * P1); }
        static ulong Merge(ulong acc, ulong val) { return unchecked((acc ^ Round(0, val)) * P1 + P4); }

        void Stripe(byte[] p, int at)
        {
            for (int i = 0; i < 4; ++i) v[i] = Round(v[i], Read64(p, at + 8 * i));
        }

        public void Update(byte[] data, int offset, int size)
        {
            total += (ulong)size;
            if (buffered > 0) {
                int take = Math.Min(32 - buffered, size);
                Array.Copy(data, offset, buf, buffered, take);
                buffered += take;
                offset += take;
                size -= take;
                if (buffered < 32) return;
                Stripe(buf, 0);
                buffered = 0;
            }
            for (; size >= 32; offset += 32, size -= 32) Stripe(data, offset);
            Array.Copy(data, offset, buf, 0, size);
            buffered = size;
        }

        public ulong Digest()
        {
            unchecked {
                ulong h = total >= 32 ? Rotl(v[0], 1) + Rotl(v[1], 7) + Rotl(v[2], 12) + Rotl(v[3], 18) : P5;
                if (total >= 32)
                    for (int i = 0; i < 4; ++i) h = Merge(h, v[i]);
                h += total;
                int p = 0, n = buffered;
                for (; n >= 8; p += 8, n -= 8) h = Rotl(h ^ Round(0, Read64(buf, p)), 27) * P1 + P4;
                if (n >= 4) {
                    h = Rotl(h ^ ((ulong)BitConverter.ToUInt32(buf, p) * P1), 23) * P2 + P3;
                    p += 4;
                    n -= 4;
                }
                for (; n > 0; ++p, --n) h = Rotl(h ^ (buf[p] * P5), 11) * P1;
                h ^= h >> 33;
                h *= P2;
                h ^= h >> 29;
                h *= P3;
                h ^= h >> 32;
                return h;
            }
        }
    }
}
