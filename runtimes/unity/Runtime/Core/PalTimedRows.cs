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

        // C's %g of a float, for messages equal to the C reader's word for word.
        static string G(double v)
        {
            return v.ToString("G6", System.Globalization.CultureInfo.InvariantCulture).Replace("E", "e");
        }

        static string NameOf(PalHeader h, byte[] d, ulong clipAt)
        {
            ulong at = h.StringsOffset + U32(d, clipAt);
            int end = (int)at;
            while (end < d.Length && d[end] != 0) ++end;
            return System.Text.Encoding.UTF8.GetString(d, (int)at, end - (int)at);
        }

        // The timed clip table (flag bit 6, header offset 208): version 7, clip_count entries of 16 bytes inside the
        // file (cbpal__validate_timed_table).
        static void ValidateTimedTable(PalHeader h, byte[] d)
        {
            if ((h.Flags & FlagTimedRows) == 0) return;
            if (h.Version < 7) throw Fail("flag bit 6 (timed rows) in a version " + h.Version + " file; timed rows are v7");
            ulong at = h.TimedTableOffset;
            if (!Fits(at, h.ClipCount, TimedEntryBytes, (ulong)d.Length) || at < HeaderBytes || at % 4 != 0)
                throw Fail("timed clip table (offset " + at + ", " + h.ClipCount + " clips) lies outside the file; the file is truncated " +
                           "or corrupt: re-bake it");
        }

        // Each clip (cbpal__validate_timed): clip flag bit 3 <=> a nonzero entry; a timed one's cells >= 1, cell_rate > 0
        // and finite, reserved 0, map_rows = ceil(cells / row_texels) <= first_row.
        static void ValidateTimedClips(PalHeader h, byte[] d)
        {
            for (uint i = 0; (h.Flags & FlagTimedRows) == 0 && i < h.ClipCount; ++i) {
                ulong c = h.ClipTableOffset + (ulong)i * ClipBytes;
                if ((U32(d, c + 28) & ClipTimed) != 0)
                    throw Fail("clip " + i + " (" + NameOf(h, d, c) + ") is marked timed (clip flag bit 3) in a file without timed rows " +
                               "(header flag bit 6); the file is corrupt: re-bake it");
            }
            if ((h.Flags & FlagTimedRows) == 0) return;
            for (uint i = 0; i < h.ClipCount; ++i) {
                ulong c = h.ClipTableOffset + (ulong)i * ClipBytes, e = h.TimedTableOffset + (ulong)i * TimedEntryBytes;
                uint cells = U32(d, e), mapRows = U32(d, e + 8), first = U32(d, c + 8);
                float rate = F32(d, e + 4);
                bool timed = (U32(d, c + 28) & ClipTimed) != 0;
                bool entry = cells != 0 || U32(d, e + 4) != 0 || mapRows != 0 || U32(d, e + 12) != 0;
                ulong want = ((ulong)cells + h.RowTexels - 1) / h.RowTexels;
                if (timed != entry)
                    throw Fail("clip " + i + " (" + NameOf(h, d, c) + "): clip flag bit 3 (timed) is " + (timed ? "set" : "clear") +
                               " but its timed table entry is " + (entry ? "not 0" : "0") + "; the file is corrupt: re-bake it");
                if (timed && (cells == 0 || !(rate > 0) || float.IsInfinity(rate) || U32(d, e + 12) != 0 || mapRows != want || mapRows > first))
                    throw Fail("clip " + i + " (" + NameOf(h, d, c) + "): bad timed entry (cells " + cells + ", cell_rate " + G(rate) +
                               ", map_rows " + mapRows + " for ceil(cells / " + h.RowTexels + ") = " + want + ", first row " + first +
                               "); the file is corrupt: re-bake it");
            }
        }

        // Every timed clip's map (cbpal__validate_maps, once the texels are at hand: after the checksum): each cell's
        // rows whole and below the clip's frames, its weights 0 <= f0 <= f1 <= 1.
        void ValidateMaps()
        {
            var m = new double[4];
            for (uint i = 0; i < Clips.Length; ++i) {
                PalClip c = Clips[i];
                for (uint cell = 0; c.Cells != 0 && cell < c.Cells; ++cell) {
                    DecodeMapTexel(Header, data, MapTexelAt(Header, c.FirstRow, c.Cells, cell), m);
                    for (int k = 0; k < 4; ++k) m[k] = (float)m[k]; // the C reader's floats
                    if (!(m[0] >= 0 && m[0] < c.Frames && m[0] == Math.Floor(m[0]) && m[1] >= 0 && m[1] < c.Frames && m[1] == Math.Floor(m[1]) &&
                          m[2] >= 0 && m[2] <= m[3] && m[3] <= 1))
                        throw Fail("clip " + i + " (" + c.Name + "): its map's cell " + cell + " reads rows " + G(m[0]) + ", " + G(m[1]) +
                                   " and weights " + G(m[2]) + ", " + G(m[3]) + " (rows must be whole and below its " + c.Frames +
                                   " frames, weights 0 <= f0 <= f1 <= 1); the file is corrupt: re-bake it");
                }
            }
        }
    }
}
