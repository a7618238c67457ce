// CrowdbakeCheck.cs - prints what the Unity package's engine-free C# (runtimes/unity/Runtime/Core)
// reads, for tests/runtimes/test_unity_cs.c to hold against the C reader (include/crowdbake_pal.h) and
// against Python's reading of roster.json. Numbers are printed round-trip ("R").
//   mono CrowdbakeCheck.exe pal FILE.pal          header, clips, bones, bone matrices
//   mono CrowdbakeCheck.exe bad FILE.pal          the reader's verdicts, checksum verified and not: "ok" or the error
//   mono CrowdbakeCheck.exe roster roster.json    the manifest's types, clips, contacts, states, sockets
//   mono CrowdbakeCheck.exe herd FILE.pal roster.json TYPE   a herd's matrices, cross-fades, speeds, footsteps
//   mono CrowdbakeCheck.exe conformance DIR CASE OUT  a runtime conformance case (tests/runtimes/conformance.h):
//                                                     every instance's skinned positions, float32, into OUT
//   mono CrowdbakeCheck.exe bonepass                  the bone pass rule's choices and layouts (Core/BonePass.cs)
//   mono CrowdbakeCheck.exe timed FILE.pal            each clip made timed by hand (.pal version 7): matrices vs untimed
using System;
using System.Globalization;
using System.IO;
using System.Text;
using Crowdbake;

static class CrowdbakeCheck
{
    static readonly StringBuilder output = new StringBuilder();

    static string R(double v) { return v.ToString("R", CultureInfo.InvariantCulture); }
    static string R(float v) { return v.ToString("R", CultureInfo.InvariantCulture); }
    static void Line(params object[] parts)
    {
        for (int i = 0; i < parts.Length; ++i) {
            object p = parts[i];
            output.Append(i > 0 ? " " : "").Append(p is float ? R((float)p) : p is double ? R((double)p) : p.ToString());
        }
        output.Append('\n');
    }
    static void Matrix(string tag, object a, object b, object c, float[] m)
    {
        var parts = new object[20];
        parts[0] = tag; parts[1] = a; parts[2] = b; parts[3] = c;
        for (int k = 0; k < 16; ++k) parts[4 + k] = m[k];
        Line(parts);
    }

    static void Pal(string path)
    {
        PalFile pal = PalFile.Read(path, true);
        PalHeader h = pal.Header;
        Line("H", h.Version, h.Flags, h.Layout, h.Precision, h.BoneCount, h.Rows, h.Width, h.Height, h.Blocks, h.ClipCount,
             h.Fps, h.LinearRange, h.MaxError, h.ModelHeight, h.VisibleError, h.Checksum);
        for (int i = 0; i < pal.Clips.Length; ++i) {
            PalClip c = pal.Clips[i];
            Line("C", i, c.FirstRow, c.Frames, c.Flags, c.Fps, c.Duration, c.Start, c.BoundsMin[1], c.BoundsMax[1]);
        }
        for (int j = 0; j < pal.Bones.Length; ++j) {
            PalBone b = pal.Bones[j];
            Line("B", j, b.Parent, b.BindPosition[0], b.BindPosition[1], b.BindPosition[2], b.PositionOffset[0], b.PositionOffset[1],
                 b.PositionOffset[2]);
        }
        var m = new float[16];
        var o = new float[3];
        for (uint c = 0; c < pal.Clips.Length; ++c)
            for (int k = -1; k <= 9; ++k) {
                // grid times, between rows, before the start and past the end (loops wrap, one-shots clamp)
                double t = k * pal.Clips[c].Duration / 7.0 + 0.0123 * k;
                for (uint bone = 0; bone < pal.Bones.Length; ++bone) {
                    if (!pal.BoneMatrix(c, t, bone, m)) throw new Exception("BoneMatrix refused clip " + c + " bone " + bone);
                    Matrix("M", c, t, bone, m);
                }
                if (!pal.TravelOffset(c, t, o)) throw new Exception("TravelOffset refused clip " + c);
                Line("T", c, t, o[0], o[1], o[2]);
            }
    }

    // The verdict with the checksum verified, then without (the checks of the tables alone).
    static void Bad(string path)
    {
        foreach (bool verify in new[] { true, false })
            try {
                PalFile.Read(File.ReadAllBytes(path), "x.pal", verify);
                Line("ok");
            } catch (PalException e) {
                Line(e.Message);
            }
    }

    static void RosterLines(string path)
    {
        Roster roster = Roster.Parse(File.ReadAllText(path), path);
        foreach (RosterType t in roster.types) {
            Line("T", t.name, t.palette, t.layout, t.precision, t.bones, t.rows, t.speedReference, t.defaultState);
            foreach (RosterClip c in t.clips) {
                Line("L", t.name, c.name, c.firstRow, c.frameCount, c.fps, c.duration, c.loops ? 1 : 0, c.groundSpeed);
                if (c.timedRows != null) Line("R", t.name, c.name, c.timedRows.cells, c.timedRows.cellRate, c.timedRows.mapRows);
                foreach (RosterContact k in c.contacts) Line("K", t.name, c.name, k.foot, k.bone, k.time, k.lift);
            }
            foreach (RosterState s in t.states)
                Line("S", t.name, s.name, s.clip, s.firstRow, s.frameCount, s.rate, s.ratePerSpeed, s.goldenRatioPhase ? "golden_ratio" : "zero");
            foreach (RosterSocket k in t.sockets) {
                var parts = new object[20];
                parts[0] = "O"; parts[1] = t.name; parts[2] = k.name; parts[3] = k.bone;
                for (int i = 0; i < 16; ++i) parts[4 + i] = k.bindTransform[i];
                Line(parts);
            }
        }
    }

    // Each state's roster numbers and HerdState.InstanceData's four floats for instance 1 standing still and
    // at speed 2 (docs/roster.md): a timed state (its clip's timed_rows) counts cells and plays at a negative rate.
    static void RosterInstances(string path)
    {
        Roster roster = Roster.Parse(File.ReadAllText(path), path);
        var still = new float[4];
        var moving = new float[4];
        foreach (RosterType t in roster.types)
            foreach (RosterState s in t.states) {
                RosterTimedRows timed = t.Clip(s.clip).timedRows;
                HerdState.InstanceData(s, 0, 1, 0, still, 0);
                HerdState.InstanceData(s, 2, 1, 0, moving, 0);
                Line("D", t.name, s.name, timed != null ? timed.cells : 0, timed != null ? timed.cellRate : 0,
                     timed != null ? timed.mapRows : 0, s.frameCount, s.rate, s.ratePerSpeed, still[0], still[1], still[2],
                     still[3], moving[0], moving[1], moving[2], moving[3]);
            }
    }

    // The herd: each instance's matrix with its numbers (the C side recomputes it from the clip the
    // numbers point at), mid-fade and after; SetSpeed's frame before and after; footsteps.
    static void Herd(string palPath, string rosterPath, string typeName)
    {
        PalFile pal = PalFile.Read(palPath, false);
        RosterType type = Roster.Parse(File.ReadAllText(rosterPath), rosterPath).Type(typeName);
        var herd = new HerdState(pal, type, 8);
        herd.OnFootstep += (e) => Line("F", e.instance, e.bone, e.lands ? "land" : "lift", e.time, herd.Inst[e.instance * 4 + 1],
                                       herd.Inst[e.instance * 4 + 2], herd.Inst[e.instance * 4 + 3], herd.StateOf[e.instance]);
        var m = new float[16];
        herd.Update(0.5);
        for (int i = 0; i < herd.Count; ++i) herd.SetSpeed(i, 0.5f + 0.25f * i);
        string[] names = new string[type.states.Count];
        for (int s = 0; s < names.Length; ++s) names[s] = type.states[s].name;
        for (int step = 1; step <= 40; ++step) {
            double t = 0.5 + step * 0.05;
            herd.Update(t);
            if (step == 10) for (int i = 0; i < herd.Count; i += 2) herd.SetState(i, names[i % names.Length], 0.4f);
            if (step == 20) {
                int i = 1;
                double before = herd.Time * Math.Abs(herd.Inst[6]) + herd.Inst[7] * Math.Abs((double)herd.Inst[5]);
                herd.SetSpeed(i, 1.7f);
                double after = herd.Time * Math.Abs(herd.Inst[6]) + herd.Inst[7] * Math.Abs((double)herd.Inst[5]);
                Line("P", i, before, after, Math.Abs((double)herd.Inst[5]));
            }
            if (step % 5 != 1 && step != 12) continue;
            for (int i = 0; i < herd.Count; ++i)
                for (int bone = 0; bone < pal.Bones.Length; bone += 7) {
                    if (!herd.BoneMatrixAt(i, bone, m)) throw new Exception("BoneMatrixAt refused instance " + i);
                    Line("I", i, bone, herd.Time, herd.FadeWeight(i, herd.Time), herd.Inst[i * 4], herd.Inst[i * 4 + 1], herd.Inst[i * 4 + 2],
                         herd.Inst[i * 4 + 3], herd.From[i * 4], herd.From[i * 4 + 1], herd.From[i * 4 + 2], herd.From[i * 4 + 3]);
                    Matrix("N", i, bone, herd.Time, m);
                }
        }
    }

    static float[] Floats(string path)
    {
        byte[] b = File.ReadAllBytes(path);
        var f = new float[b.Length / 4];
        Buffer.BlockCopy(b, 0, f, 0, f.Length * 4);
        return f;
    }

    // A conformance case through the C# reader: each instance's bone matrices (PalFile.InstanceBoneMatrix,
    // cross-faded as the herd does) skin the case's mesh, positions in the expected file's order.
    static void Conformance(string dir, string name, string outPath)
    {
        var doc = (JsonObject)MiniJson.Parse(File.ReadAllText(Path.Combine(dir, "cases.json")));
        JsonObject k = null;
        foreach (object c in (System.Collections.Generic.List<object>)doc.Get("cases"))
            if ((string)((JsonObject)c).Get("name") == name) k = (JsonObject)c;
        if (k == null) throw new Exception("no conformance case " + name);
        PalFile pal = PalFile.Read(Path.Combine(dir, (string)k.Get("pal")), true);
        var mesh = (JsonObject)k.Get("mesh");
        float[] positions = Floats(Path.Combine(dir, (string)mesh.Get("positions")));
        float[] weights = Floats(Path.Combine(dir, (string)mesh.Get("weights")));
        byte[] joints = File.ReadAllBytes(Path.Combine(dir, (string)mesh.Get("joints")));
        int verts = positions.Length / 3, bones = pal.Bones.Length;
        var mats = new float[bones * 16];
        var m = new float[16];
        var output = new MemoryStream();
        var writer = new BinaryWriter(output);
        foreach (object g in (System.Collections.Generic.List<object>)k.Get("groups")) {
            var group = (JsonObject)g;
            double time = (double)group.Get("time");
            foreach (object o in (System.Collections.Generic.List<object>)group.Get("instances")) {
                var v = (System.Collections.Generic.List<object>)o;
                float[] inst = new float[4], from = new float[4];
                for (int i = 0; i < 4; ++i) {
                    inst[i] = (float)(double)v[4 + i];
                    from[i] = (float)(double)v[8 + i];
                }
                double length = (double)v[13];
                float fade = length > 0 ? (float)Math.Min(Math.Max((time - (double)v[12]) / length, 0), 1) : 1;
                for (uint bone = 0; bone < bones; ++bone) {
                    if (!pal.InstanceBoneMatrix(inst, from, fade, time, bone, m)) throw new Exception("InstanceBoneMatrix refused bone " + bone);
                    Array.Copy(m, 0, mats, bone * 16, 16);
                }
                for (int x = 0; x < verts; ++x) {
                    double[] p = new double[3];
                    for (int i = 0; i < 4; ++i) {
                        float w = weights[x * 4 + i];
                        if (w == 0) continue;
                        int j = joints[(x * 4 + i) * 2] | joints[(x * 4 + i) * 2 + 1] << 8;
                        for (int c = 0; c < 3; ++c)
                            p[c] += w * ((double)mats[j * 16 + c] * positions[x * 3] + (double)mats[j * 16 + 4 + c] * positions[x * 3 + 1] +
                                         (double)mats[j * 16 + 8 + c] * positions[x * 3 + 2] + mats[j * 16 + 12 + c]);
                    }
                    for (int c = 0; c < 3; ++c) writer.Write((float)p[c]);
                }
            }
        }
        writer.Flush();
        File.WriteAllBytes(outPath, output.ToArray());
    }

    // The bone pass rule for herd sizes around the thresholds, global and local, each mode, a given threshold, and
    // unavailable; then layouts: every thread of the dispatch mapped to its (instance, bone), which must cover each
    // pair once at the texel cb_passed_bone reads. D lines: mode local given instances vertices -> pass threshold reason.
    static void BonePassLines()
    {
        Line("T", BonePassRule.AutoVertices, BonePassRule.AutoVerticesLocal);
        int[] instances = { 1, 3, 9, 10, 11, 20, 50, 100, 1000, 4000 };
        int[] vertices = { 336, 1000, 1128, 4970 }; // a fish, a round number (3, 20, 50 of it: on a threshold), the quadruped sample, Cow
        foreach (BonePassMode mode in new[] { BonePassMode.Auto, BonePassMode.On, BonePassMode.Off })
            foreach (bool local in new[] { false, true })
                foreach (int given in new[] { 0, 20000 })
                    foreach (int n in instances)
                        foreach (int v in vertices) {
                            BonePassChoice c = BonePassRule.Choose(mode, given, local, n, v, null);
                            Line("D", (int)mode, local ? 1 : 0, given, n, v, c.bonePass ? 1 : 0, c.threshold, c.reason);
                        }
        foreach (BonePassMode mode in new[] { BonePassMode.Auto, BonePassMode.On }) {
            BonePassChoice c = BonePassRule.Choose(mode, 0, true, 4000, 4970, "no compute shaders");
            Line("U", (int)mode, c.bonePass ? 1 : 0, c.reason);
        }
        int[,] layouts = { { 1, 1, 16384 }, { 7, 41, 16384 }, { 100, 17, 16384 }, { 1023, 41, 16384 }, { 4000, 17, 1024 },
                           { 10000, 41, 4096 }, { 65, 3, 8 }, { 9, 2, 4 }, { 9, 2, 8 }, { 65, 3, 16 }, { 200, 41, 8192 }, { 100000, 41, 16384 }, { 9, 3, 4 } };
        for (int k = 0; k < layouts.GetLength(0); ++k) {
            int n = layouts[k, 0], bones = layouts[k, 1], max = layouts[k, 2];
            BonePassLayout l;
            try {
                l = BonePassLayout.For(n, bones, max);
            } catch (ArgumentException e) {
                Line("E", n, bones, max, e.Message);
                continue;
            }
            var seen = new int[n * bones];
            int threads = 0, misplaced = 0;
            int tx = l.ThreadGroupsX * BonePassLayout.ThreadGroupSize, ty = l.ThreadGroupsY * BonePassLayout.ThreadGroupSize;
            for (int y = 0; y < ty; ++y)
                for (int x = 0; x < tx; ++x) {
                    int i, j, px, py;
                    if (!l.ThreadTexel(x, y, out i, out j)) continue;
                    ++threads;
                    ++seen[i * bones + j];
                    l.Texel(i, j, out px, out py);
                    if (px != x || py != y || j < 0 || j >= bones) ++misplaced;
                }
            int once = 0;
            foreach (int c in seen) once += c == 1 ? 1 : 0;
            Line("L", n, bones, max, l.rows, l.blocks, l.width, l.ThreadGroupsX, l.ThreadGroupsY, l.TextureBytes,
                 BonePassLayout.BytesPerInstance(bones), threads, once, misplaced);
        }
    }

    // ---- A timed palette made by hand (.pal version 7) from an untimed one ----
    static void Put32(byte[] b, int at, uint v) { for (int i = 0; i < 4; ++i) b[at + i] = (byte)(v >> (8 * i)); }
    static uint Get32(byte[] b, int at) { return (uint)(b[at] | b[at + 1] << 8 | b[at + 2] << 16 | b[at + 3] << 24); }

    // A half float's bits for a value it holds exactly (0, 0.5, 1, integers below 2048).
    static ushort ExactHalf(double v)
    {
        if (v == 0) return 0;
        int e = (int)Math.Floor(Math.Log(v, 2));
        return (ushort)((e + 15) << 10 | (int)Math.Round((v / Math.Pow(2, e) - 1) * 1024));
    }

    // Clip `clip` of `good` made timed: its grid twice as fine as its rows (cells = 2 x intervals, cell_rate =
    // 2 fps; row k on cell 2k), its map written over the rows just before it (the previous clip's, no longer
    // read), the timed table in the padding before the payload. Its matrices then equal the untimed clip's.
    static byte[] MakeTimed(byte[] good, PalFile pal, uint clip, bool badMap)
    {
        PalHeader h = pal.Header;
        PalClip c = pal.Clips[clip];
        uint cells = 2 * (c.Loops ? c.Frames : c.Frames - 1), mapRows = PalFile.TimedMapRows(cells, h.RowTexels);
        if (mapRows > c.FirstRow) throw new Exception("clip " + clip + " has no room for its map");
        ulong table = (h.PayloadOffset - h.ClipCount * 16) & ~15UL;
        byte[] b = (byte[])good.Clone();
        for (ulong at = table; at < h.PayloadOffset; ++at)
            if (b[at] != 0) throw new Exception("no padding for the timed table");
        Put32(b, 8, 7);
        Put32(b, 12, h.Flags | PalFile.FlagTimedRows);
        Put32(b, 208, (uint)table);
        int entry = (int)table + (int)clip * 16, clipAt = (int)h.ClipTableOffset + (int)clip * 80;
        Put32(b, entry, cells);
        Put32(b, entry + 4, BitConverter.ToUInt32(BitConverter.GetBytes(2 * c.Fps), 0));
        Put32(b, entry + 8, mapRows);
        Put32(b, clipAt + 28, Get32(b, clipAt + 28) | PalFile.ClipTimed);
        for (uint cell = 0; cell < cells; ++cell) {
            uint k = cell / 2, row = c.FirstRow - mapRows + cell / h.RowTexels;
            double[] m = { k, k + 1 < c.Frames ? k + 1 : 0, (cell % 2) * 0.5, (cell % 2) * 0.5 + 0.5 };
            if (badMap && cell == cells / 2) m[1] = c.Frames; // a row past the clip's: the reader refuses it
            ulong x = (row / h.Height) * h.RowTexels + cell % h.RowTexels, y = row % h.Height;
            int p = (int)(h.PayloadOffset + (y * h.Width + x) * h.TexelBytes);
            for (int i = 0; i < 4; ++i) {
                if (h.Precision == (uint)PalPrecision.Float) Put32(b, p + 4 * i, BitConverter.ToUInt32(BitConverter.GetBytes((float)m[i]), 0));
                else {
                    ushort v = h.Precision == (uint)PalPrecision.Half ? ExactHalf(m[i]) : (ushort)(i < 2 ? m[i] : Math.Round(m[i] * 65535));
                    b[p + 2 * i] = (byte)v;
                    b[p + 2 * i + 1] = (byte)(v >> 8);
                }
            }
        }
        return b;
    }

    static double WorstDifference(float[] a, float[] b, double worst)
    {
        for (int k = 0; k < 16; ++k) worst = Math.Max(worst, Math.Abs(a[k] - b[k]) / Math.Max(1.0, Math.Abs(b[k])));
        return worst;
    }

    // T lines: clip, its cells, the worst relative difference of the timed clip's bone matrices (BoneMatrix, the
    // herd's BoneMatrixAt and travel offsets) from the untimed clip's at 23 times, and of the same numbers read
    // without the map (rate positive: cells taken for rows). V lines: the reader's verdict on a bad map.
    static void Timed(string path)
    {
        byte[] good = File.ReadAllBytes(path);
        PalFile plain = PalFile.Read(good, "plain", true);
        for (uint clip = 1; clip < plain.Clips.Length; ++clip) {
            PalClip c = plain.Clips[clip];
            uint cells = 2 * (c.Loops ? c.Frames : c.Frames - 1);
            if (PalFile.TimedMapRows(cells, plain.Header.RowTexels) > c.FirstRow || c.Frames < 2) continue;
            PalFile timed = PalFile.Read(MakeTimed(good, plain, clip, false), "timed", false);
            if (timed.Header.Version != 7 || !timed.Clips[clip].Timed || timed.Clips[clip].Cells != cells) throw new Exception("timed clip not read");
            float[] inst = PalFile.InstanceOf(timed.Clips[clip]), ignored = (float[])inst.Clone();
            ignored[2] = -ignored[2];
            var herd = new HerdState(timed, null, 1);
            herd.SetState(0, c.Name, 0);
            herd.SetPhase(0, 0);
            float[] a = new float[16], b = new float[16], h = new float[16], o = new float[3], ot = new float[3];
            double worst = 0, travel = 0, without = 0;
            for (int k = -1; k < 22; ++k) {
                double t = k * c.Duration / 17.0 + 0.0071 * k;
                herd.Update(t);
                plain.TravelOffset(clip, t, o);
                timed.TravelOffset(clip, t, ot);
                for (int i = 0; i < 3; ++i) travel = Math.Max(travel, Math.Abs(o[i] - ot[i]));
                for (uint bone = 0; bone < plain.Bones.Length; ++bone) {
                    if (!plain.BoneMatrix(clip, t, bone, a) || !timed.BoneMatrix(clip, t, bone, b) || !herd.BoneMatrixAt(0, (int)bone, h))
                        throw new Exception("a bone matrix refused");
                    worst = WorstDifference(b, a, WorstDifference(h, a, worst));
                    if (timed.InstanceBoneMatrix(ignored, t, bone, b)) without = WorstDifference(b, a, without);
                    else without = double.PositiveInfinity; // rows past the texture: refused, as far off as can be
                }
            }
            Line("T", clip, cells, worst, travel, without);
        }
        try {
            PalFile.Read(MakeTimed(good, plain, 1, true), "badmap", false);
            Line("V", "ok");
        } catch (PalException e) {
            Line("V", e.Message);
        }
    }

    static int Main(string[] args)
    {
        try {
            if (args.Length == 2 && args[0] == "pal") Pal(args[1]);
            else if (args.Length == 2 && args[0] == "bad") Bad(args[1]);
            else if (args.Length == 2 && args[0] == "roster") RosterLines(args[1]);
            else if (args.Length == 2 && args[0] == "instances") RosterInstances(args[1]);
            else if (args.Length == 4 && args[0] == "herd") Herd(args[1], args[2], args[3]);
            else if (args.Length == 4 && args[0] == "conformance") Conformance(args[1], args[2], args[3]);
            else if (args.Length == 1 && args[0] == "bonepass") BonePassLines();
            else if (args.Length == 2 && args[0] == "timed") Timed(args[1]);
            else {
                Console.Error.WriteLine("usage: CrowdbakeCheck.exe pal|bad FILE.pal | roster|instances roster.json | herd FILE.pal roster.json TYPE | conformance DIR CASE OUT | bonepass");
                return 2;
            }
        } catch (Exception e) {
            Console.Error.WriteLine("CrowdbakeCheck: " + e.Message);
            return 1;
        }
        Console.Out.Write(output.ToString());
        return 0;
    }
}
