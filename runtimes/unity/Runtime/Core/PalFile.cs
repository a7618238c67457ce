// PalFile.cs - reader for crowdbake .pal bone-matrix palettes (docs/pal-format.md), in plain C#
// (no UnityEngine): the importer, the herd and the tests (under mono) share it. It makes the
// checks of the C reader include/crowdbake_pal.h, in the same order with the same verdicts, and
// its BoneMatrix gives the numbers of cbpal_bone_matrix (tests/runtimes/test_unity_cs.c holds them equal
// on every layout x precision).
//
// zstd payloads (bake --zstd) are refused with the fix: .NET has no zstd decoder, and a Unity
// project imports the palette once, so the uncompressed file costs nothing at run time.
using System;
using System.Text;

namespace Crowdbake
{
    public sealed class PalException : Exception
    {
        public PalException(string message) : base(message) { }
    }

    public enum PalLayout { Mat4 = 0, Affine = 1, Qpos = 2 }
    public enum PalPrecision { Float = 0, Half = 1, U16 = 2 }

    public sealed class PalHeader
    {
        public uint Version, Flags, HeaderSize, Layout, Precision, TexelsPerBone, BoneCount, RowTexels;
        public uint Rows, Width, Height, Blocks, TexelBytes, ClipCount;
        public float Fps, SpeedReference, LinearRange, MaxError, ModelHeight, VisibleError;
        public float[] BoundsMin = new float[3], BoundsMax = new float[3];
        public ulong InputHash, ClipTableOffset, BoneTableOffset, StringsOffset, StringsSize;
        public ulong PayloadOffset, PayloadSize, PayloadRawSize, Checksum, OffsetTableOffset, TravelTableOffset;
        public ulong BoneRangeTableOffset; // version 6 with flag bit 5 (local rows): bone_count x 32 bytes
        public ulong TimedTableOffset; // version 7 with flag bit 6 (timed rows): clip_count x 16 bytes
    }

    public struct PalClip
    {
        public string Name;
        public uint FirstRow, Frames, Flags;
        public float Fps, Duration, Start;
        public float[] RootVelocity, BoundsMin, BoundsMax;
        public float[] TravelHeading; // version 5: the direction its rows' travel offsets lie along (0 where it has none)
        // Version 7, a timed clip (clip flag bit 3): its rows lie on a grid of Cells steps, CellRate cells a second,
        // its map in the MapRows rows before FirstRow (PalTimedRows.cs); all 0 for an untimed clip.
        public uint Cells, MapRows;
        public float CellRate;
        public bool Timed { get { return (Flags & PalFile.ClipTimed) != 0; } }
        public bool Loops { get { return (Flags & PalFile.ClipLoops) != 0; } }
        // Its rows are held, not blended (a STEP-keyed clip): the instance's first row is -FirstRow - 1.
        public bool Step { get { return (Flags & PalFile.ClipStep) != 0; } }
    }

    public struct PalBone
    {
        public string Name;
        public int Parent;
        public float[] BindPosition, PositionOffset;
        // Version 6, local rows: the box of this bone's stored positions and its largest stored scale
        // (u16 rows decode with them); zero in other files.
        public float[] RangeMin, RangeMax;
        public float ScaleMax;
    }

    public sealed partial class PalFile
    {
        public const uint NewestVersion = 7, HeaderBytes = 256, ClipBytes = 80, BoneBytes = 32, PayloadAlign = 4096;
        public const int ChecksumOffset = 176;
        public const uint FlagZstd = 1, FlagInPlace = 2, FlagPositionsRelative = 4, FlagFittedRows = 8, FlagLocalRows = 32, FlagTimedRows = 64;
        public const uint ClipLoops = 1, ClipFitted = 2, ClipStep = 4; // ClipStep (version 4): rows held, not blended
        public const uint ClipTimed = 8; // version 7: rows at cells of a grid, read through the clip's map
        static readonly byte[] Magic = { 0x43, 0x42, 0x50, 0x41, 0x4C, 0x0D, 0x0A, 0x1A };

        public readonly PalHeader Header;
        public readonly PalClip[] Clips;
        public readonly PalBone[] Bones;
        readonly byte[] data;

        // The texels, width x height x TexelBytes from TexelOffset in Data (uncompressed: a view, no copy).
        public byte[] Data { get { return data; } }
        public int TexelOffset { get { return (int)Header.PayloadOffset; } }
        public int TexelSize { get { return (int)Header.PayloadRawSize; } }

        PalFile(byte[] bytes, PalHeader h)
        {
            data = bytes;
            Header = h;
            Clips = new PalClip[h.ClipCount];
            for (uint i = 0; i < h.ClipCount; ++i) Clips[i] = ReadClip(i);
            Bones = new PalBone[h.BoneCount];
            for (uint i = 0; i < h.BoneCount; ++i) Bones[i] = ReadBone(i);
        }

        // Reads and checks a whole .pal file's bytes; `name` prefixes every error ("goat.pal: ...").
        public static PalFile Read(byte[] bytes, string name, bool verifyChecksum)
        {
            try {
                PalHeader h = Validate(bytes);
                if (verifyChecksum && ComputeChecksum(bytes, h.PayloadOffset + h.PayloadSize) != h.Checksum)
                    throw new PalException("checksum mismatch: the file is corrupted");
                if ((h.Flags & FlagZstd) != 0)
                    throw new PalException("payload is zstd-compressed, which this reader does not decompress; bake it again without --zstd");
                var pal = new PalFile(bytes, h);
                pal.ValidateMaps(); // the texels at hand, after the checksum (include/crowdbake_pal.h's order)
                return pal;
            } catch (PalException e) {
                throw new PalException(name + ": " + e.Message);
            }
        }

        public static PalFile Read(string path, bool verifyChecksum)
        {
            return Read(System.IO.File.ReadAllBytes(path), path, verifyChecksum);
        }

        // ---- little-endian fields ----
        static uint U32(byte[] d, ulong at)
        {
            int i = (int)at;
            return (uint)(d[i] | d[i + 1] << 8 | d[i + 2] << 16 | d[i + 3] << 24);
        }
        static ulong U64(byte[] d, ulong at) { return U32(d, at) | (ulong)U32(d, at + 4) << 32; }
        static float F32(byte[] d, ulong at) { return BitConverter.ToSingle(BitConverter.GetBytes(U32(d, at)), 0); }
        static ushort U16(byte[] d, int at) { return (ushort)(d[at] | d[at + 1] << 8); }

        // begin + count * size <= limit, without overflow (cbpal__fits).
        static bool Fits(ulong begin, ulong count, ulong size, ulong limit)
        {
            if (begin > limit) return false;
            return size == 0 || count <= (limit - begin) / size;
        }

        static bool CheckString(PalHeader h, byte[] d, uint offset, uint length)
        {
            return (ulong)offset + length < h.StringsSize && d[(int)(h.StringsOffset + offset + length)] == 0;
        }

        static PalException Fail(string message) { return new PalException(message); }

        static PalHeader ReadHeader(byte[] d)
        {
            var h = new PalHeader();
            h.Version = U32(d, 8); h.Flags = U32(d, 12); h.HeaderSize = U32(d, 16); h.Layout = U32(d, 20);
            h.Precision = U32(d, 24); h.TexelsPerBone = U32(d, 28); h.BoneCount = U32(d, 32); h.RowTexels = U32(d, 36);
            h.Rows = U32(d, 40); h.Width = U32(d, 44); h.Height = U32(d, 48); h.Blocks = U32(d, 52);
            h.TexelBytes = U32(d, 56); h.ClipCount = U32(d, 60); h.Fps = F32(d, 64); h.SpeedReference = F32(d, 68);
            h.LinearRange = F32(d, 72);
            for (uint k = 0; k < 3; ++k) {
                h.BoundsMin[k] = F32(d, 76 + 4 * k);
                h.BoundsMax[k] = F32(d, 88 + 4 * k);
            }
            h.MaxError = F32(d, 100); h.ModelHeight = F32(d, 104); h.VisibleError = F32(d, 108);
            h.InputHash = U64(d, 112); h.ClipTableOffset = U64(d, 120); h.BoneTableOffset = U64(d, 128);
            h.StringsOffset = U64(d, 136); h.StringsSize = U64(d, 144); h.PayloadOffset = U64(d, 152);
            h.PayloadSize = U64(d, 160); h.PayloadRawSize = U64(d, 168); h.Checksum = U64(d, 176);
            h.OffsetTableOffset = h.Version >= 3 ? U64(d, 184) : 0;
            // Version 5: the per-row travel offsets (docs/pal-format.md), which HerdState.TravelOffsetAt adds.
            h.TravelTableOffset = h.Version >= 5 && (h.Flags & 16u) != 0 ? U64(d, 192) : 0;
            // Version 6: each bone's range, for local rows (PalLocalRows.cs).
            h.BoneRangeTableOffset = h.Version >= 6 && (h.Flags & FlagLocalRows) != 0 ? U64(d, 200) : 0;
            // Version 7: the timed clip table (PalTimedRows.cs).
            h.TimedTableOffset = h.Version >= 7 && (h.Flags & FlagTimedRows) != 0 ? U64(d, 208) : 0;
            return h;
        }

        // cbpal__validate: every offset and size against the file length, before anything is read.
        static PalHeader Validate(byte[] d)
        {
            ulong size = (ulong)d.Length;
            bool magic = size >= 8;
            for (int i = 0; magic && i < 8; ++i) magic = d[i] == Magic[i];
            if (!magic) throw Fail("not a crowdbake palette (wrong magic)");
            if (size < 12) throw Fail("truncated: " + size + " bytes, shorter than the header");
            uint version = U32(d, 8);
            if (version > NewestVersion)
                throw Fail("palette format version " + version + " is newer than this reader (version " + NewestVersion + "); update the reader");
            if (version < 1) throw Fail("unknown palette format version " + version);
            if (size < HeaderBytes) throw Fail("truncated: " + size + " bytes, shorter than the header");
            PalHeader h = ReadHeader(d);
            if (h.HeaderSize != HeaderBytes) throw Fail("bad header size " + h.HeaderSize);
            if (h.Layout > 2 || h.Precision > 2) throw Fail("unknown layout " + h.Layout + " or precision " + h.Precision);
            uint[] tpb = { 4, 3, 2 }, tbytes = { 16, 8, 8 };
            if (h.TexelsPerBone != tpb[h.Layout] || h.TexelBytes != tbytes[h.Precision])
                throw Fail("texels per bone or bytes per texel do not match the layout and precision");
            if (h.BoneCount == 0 || (ulong)h.BoneCount * h.TexelsPerBone != h.RowTexels || h.Blocks == 0 ||
                (ulong)h.Blocks * h.RowTexels != h.Width || h.Height == 0 || (ulong)h.Height * h.Blocks < h.Rows ||
                (ulong)(h.Blocks - 1) * h.Height >= h.Rows || (ulong)h.Width * h.Height * h.TexelBytes != h.PayloadRawSize)
                throw Fail("inconsistent texture geometry (" + h.BoneCount + " bones, " + h.Rows + " rows, " + h.Width + "x" +
                           h.Height + " in " + h.Blocks + " blocks)");
            if (!Fits(h.ClipTableOffset, h.ClipCount, ClipBytes, size) || h.ClipTableOffset < HeaderBytes)
                throw Fail("clip table (offset " + h.ClipTableOffset + ", " + h.ClipCount + " clips) lies outside the file");
            if (!Fits(h.BoneTableOffset, h.BoneCount, BoneBytes, size) || h.BoneTableOffset < HeaderBytes)
                throw Fail("bone table (offset " + h.BoneTableOffset + ", " + h.BoneCount + " bones) lies outside the file");
            if (h.Version >= 3 && (h.Flags & FlagPositionsRelative) != 0 &&
                (!Fits(h.OffsetTableOffset, h.BoneCount, 12, size) || h.OffsetTableOffset < HeaderBytes))
                throw Fail("position offset table (offset " + h.OffsetTableOffset + ", " + h.BoneCount + " bones) lies outside the file");
            if (h.Version >= 5 && (h.Flags & 16u) != 0 && (!Fits(h.TravelTableOffset, h.Rows, 4, size) || h.TravelTableOffset < HeaderBytes))
                throw Fail("travel offset table (offset " + h.TravelTableOffset + ", " + h.Rows + " rows) lies outside the file");
            ValidateLocalRows(h, d);
            ValidateTimedTable(h, d);
            if (!Fits(h.StringsOffset, h.StringsSize, 1, size) || h.StringsOffset < HeaderBytes)
                throw Fail("string table lies outside the file");
            if (h.PayloadOffset % PayloadAlign != 0 || !Fits(h.PayloadOffset, h.PayloadSize, 1, size) || h.PayloadOffset < HeaderBytes)
                throw Fail("truncated or bad payload: offset " + h.PayloadOffset + " + " + h.PayloadSize + " bytes, file has " + size);
            if ((h.Flags & FlagZstd) == 0 && h.PayloadSize != h.PayloadRawSize)
                throw Fail("payload is " + h.PayloadSize + " bytes, the texture needs " + h.PayloadRawSize);
            for (uint i = 0; i < h.ClipCount; ++i) {
                ulong c = h.ClipTableOffset + (ulong)i * ClipBytes;
                uint first = U32(d, c + 8), frames = U32(d, c + 12);
                if (!CheckString(h, d, U32(d, c), U32(d, c + 4)) || frames == 0 || first > h.Rows || frames > h.Rows - first)
                    throw Fail("clip " + i + " has a bad name or rows " + first + ".." + (uint)(first + frames) + " outside the " + h.Rows + " rows");
            }
            for (uint i = 0; i < h.BoneCount; ++i) {
                ulong b = h.BoneTableOffset + (ulong)i * BoneBytes;
                int parent = (int)U32(d, b + 8);
                if (!CheckString(h, d, U32(d, b), U32(d, b + 4)) || parent < -1 || parent >= (int)h.BoneCount)
                    throw Fail("bone " + i + " has a bad name or parent");
            }
            ValidateTimedClips(h, d);
            ValidateParents(h, d);
            return h;
        }

        string StringAt(uint offset, uint length)
        {
            return Encoding.UTF8.GetString(data, (int)(Header.StringsOffset + offset), (int)length);
        }

        PalClip ReadClip(uint i)
        {
            ulong c = Header.ClipTableOffset + (ulong)i * ClipBytes;
            var clip = new PalClip {
                Name = StringAt(U32(data, c), U32(data, c + 4)), FirstRow = U32(data, c + 8), Frames = U32(data, c + 12),
                Fps = F32(data, c + 16), Duration = F32(data, c + 20), Start = F32(data, c + 24),
                Flags = U32(data, c + 28) | ((Header.Flags & FlagFittedRows) != 0 ? ClipFitted : 0u),
                RootVelocity = new float[3], BoundsMin = new float[3], BoundsMax = new float[3], TravelHeading = new float[3]
            };
            for (uint k = 0; k < 3; ++k) {
                clip.RootVelocity[k] = F32(data, c + 32 + 4 * k);
                clip.BoundsMin[k] = F32(data, c + 44 + 4 * k);
                clip.BoundsMax[k] = F32(data, c + 56 + 4 * k);
                clip.TravelHeading[k] = Header.TravelTableOffset != 0 ? F32(data, c + 68 + 4 * k) : 0;
            }
            if (Header.TimedTableOffset != 0) {
                ulong e = Header.TimedTableOffset + (ulong)i * TimedEntryBytes;
                clip.Cells = U32(data, e);
                clip.CellRate = F32(data, e + 4);
                clip.MapRows = U32(data, e + 8);
            }
            return clip;
        }

        PalBone ReadBone(uint i)
        {
            PalHeader h = Header;
            ulong b = h.BoneTableOffset + (ulong)i * BoneBytes, o = h.OffsetTableOffset + (ulong)i * 12;
            var bone = new PalBone {
                Name = StringAt(U32(data, b), U32(data, b + 4)), Parent = (int)U32(data, b + 8),
                BindPosition = new float[3], PositionOffset = new float[3], RangeMin = new float[3], RangeMax = new float[3]
            };
            ReadBoneRange(i, ref bone);
            bool relative = (h.Flags & FlagPositionsRelative) != 0;
            for (uint k = 0; k < 3; ++k) {
                bone.BindPosition[k] = F32(data, b + 16 + 4 * k);
                bone.PositionOffset[k] = !relative ? 0.0f : h.Version >= 3 ? F32(data, o + 4 * k) : bone.BindPosition[k];
            }
            return bone;
        }

        // Texel coordinates of a bone's first texel in a baked row (rows wrap into column blocks).
        public void TexelXY(uint row, uint bone, out uint x, out uint y)
        {
            x = (row / Header.Height) * Header.RowTexels + bone * Header.TexelsPerBone;
            y = row % Header.Height;
        }

        // XXH64 of bytes [0, end) with the checksum field read as 0 (the header's checksum).
        public static ulong ComputeChecksum(byte[] d, ulong end)
        {
            var s = new Xxh64();
            s.Update(d, 0, ChecksumOffset);
            s.Update(new byte[8], 0, 8);
            s.Update(d, ChecksumOffset + 8, (int)end - ChecksumOffset - 8);
            return s.Digest();
        }

        internal ushort RawU16(int offset) { return U16(data, offset); }
    }
}
