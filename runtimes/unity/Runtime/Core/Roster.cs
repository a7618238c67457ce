// Roster.cs - the roster manifest (roster.json, docs/roster.md) as C# objects, with the checks of
// the JavaScript reader (runtimes/web/crowdbake_pal.mjs readRoster): every field a game relies on is there,
// of the right kind, and inside the palette (rows, bones); an error names the file and the field.
using System;
using System.Collections.Generic;

namespace Crowdbake
{
    [Serializable]
    public sealed class RosterContact
    {
        public string foot;
        public int bone;
        public float time, lift; // seconds into the clip: it lands, it lifts
    }

    // A timed clip's map (.pal version 7, docs/pal-format.md "Timed rows"): its cells, their rate, its map rows.
    [Serializable]
    public sealed class RosterTimedRows
    {
        public int cells, mapRows;
        public float cellRate;
    }

    [Serializable]
    public sealed class RosterClip
    {
        public string name;
        public int firstRow, frameCount;
        public float fps, duration, groundSpeed;
        public bool loops;
        public RosterTimedRows timedRows; // null: the clip plays its rows uniformly (no timed rows, .pal version < 7)
        public List<RosterContact> contacts = new List<RosterContact>();
    }

    [Serializable]
    public sealed class RosterState
    {
        public string name, clip;
        public int firstRow, frameCount; // frameCount < 0: a one-shot
        public float rate, ratePerSpeed; // < 0: a timed clip's cells per second, and per unit of speed, negated
        public bool goldenRatioPhase; // else "zero": a one-shot starts on its first row
    }

    [Serializable]
    public sealed class RosterSocket
    {
        public string name;
        public int bone;
        public float[] bindTransform = new float[16]; // column-major, bind space
    }

    [Serializable]
    public sealed class RosterLod
    {
        public string model;
        public int[] jointRemap;
    }

    [Serializable]
    public sealed class RosterType
    {
        public string name, model, palette, paletteExr, sharesPaletteOf, layout, precision, defaultState;
        public int bones, texelsPerBone, rows, width, height, blocks;
        public float speedReference;
        public List<RosterClip> clips = new List<RosterClip>();
        public List<RosterState> states = new List<RosterState>();
        public List<RosterLod> lods = new List<RosterLod>();
        public List<RosterSocket> sockets = new List<RosterSocket>();

        public RosterState State(string stateName)
        {
            foreach (RosterState s in states)
                if (s.name == stateName) return s;
            return null;
        }

        public RosterClip Clip(string clipName)
        {
            foreach (RosterClip c in clips)
                if (c.name == clipName) return c;
            return null;
        }
    }

    public sealed class Roster
    {
        public string generator, catalog;
        public List<RosterType> types = new List<RosterType>();
        public Dictionary<string, string> failed = new Dictionary<string, string>(); // type -> error

        static readonly string[] Layouts = { "mat4", "affine", "qpos" }, Precisions = { "float", "half", "u16" };

        public RosterType Type(string typeName)
        {
            foreach (RosterType t in types)
                if (t.name == typeName) return t;
            return null;
        }

        // ---- checked field access: `at` names the place, as readRoster's messages do ----
        sealed class Reader
        {
            public string file;
            public Exception Fail(string at, string what) { return new JsonException(file + ": " + at + ": " + what); }

            public object Need(JsonObject o, string at, string key)
            {
                if (o == null || !o.Has(key)) throw Fail(at, "missing \"" + key + "\"");
                return o.Get(key);
            }
            public JsonObject Obj(object v, string at)
            {
                var o = v as JsonObject;
                if (o == null) throw Fail(at, "expected an object");
                return o;
            }
            public string Str(JsonObject o, string at, string key)
            {
                var s = Need(o, at, key) as string;
                if (s == null) throw Fail(at + "." + key, "expected a string");
                return s;
            }
            public string OptStr(JsonObject o, string at, string key) { return o.Has(key) ? Str(o, at, key) : null; }
            public double Num(JsonObject o, string at, string key, double min, bool exclusive)
            {
                object v = Need(o, at, key);
                if (!(v is double) || (exclusive ? !((double)v > min) : !((double)v >= min)))
                    throw Fail(at + "." + key, "expected a number " + (exclusive ? "> " : ">= ") + min);
                return (double)v;
            }
            public double Number(JsonObject o, string at, string key)
            {
                object v = Need(o, at, key);
                if (!(v is double) || double.IsNaN((double)v) || double.IsInfinity((double)v)) throw Fail(at + "." + key, "expected a number");
                return (double)v;
            }
            public int Int(JsonObject o, string at, string key, long min, long below)
            {
                object v = Need(o, at, key);
                if (!(v is double) || (double)v != Math.Floor((double)v) || (double)v < min || (double)v >= below)
                    throw Fail(at + "." + key, "expected an integer from " + min + " below " + below);
                return (int)(double)v;
            }
            public bool Bool(JsonObject o, string at, string key)
            {
                object v = Need(o, at, key);
                if (!(v is bool)) throw Fail(at + "." + key, "expected true or false");
                return (bool)v;
            }
            public List<object> Arr(JsonObject o, string at, string key, bool optional)
            {
                if (optional && !o.Has(key)) return new List<object>();
                var a = Need(o, at, key) as List<object>;
                if (a == null) throw Fail(at + "." + key, "expected an array");
                return a;
            }
            public string OneOf(JsonObject o, string at, string key, string[] allowed)
            {
                string s = Str(o, at, key);
                if (Array.IndexOf(allowed, s) < 0) throw Fail(at + "." + key, "expected one of " + string.Join(", ", allowed));
                return s;
            }
        }

        // Parses and checks roster.json's text; `file` names it in errors.
        public static Roster Parse(string json, string file)
        {
            var r = new Reader { file = file };
            JsonObject doc;
            try {
                doc = r.Obj(MiniJson.Parse(json), "top level");
            } catch (JsonException e) {
                throw new JsonException(file + ": " + e.Message);
            }
            string schema = r.Str(doc, "top level", "schema");
            if (schema != "crowdbake-roster/1")
                throw r.Fail("schema", "\"" + schema + "\" is not crowdbake-roster/1; update the reader or re-bake with a matching crowdbake");
            var roster = new Roster { generator = r.Str(doc, "top level", "generator"), catalog = r.Str(doc, "top level", "catalog") };
            JsonObject types = r.Obj(r.Need(doc, "top level", "types"), "types");
            foreach (string name in types.Keys) roster.types.Add(ReadType(r, name, r.Obj(types.Get(name), "types." + name)));
            if (doc.Has("failed")) {
                JsonObject failed = r.Obj(doc.Get("failed"), "failed");
                foreach (string name in failed.Keys) {
                    JsonObject f = r.Obj(failed.Get(name), "failed." + name);
                    r.Str(f, "failed." + name, "model");
                    roster.failed[name] = r.Str(f, "failed." + name, "error");
                }
            }
            return roster;
        }

        static RosterType ReadType(Reader r, string name, JsonObject t)
        {
            string at = "types." + name;
            var type = new RosterType {
                name = name, model = r.Str(t, at, "model"), palette = r.OptStr(t, at, "palette"),
                paletteExr = r.OptStr(t, at, "palette_exr"), sharesPaletteOf = r.OptStr(t, at, "shares_palette_of"),
                layout = r.OneOf(t, at, "layout", Layouts), precision = r.OneOf(t, at, "precision", Precisions),
                bones = r.Int(t, at, "bones", 1, int.MaxValue), texelsPerBone = r.Int(t, at, "texels_per_bone", 2, 5),
                rows = r.Int(t, at, "rows", 1, int.MaxValue), width = r.Int(t, at, "width", 1, int.MaxValue),
                height = r.Int(t, at, "height", 1, int.MaxValue), blocks = r.Int(t, at, "blocks", 1, int.MaxValue),
                speedReference = (float)r.Num(t, at, "speed_reference", 0, false), defaultState = r.Str(t, at, "default_state")
            };
            if (type.palette == null && type.paletteExr == null) throw r.Fail(at, "has neither palette nor palette_exr");
            List<object> clips = r.Arr(t, at, "clips", false);
            for (int i = 0; i < clips.Count; ++i) type.clips.Add(ReadClip(r, type, at + ".clips[" + i + "]", r.Obj(clips[i], at + ".clips[" + i + "]")));
            JsonObject states = r.Obj(r.Need(t, at, "states"), at + ".states");
            foreach (string s in states.Keys) type.states.Add(ReadState(r, type, s, r.Obj(states.Get(s), at + ".states." + s)));
            List<object> lods = r.Arr(t, at, "lods", false);
            for (int i = 0; i < lods.Count; ++i) {
                string w = at + ".lods[" + i + "]";
                JsonObject l = r.Obj(lods[i], w);
                List<object> remap = r.Arr(l, w, "joint_remap", false);
                var lod = new RosterLod { model = r.Str(l, w, "model"), jointRemap = new int[remap.Count] };
                for (int j = 0; j < remap.Count; ++j) {
                    if (!(remap[j] is double) || (double)remap[j] != Math.Floor((double)remap[j]) || (double)remap[j] < 0 ||
                        (double)remap[j] >= type.bones)
                        throw r.Fail(w + ".joint_remap", "expected an array of bone indices below " + type.bones);
                    lod.jointRemap[j] = (int)(double)remap[j];
                }
                type.lods.Add(lod);
            }
            List<object> sockets = r.Arr(t, at, "sockets", true);
            for (int i = 0; i < sockets.Count; ++i) type.sockets.Add(ReadSocket(r, type, at + ".sockets[" + i + "]", r.Obj(sockets[i], at + ".sockets[" + i + "]")));
            if (type.State(type.defaultState) == null)
                throw r.Fail(at + ".default_state", "\"" + type.defaultState + "\" is not one of the type's states");
            return type;
        }

        static RosterClip ReadClip(Reader r, RosterType type, string w, JsonObject c)
        {
            var clip = new RosterClip {
                name = r.Str(c, w, "name"), firstRow = r.Int(c, w, "first_row", 0, int.MaxValue),
                frameCount = r.Int(c, w, "frame_count", 1, int.MaxValue), fps = (float)r.Num(c, w, "fps", 0, true),
                duration = (float)r.Num(c, w, "duration", 0, false), loops = r.Bool(c, w, "loops"),
                groundSpeed = (float)r.Num(c, w, "ground_speed", 0, false)
            };
            if (c.Has("timed_rows")) {
                string wt = w + ".timed_rows";
                JsonObject t = r.Obj(c.Get("timed_rows"), wt);
                clip.timedRows = new RosterTimedRows {
                    cells = r.Int(t, wt, "cells", 1, int.MaxValue), cellRate = (float)r.Num(t, wt, "cell_rate", 0, true),
                    mapRows = r.Int(t, wt, "map_rows", 1, int.MaxValue)
                };
            }
            List<object> contacts = r.Arr(c, w, "contacts", true);
            for (int j = 0; j < contacts.Count; ++j) {
                string wc = w + ".contacts[" + j + "]";
                JsonObject k = r.Obj(contacts[j], wc);
                clip.contacts.Add(new RosterContact {
                    foot = r.Str(k, wc, "foot"), bone = r.Int(k, wc, "bone", 0, type.bones),
                    time = (float)r.Num(k, wc, "time", 0, false), lift = (float)r.Num(k, wc, "lift", 0, false)
                });
            }
            if ((long)clip.firstRow + clip.frameCount > type.rows)
                throw r.Fail(w, "rows " + clip.firstRow + ".." + ((long)clip.firstRow + clip.frameCount) + " outside the type's " + type.rows + " rows");
            return clip;
        }

        static RosterState ReadState(Reader r, RosterType type, string name, JsonObject s)
        {
            string w = "types." + type.name + ".states." + name, wi = w + ".instance";
            string clip = r.Str(s, w, "clip");
            if (type.Clip(clip) == null) throw r.Fail(w + ".clip", "\"" + clip + "\" is not one of the type's clips");
            JsonObject inst = r.Obj(r.Need(s, w, "instance"), wi);
            var state = new RosterState {
                name = name, clip = clip, firstRow = r.Int(inst, wi, "first_row", int.MinValue + 1, int.MaxValue), // < 0: held rows
                frameCount = r.Int(inst, wi, "frame_count", int.MinValue + 1, int.MaxValue),
                // < 0: a timed clip (its cells per second, and per unit of speed, negated: docs/roster.md)
                rate = (float)r.Number(inst, wi, "rate"),
                ratePerSpeed = (float)r.Number(inst, wi, "rate_per_speed"),
                goldenRatioPhase = r.OneOf(inst, wi, "phase", new[] { "golden_ratio", "zero" }) == "golden_ratio"
            };
            if (state.frameCount == 0) throw r.Fail(wi + ".frame_count", "expected a non-zero integer");
            RosterClip c = type.Clip(clip);
            RosterTimedRows timed = c.timedRows;
            if ((state.rate < 0) != (timed != null) || state.ratePerSpeed * state.rate < 0)
                throw r.Fail(wi + ".rate", timed != null ? "clip \"" + clip + "\" has timed rows: rate and rate_per_speed must be negative"
                                                         : "expected a number >= 0, and rate_per_speed too");
            if (timed != null && Math.Abs((long)state.frameCount) != timed.cells)
                throw r.Fail(wi + ".frame_count", "clip \"" + clip + "\" has " + timed.cells + " cells, got " + state.frameCount);
            long first = state.firstRow < 0 ? -(long)state.firstRow - 1 : state.firstRow; // held rows: -first_row - 1
            long rows = timed != null ? c.frameCount : Math.Abs((long)state.frameCount); // a timed state counts cells, not rows
            if (first + rows > type.rows || (timed != null && timed.mapRows > first))
                throw r.Fail(wi, "rows " + first + ".." + (first + rows) + " outside the type's " + type.rows + " rows");
            return state;
        }

        static RosterSocket ReadSocket(Reader r, RosterType type, string w, JsonObject k)
        {
            var socket = new RosterSocket { name = r.Str(k, w, "name"), bone = r.Int(k, w, "bone", 0, type.bones) };
            List<object> m = r.Arr(k, w, "bind_transform", false);
            if (m.Count != 16) throw r.Fail(w + ".bind_transform", "expected 16 numbers");
            for (int i = 0; i < 16; ++i) {
                if (!(m[i] is double)) throw r.Fail(w + ".bind_transform", "expected 16 numbers");
                socket.bindTransform[i] = (float)(double)m[i];
            }
            return socket;
        }
    }
}
