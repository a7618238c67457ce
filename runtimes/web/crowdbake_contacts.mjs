// crowdbake_contacts.mjs - footsteps for a crowd: which of a clip's contacts (the roster manifest's
// `contacts`: when each foot lands and lifts, seconds into the clip) an instance passes as its clock
// moves on. An ES module with no dependencies; CrowdbakeHerd (crowdbake_three.mjs) raises its
// onContact callbacks from it, and any runtime holding the four per-instance numbers can do the same.
//
// Positions are in rows, unwrapped: time * rate + phase * frames, as the shader computes before it
// wraps a loop. A contact at t seconds sits at row t * fps and again every `frames` rows in a loop. A timed clip's
// instance (a negative rate, .pal version 7) counts cells instead: time * |rate| + phase * cells, a contact at cell
// t * cells / duration.

// An instance's unwrapped row (or cell) position at `time` (the four numbers of instanceData).
export const rowPosition = (inst, time) => time * Math.abs(inst[2]) + inst[3] * Math.abs(inst[1]);

// The contacts crossed as a row position moves from `from` (exclusive) to `to` (inclusive), in the
// order they are crossed: [{ contact, kind: 'land' | 'lift', at }], `at` the row position crossed.
// A loop (frameCount > 0) crosses each contact once a cycle however far it moves; a one-shot clamps
// to its rows and crosses each at most once. Nothing is crossed moving backwards. timed: frameCount counts the
// clip's cells (a timed clip's instance), over its duration.
export function contactsCrossed(clip, frameCount, from, to, timed = false) {
    const out = [];
    if (!(to > from) || !clip?.contacts?.length) return out;
    const frames = Math.abs(frameCount), end = timed ? frames : frames - 1, perSecond = timed ? frames / clip.duration : clip.fps;
    if (frameCount < 0) { // one-shot: clamped to its rows
        from = Math.min(Math.max(from, 0), end), to = Math.min(Math.max(to, 0), end);
    }
    clip.contacts.forEach((contact, order) => {
        for (const kind of ['land', 'lift']) {
            const row = (kind === 'land' ? contact.time : contact.lift) * perSecond;
            if (frameCount < 0) {
                if (from < row && row <= to) out.push({ contact, kind, at: row, order });
                continue;
            }
            for (let k = Math.floor((from - row) / frames) + 1; row + k * frames <= to; ++k)
                out.push({ contact, kind, at: row + k * frames, order });
        }
    });
    return out.sort((a, b) => a.at - b.at || a.order - b.order || (a.kind === 'land' ? -1 : 1));
}

// Per instance, the row position its footsteps were last raised at; advance() raises what each
// instance crossed since. `clips`: the roster type's clips (readRoster(...).types.NAME.clips).
export class FootstepClock {
    constructor(clips, count) {
        this.clips = new Map((clips ?? []).map((c) => [c.name, c]));
        this.position = new Float64Array(count).fill(NaN);
        this.listeners = [];
    }

    // The instance starts (or restarts, in a new state or at a new rate) at `inst` at `time`: what it
    // has passed is behind it.
    restart(i, inst, time) {
        this.position[i] = rowPosition(inst, time);
    }

    // Calls listener({ instance, foot, bone, kind, time }) for every contact each instance crossed
    // between its last position and `time` (time: the herd clock's moment of the crossing, in
    // seconds), instance by instance, each in the order crossed. clipOf(i) -> [clip, inst].
    advance(count, time, clipOf) {
        if (!this.listeners.length) return;
        for (let i = 0; i < count; ++i) {
            const [name, inst] = clipOf(i);
            const to = rowPosition(inst, time), from = this.position[i];
            this.position[i] = to;
            const clip = this.clips.get(name);
            const rate = Math.abs(inst[2]);
            if (!clip || Number.isNaN(from) || !(rate > 0)) continue;
            for (const e of contactsCrossed(clip, inst[1], from, to, inst[2] < 0)) {
                const event = { instance: i, foot: e.contact.foot, bone: e.contact.bone, kind: e.kind,
                                time: time - (to - e.at) / rate };
                for (const listener of this.listeners) listener(event);
            }
        }
    }
}
