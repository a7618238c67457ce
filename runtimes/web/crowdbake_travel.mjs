// crowdbake_travel.mjs - the per-row travel offset of a .pal (version 5; docs/pal-format.md):
// where an instance is drawn while the game moves it at its clip's ground speed. An ES module with
// no dependencies beyond crowdbake_pal.mjs. Public domain / MIT-0.
//
//     const o = instanceTravelOffset(pal, clip, inst, seconds);  // model frame, model units
//     position = instancePosition + rotateY(yaw, o) * scale;     // where the instance is drawn
//
// The bake ships offsets for the striding loops whose planted feet they keep still (a gallop); a
// runtime that adds them where it sets the instance's position keeps those feet planted. Clips and
// files without them give [0, 0, 0], so a runtime may always add it.

import { clipInstance, instanceFrame } from './crowdbake_pal.mjs';

// The body's travel offset for an instance's four numbers at `time`: the rows' offsets blended as
// the shaders blend the rows (a timed clip's the two its map names, with its weight), times the heading of `clip`
// (a pal.clips entry), in the model's frame. Same numbers as cbpal_travel_offset in include/crowdbake_pal.h.
export function instanceTravelOffset(pal, clip, inst, time, out = [0, 0, 0]) {
    out.fill(0);
    const d = clip.travel_heading;
    if (!pal.rowTravel || !d || (d[0] === 0 && d[1] === 0 && d[2] === 0)) return out;
    const { row0, row1, fr } = instanceFrame(inst, time, pal);
    if (row0 >= pal.rowTravel.length || row1 >= pal.rowTravel.length) return out;
    const a = pal.rowTravel[row0], o = a + (pal.rowTravel[row1] - a) * fr;
    for (let k = 0; k < 3; ++k) out[k] = o * d[k];
    return out;
}

// The same `time` seconds into clip `clip` (an index into pal.clips), as boneMatrix plays it.
export function travelOffset(pal, clip, time, out) {
    const c = pal.clips[clip];
    if (!Number.isInteger(clip) || !c) throw new Error(`clip ${clip} is not one of the palette's ${pal.clips.length} clips`);
    if (!Number.isFinite(time)) throw new Error(`time ${time} is not a finite number`);
    return instanceTravelOffset(pal, c, clipInstance(c), time, out);
}
