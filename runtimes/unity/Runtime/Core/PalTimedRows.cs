// PalTimedRows.cs - .pal version 7's timed rows (header flag bit 6, clip flag bit 3; docs/pal-format.md
// "Timed rows"): a timed clip's rows lie at increasing cells of a grid of `cells` equal steps, and its map
// (one texel per cell, in the map rows just before its first row) names the two rows blended in the cell
// and the weights at its ends. The reader checks the timed clip table and every map texel as the format
// says; InstanceFrame (PalBoneMatrix.cs) reads the map for an instance whose third number is negative.
using System;

namespace Crowdbake
{
    public sealed partial class PalFile
    {
        public const uint TimedEntryBytes = 16;

        // ceil(cells / row_texels): the map rows before a timed clip's first row.
        public static uint TimedMapRows(uint cells, uint rowTexels)
        {
            return rowTexels == 0 ? 0 : (uint)(((ulong)cells + rowTexels - 1) / rowTexels);
        }

        // The four instance numbers of a clip at rate 1, phase 0 (cb_instance_of): held rows' first row
        // -first - 1, a one-shot's count negative; a timed clip counts its cells at -cell_rate (negative marks it).
        public static float[] InstanceOf(PalClip c)
        {
            float count = c.Timed ? c.Cells : c.Frames;
            return new[] { c.Step ? -(float)c.FirstRow - 1 : c.FirstRow, c.Loops ? count : -count, c.Timed ? -c.CellRate : c.Fps, 0f };
        }

        // Where cell `cell`'s map texel lies in the file: texel cell mod row_texels of row first - map_rows +
        // cell / row_texels, addressed as any texel (map rows wrap into column blocks like any row).
        static ulong MapTexelAt(PalHeader h, uint first, uint cells, uint cell)
        {
            ulong row = first - TimedMapRows(cells, h.RowTexels) + cell / h.RowTexels;
            ulong x = (row / h.Height) * h.RowTexels + cell % h.RowTexels, y = row % h.Height;
            return h.PayloadOffset + (y * h.Width + x) * h.TexelBytes;
        }

        // A map texel's (r0, r1, f0, f1): float and half as stored; u16 rows as integers, weights round(f x 65535).
        static void DecodeMapTexel(PalHeader h, byte[] d, ulong p, double[] m)
        {
            for (uint k = 0; k < 4; ++k) {
                if (h.Precision == (uint)PalPrecision.Float) m[k] = F32(d, p + 4 * k);
                else if (h.Precision == (uint)PalPrecision.Half) m[k] = HalfToFloat(U16(d, (int)(p + 2 * k)));
                else m[k] = k < 2 ? U16(d, (int)(p + 2 * k)) : U16(d, (int)(p + 2 * k)) / 65535.0;
            }
        }

        // Cell `cell`'s map texel of the timed clip whose first row is `first`: (r0, r1, f0, f1), rows relative
        // to `first`. False where the map would lie outside the texture (numbers of no timed clip).
        public bool MapTexel(uint first, uint cells, uint cell, double[] m)
        {
            if (cells == 0 || cell >= cells || TimedMapRows(cells, Header.RowTexels) > first || first > Header.Rows) return false;
            DecodeMapTexel(Header, data, MapTexelAt(Header, first, cells, cell), m);
            return true;
        }

        // The timed clip table (flag bit 6, header offset 208): version 7, inside the file before the payload,
        // clip_count entries of 16 bytes.
        static void ValidateTimedTable(PalHeader h, byte[] d)
        {
            if ((h.Flags & FlagTimedRows) == 0) return;
            if (h.Version < 7) throw Fail("flag bit 6 (timed rows) in a version " + h.Version + " file; timed rows are v7");
            ulong at = h.TimedTableOffset;
            if (!Fits(at, h.ClipCount, TimedEntryBytes, h.PayloadOffset) || at < HeaderBytes || at % 4 != 0)
                throw Fail("timed clip table (offset " + at + ", " + h.ClipCount + " clips) lies outside the file");
        }

        // Each clip's entry: clip flag bit 3 <=> a nonzero entry, cells >= 1, cell_rate > 0 and finite,
        // map_rows = ceil(cells / row_texels) <= first_row, reserved 0; then (uncompressed payloads) every map
        // texel's rows below the clip's frames and weights within [0, 1] with f0 <= f1.
        static void ValidateTimedClips(PalHeader h, byte[] d)
        {
            for (uint i = 0; i < h.ClipCount; ++i) {
                ulong c = h.ClipTableOffset + (ulong)i * ClipBytes;
                bool timed = (U32(d, c + 28) & ClipTimed) != 0;
                if ((h.Flags & FlagTimedRows) == 0) {
                    if (timed) throw Fail("clip " + i + " is timed (clip flag bit 3) in a file without timed rows (flag bit 6)");
                    continue;
                }
                ulong e = h.TimedTableOffset + (ulong)i * TimedEntryBytes;
                uint cells = U32(d, e), mapRows = U32(d, e + 8), first = U32(d, c + 8);
                float rate = F32(d, e + 4);
                bool zero = cells == 0 && U32(d, e + 4) == 0 && mapRows == 0 && U32(d, e + 12) == 0;
                if (!timed) {
                    if (!zero) throw Fail("clip " + i + " is not timed but has a timed clip table entry");
                    continue;
                }
                if (cells < 1 || !(rate > 0) || float.IsInfinity(rate) || mapRows != TimedMapRows(cells, h.RowTexels) ||
                    mapRows > first || U32(d, e + 12) != 0)
                    throw Fail("clip " + i + " has a bad timed entry (" + cells + " cells at " + rate + " a second, " + mapRows +
                               " map rows before row " + first + ")");
                if ((h.Flags & FlagZstd) == 0) ValidateMap(h, d, i, first, cells, U32(d, c + 12));
            }
        }

        static void ValidateMap(PalHeader h, byte[] d, uint clip, uint first, uint cells, uint frames)
        {
            var m = new double[4];
            for (uint cell = 0; cell < cells; ++cell) {
                DecodeMapTexel(h, d, MapTexelAt(h, first, cells, cell), m);
                if (!(m[0] >= 0 && m[0] < frames && m[1] >= 0 && m[1] < frames && m[0] == Math.Floor(m[0]) && m[1] == Math.Floor(m[1]) &&
                      m[2] >= 0 && m[3] <= 1 && m[2] <= m[3]))
                    throw Fail("clip " + clip + "'s map, cell " + cell + ": rows " + m[0] + ", " + m[1] + " of " + frames + ", weights " +
                               m[2] + ".." + m[3]);
            }
        }
    }
}
