// HerdState.cs - what a herd of palette-skinned instances plays, without the engine: per instance
// the four numbers the shader reads (first row, frame count, rate, phase), the four it cross-fades
// from and the fade's start and length; states by name, speeds that keep feet planted, scale,
// footsteps. The logic of runtimes/web/crowdbake_three.mjs's CrowdbakeHerd, so a Unity herd and a three.js
// herd given the same calls play the same frames. CrowdbakeHerd (the MonoBehaviour) uploads
// Inst, From and Fade as per-instance shader data.
using System;
using System.Collections.Generic;

namespace Crowdbake
{
    public struct Footstep
    {
        public int instance, bone;
        public string foot;
        public bool lands;  // false: it lifts
        public double time; // the herd clock's moment of the crossing, seconds
    }

    public sealed class HerdState
    {
        public readonly int Count;
        public readonly float[] Inst, From, Fade; // 4, 4 and 2 floats an instance
        public readonly string[] StateOf;
        public readonly float[] Speed, Phase, Scale; // Phase NaN: the state's own rule
        public double Time { get; private set; }
        public float DefaultFade = 0.25f;
        public event Action<Footstep> OnFootstep;

        readonly PalFile pal;
        readonly List<RosterState> states;
        readonly Dictionary<string, RosterClip> clips = new Dictionary<string, RosterClip>(StringComparer.Ordinal);
        readonly double[] rowPosition; // footsteps: where each instance's clock last was, in rows (NaN: nowhere yet)

        // pal: the palette; type: its roster type, or null to make one state of each clip.
        public HerdState(PalFile pal, RosterType type, int count)
        {
            this.pal = pal;
            Count = count;
            Inst = new float[count * 4];
            From = new float[count * 4];
            Fade = new float[count * 2];
            StateOf = new string[count];
            Speed = new float[count];
            Phase = new float[count];
            Scale = new float[count];
            rowPosition = new double[count];
            states = type != null ? type.states : StatesOf(pal);
            if (type != null)
                foreach (RosterClip c in type.clips) clips[c.name] = c;
            string first = type != null ? type.defaultState : states.Count > 0 ? states[0].name : null;
            for (int i = 0; i < count; ++i) {
                Phase[i] = float.NaN;
                Scale[i] = 1;
                rowPosition[i] = double.NaN;
                if (first != null) SetState(i, first, float.NaN, float.NaN, 0);
            }
        }

        public IList<RosterState> States { get { return states; } }

        // The rate a timed instance plays at standstill (crowdbake_pal.mjs TIMED_STILL_RATE): its rate must stay
        // negative to mark it timed (-0 reads as an untimed clip's, its cells taken for rows); a cell in 3e22 years.
        public const double TimedStillRate = 1e-30;

        // A state per clip, for a palette without a roster: loops spread by the golden ratio,
        // one-shots start on their first row. Its numbers are the clip's (PalFile.InstanceOf): a timed
        // clip's count is its cells and its rate -cell_rate, negative.
        public static List<RosterState> StatesOf(PalFile pal)
        {
            var list = new List<RosterState>();
            foreach (PalClip c in pal.Clips) {
                float[] inst = PalFile.InstanceOf(c);
                list.Add(new RosterState {
                    name = c.Name, clip = c.Name, firstRow = (int)inst[0], frameCount = (int)inst[1], rate = inst[2], ratePerSpeed = 0,
                    goldenRatioPhase = c.Loops
                });
            }
            return list;
        }

        RosterState Find(string name)
        {
            foreach (RosterState s in states)
                if (s.name == name) return s;
            return null;
        }

        // The four per-instance numbers of docs/roster.md for `state` at ground speed `speed` (model
        // units/s), instance index `index`; a one-shot started at `startTime`. A timed state (rate < 0, .pal
        // version 7) keeps the sign: its rate is -cells a second.
        // A state follows the speed when its rate_per_speed != 0 (a timed one's is negative, cells per unit of
        // speed); standing still, a timed instance's rate is -TimedStillRate, never -0, as z < 0 marks it timed.
        public static void InstanceData(RosterState state, double speed, int index, double startTime, float[] out4, int at)
        {
            double rate = state.ratePerSpeed != 0 ? Math.Abs(state.ratePerSpeed) * speed : Math.Abs(state.rate);
            double frames = Math.Abs(state.frameCount), golden = index * 0.6180339887;
            double phase = state.goldenRatioPhase ? golden - Math.Floor(golden) : -startTime * rate / frames;
            out4[at] = state.firstRow;
            out4[at + 1] = state.frameCount;
            out4[at + 2] = (float)(state.rate < 0 ? -Math.Max(rate, TimedStillRate) : rate);
            out4[at + 3] = (float)phase;
        }

        // Puts instance i in `state`, cross-fading over `fade` seconds (NaN: DefaultFade) from what it
        // played; `speed` (NaN: as it was, world units/s) drives locomotion states so feet stay
        // planted; `phase` 0..1 overrides the golden-ratio spread (NaN: the state's own rule).
        public void SetState(int i, string state, float speed, float phase, float fade)
        {
            RosterState s = state != null ? Find(state) : null;
            if (s == null) {
                var names = new List<string>();
                foreach (RosterState x in states) names.Add(x.name);
                throw new ArgumentException("CrowdbakeHerd: no state '" + state + "' (have " + string.Join(", ", names.ToArray()) + ")");
            }
            if (float.IsNaN(speed)) speed = Speed[i];
            if (float.IsNaN(fade)) fade = DefaultFade;
            var current = new float[4];
            Array.Copy(Inst, i * 4, current, 0, 4);
            InstanceData(s, speed / Scale[i], i, Time, Inst, i * 4); // world speed / scale: the model's own speed
            if (!float.IsNaN(phase)) Inst[i * 4 + 3] = phase;
            StateOf[i] = state;
            Speed[i] = speed;
            Phase[i] = phase;
            if (fade > 0 && current[1] != 0) Array.Copy(current, 0, From, i * 4, 4);
            else Array.Copy(Inst, i * 4, From, i * 4, 4);
            Fade[i * 2] = (float)Time;
            Fade[i * 2 + 1] = fade;
            rowPosition[i] = RowPosition(i, Time);
        }

        public void SetState(int i, string state, float fade) { SetState(i, state, float.NaN, float.NaN, fade); }

        // A new speed, keeping the frame it is on (no pop): the phase absorbs the change of rate.
        public void SetSpeed(int i, float speed)
        {
            double frames = Math.Abs((double)Inst[i * 4 + 1]), fpos = Time * Math.Abs(Inst[i * 4 + 2]) + Inst[i * 4 + 3] * frames;
            var next = new float[4];
            InstanceData(Find(StateOf[i]), speed / Scale[i], i, Time, next, 0);
            double p = (fpos - Time * Math.Abs(next[2])) / frames;
            SetState(i, StateOf[i], speed, (float)(p - Math.Floor(p)), 0);
        }

        // The instance's scale (its place): a locomotion state then plays at speed / (scale x speed
        // reference), feet planted, on the frame it was on.
        public void SetScale(int i, float scale)
        {
            float was = Scale[i];
            Scale[i] = scale;
            if (was != scale && Find(StateOf[i]).ratePerSpeed != 0) SetSpeed(i, Speed[i]);
        }

        public void SetPhase(int i, float phase) { SetState(i, StateOf[i], float.NaN, phase, 0); }

        // The weight of the current state in instance i's cross-fade at `time` (1: no fade).
        public float FadeWeight(int i, double time)
        {
            float length = Fade[i * 2 + 1];
            return length > 0 ? (float)Math.Min(Math.Max((time - Fade[i * 2]) / length, 0), 1) : 1;
        }

        // The skinning matrix (column-major, bind space to the instance's posed model) of `bone` for
        // instance i at the herd's time: its clip, time and cross-fade, as the shader blends.
        public bool BoneMatrixAt(int i, int bone, float[] m)
        {
            var inst = new float[4];
            var from = new float[4];
            Array.Copy(Inst, i * 4, inst, 0, 4);
            Array.Copy(From, i * 4, from, 0, 4);
            return pal.InstanceBoneMatrix(inst, from, FadeWeight(i, Time), Time, (uint)bone, m);
        }

        // Instance i's per-row travel offset at the herd's time, model units in the model's frame: where
        // its body is drawn relative to the point the game moves at the state's speed, so the planted
        // feet of a clip with offsets (.pal version 5, a gallop) stay still; a cross-fade mixes the two
        // clips' offsets as the shader mixes their poses (crowdbake_three.mjs travelOffsetAt). Zero at
        // standstill, in a state that does not follow the speed, and for palettes without offsets.
        public void TravelOffsetAt(int i, float[] o)
        {
            Array.Clear(o, 0, 3);
            RosterState s = Find(StateOf[i]);
            if (pal.Header.TravelTableOffset == 0 || s == null || s.ratePerSpeed == 0 || !(Speed[i] > 0)) return;
            var inst = new float[4];
            Array.Copy(Inst, i * 4, inst, 0, 4);
            pal.InstanceTravelOffset(inst, Time, o);
            float fade = FadeWeight(i, Time);
            if (fade >= 1) return;
            var from = new float[3];
            Array.Copy(From, i * 4, inst, 0, 4);
            pal.InstanceTravelOffset(inst, Time, from);
            for (int k = 0; k < 3; ++k) o[k] = from[k] + (o[k] - from[k]) * fade;
        }

        // Instance i's unwrapped row position at `time` (crowdbake_contacts.mjs rowPosition).
        // A timed instance's (z < 0) counts cells.
        double RowPosition(int i, double time) { return time * Math.Abs(Inst[i * 4 + 2]) + Inst[i * 4 + 3] * Math.Abs((double)Inst[i * 4 + 1]); }

        // The herd's clock, seconds: raises the footsteps every instance crossed since the last call.
        public void Update(double time)
        {
            if (OnFootstep != null)
                for (int i = 0; i < Count; ++i) RaiseFootsteps(i, time);
            else
                for (int i = 0; i < Count; ++i) rowPosition[i] = RowPosition(i, time);
            Time = time;
        }

        void RaiseFootsteps(int i, double time)
        {
            double to = RowPosition(i, time), from = rowPosition[i];
            rowPosition[i] = to;
            RosterState s = Find(StateOf[i]);
            RosterClip clip;
            float rate = Math.Abs(Inst[i * 4 + 2]);
            if (s == null || !clips.TryGetValue(s.clip, out clip) || double.IsNaN(from) || !(rate > 0)) return;
            foreach (Crossing c in Contacts.Crossed(clip, (int)Inst[i * 4 + 1], from, to, Inst[i * 4 + 2] < 0)) {
                var e = new Footstep { instance = i, foot = c.contact.foot, bone = c.contact.bone, lands = c.lands,
                                       time = time - (to - c.at) / rate };
                OnFootstep(e);
            }
        }
    }

    public struct Crossing
    {
        public RosterContact contact;
        public bool lands;
        public double at; // the row position crossed
        internal int order;
    }

    // Footsteps: which of a clip's contacts a row position crosses (crowdbake_contacts.mjs).
    public static class Contacts
    {
        // The contacts crossed moving from `from` (exclusive) to `to` (inclusive), in the order
        // crossed. A loop (frameCount > 0) crosses each contact once a cycle however far it moves; a
        // one-shot clamps to its rows and crosses each at most once. Nothing is crossed backwards. timed: frameCount
        // counts the clip's cells (a timed clip's instance, z < 0), over its duration.
        public static List<Crossing> Crossed(RosterClip clip, int frameCount, double from, double to, bool timed = false)
        {
            var list = new List<Crossing>();
            if (!(to > from) || clip == null || clip.contacts.Count == 0) return list;
            double frames = Math.Abs((double)frameCount), end = timed ? frames : frames - 1;
            double perSecond = timed ? frames / clip.duration : clip.fps;
            if (frameCount < 0) {
                from = Math.Min(Math.Max(from, 0), end);
                to = Math.Min(Math.Max(to, 0), end);
            }
            for (int order = 0; order < clip.contacts.Count; ++order) {
                RosterContact contact = clip.contacts[order];
                for (int kind = 0; kind < 2; ++kind) {
                    double row = (double)(kind == 0 ? contact.time : contact.lift) * perSecond;
                    if (frameCount < 0) {
                        if (from < row && row <= to) list.Add(new Crossing { contact = contact, lands = kind == 0, at = row, order = order });
                        continue;
                    }
                    for (double k = Math.Floor((from - row) / frames) + 1; row + k * frames <= to; ++k)
                        list.Add(new Crossing { contact = contact, lands = kind == 0, at = row + k * frames, order = order });
                }
            }
            list.Sort((a, b) => a.at != b.at ? a.at.CompareTo(b.at) : a.order != b.order ? a.order.CompareTo(b.order)
                                                                     : a.lands == b.lands ? 0 : a.lands ? -1 : 1);
            return list;
        }
    }
}
