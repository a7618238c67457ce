// crowdbake_pose.mjs - a bone's skinning matrix at a time, decoded and blended as
// runtimes/glsl/crowdbake_palette.glsl does it (sockets, the LOD's measure, tests), the local rows of
// .pal version 6 composed down the skeleton, and the timed rows of version 7 found through their clip's map
// (docs/pal-format.md). crowdbake_pal.mjs re-exports these.
// No third-party dependencies; it imports crowdbake_pal.mjs's constants (which re-exports it). Public domain / MIT-0.

import { FLAG_POSITIONS_RELATIVE, FLAG_LOCAL_ROWS, FLAG_TIMED_ROWS } from './crowdbake_pal.mjs';

// Index into `texels` of a bone's first component in a baked row (rows wrap into column blocks).
export function texelIndex(header, row, bone) {
    const x = Math.floor(row / header.height) * header.row_texels + bone * header.texels_per_bone;
    const y = row % header.height;
    return (y * header.width + x) * 4;
}

// Whether a palette's rows hold each bone in its parent's frame (version 6, flag bit 5): its bones compose.
export const hasLocalRows = (header) => header.version >= 6 && (header.flags & FLAG_LOCAL_ROWS) !== 0;
// Whether a palette has timed clips (version 7, flag bit 6): their rows lie on cells and a map before them says which
// two to blend.
export const hasTimedRows = (header) => header.version >= 7 && (header.flags & FLAG_TIMED_ROWS) !== 0;

const halfToFloat = (h) => { // exponent rebiased; zero and subnormals are m 2^-24
    const e = (h >> 10) & 0x1f, m = h & 0x3ff, sign = h & 0x8000 ? -1 : 1;
    if (e === 0) return sign * m * 2 ** -24;
    return e === 31 ? (m ? NaN : sign * Infinity) : sign * (1 + m / 1024) * 2 ** (e - 15);
};
const snorm = (u) => Math.max((u >= 32768 ? u - 65536 : u) / 32767, -1);

// Texel k of a bone in a row, as the GLSL's cb_texel decodes it.
function decodeTexel(pal, row, bone, k) {
    const h = pal.header, i = texelIndex(h, row, bone) + 4 * k, t = pal.texels;
    if (h.precision === 0) return [t[i], t[i + 1], t[i + 2], t[i + 3]];
    if (h.precision === 1) return [0, 1, 2, 3].map((c) => halfToFloat(t[i + c]));
    // Local rows: a qpos position and scale in the bone's own ranges (the bone range table), not the header's box.
    const r = pal.bones[bone].range;
    const lo = r ? r.pos_min : h.bounds_min, hi = r ? r.pos_max : h.bounds_max, range = r ? r.scale_max : h.linear_range;
    const u = [t[i], t[i + 1], t[i + 2], t[i + 3]];
    const box = (h.layout === 2 && k === 1) || (h.layout === 0 && k === 3);
    const out = [0, 1, 2].map((c) => (box ? lo[c] + (hi[c] - lo[c]) * (u[c] / 65535) : snorm(u[c]) * (h.layout === 2 ? 1 : range)));
    if (h.layout === 2) out.push(k === 0 ? snorm(u[3]) : (range * u[3]) / 65535);
    else if (h.layout === 1) out.push(lo[k] + (hi[k] - lo[k]) * (u[3] / 65535));
    else out.push(k === 3 ? 1 : 0);
    return out;
}

// A clip's first row as the per-instance numbers hold it: negative for held rows (CLIP_STEP), -first_row - 1.
export const instanceFirstRow = (clip) => (clip.step ? -clip.first_row - 1 : clip.first_row);

// The four per-instance numbers of a clip (a pal.clips entry) played at `rate` from `phase` (cb_instance_of): first
// row (instanceFirstRow), its rows (negative for a one-shot) and rows per second; a timed clip's cells (negative for a
// one-shot) and -(cells per second x rate), the negative rate marking it.
export function clipInstance(clip, rate = 1, phase = 0) {
    const steps = clip.timed ? clip.cells : clip.frames;
    return [instanceFirstRow(clip), clip.loops ? steps : -steps, clip.timed ? -clip.cell_rate * rate : clip.fps * rate, phase];
}

// Cell `cell`'s texel of the map of the timed clip whose rows start at `first` (cells: its cells): [r0, r1, f0, f1],
// the rows blended in the cell relative to first and the second's weight at the cell's start and end. The map's
// ceil(cells / row_texels) rows lie just before the first, one texel a cell; u16 holds rows as integers and weights
// as f x 65535, never through a bone's range (docs/pal-format.md "Timed rows").
export function timedMapTexel(pal, first, cells, cell) {
    const h = pal.header, line = Math.floor(cell / h.row_texels), t = pal.texels;
    const i = texelIndex(h, first - Math.ceil(cells / h.row_texels) + line, 0) + 4 * (cell - line * h.row_texels);
    if (h.precision === 0) return [t[i], t[i + 1], t[i + 2], t[i + 3]];
    if (h.precision === 1) return [0, 1, 2, 3].map((c) => halfToFloat(t[i + c]));
    return [t[i], t[i + 1], t[i + 2] / 65535, t[i + 3] / 65535];
}

// The two rows to blend for the four per-instance numbers at `time`, and the weight of the second (the GLSL's cb_frame,
// the C runtime's cb_runtime_frame_in); held rows (a negative first row) give their row alone. A timed instance (a
// negative rate) needs the palette `pal`, whose map says which rows its cell blends.
export function instanceFrame(inst, time, pal) {
    const held = inst[0] < 0, first = held ? -inst[0] - 1 : inst[0];
    const frames = Math.abs(inst[1]); // rows; a timed clip's cells
    let fpos = time * Math.abs(inst[2]) + inst[3] * frames, f1;
    if (inst[2] < 0) { // timed: the cell's map texel
        if (!pal) throw new Error('a timed instance (a negative rate) needs its palette: instanceFrame(inst, time, pal)');
        if (inst[1] > 0) fpos -= frames * Math.floor(fpos / frames);
        else fpos = Math.min(Math.max(fpos, 0), frames);
        if (!(fpos >= 0 && fpos <= frames)) fpos = 0;
        const cell = Math.min(Math.floor(fpos), frames - 1); // a one-shot's end, or a loop's rounding onto n: its end
        const [r0, r1, w0, w1] = timedMapTexel(pal, first, frames, cell);
        if (held) return { row0: first + r0, row1: first + r0, fr: 0 };
        return { row0: first + r0, row1: first + r1, fr: w0 + (w1 - w0) * (fpos - cell) };
    }
    if (inst[1] > 0) fpos -= frames * Math.floor(fpos / frames);
    else fpos = Math.min(Math.max(fpos, 0), frames - 1);
    if (!(fpos >= 0 && fpos < frames)) fpos = 0; // rounding at the wrap
    const f0 = Math.floor(fpos);
    if (inst[1] > 0) f1 = f0 + 1 < frames ? f0 + 1 : 0; // a loop's last row blends into its first
    else f1 = Math.min(f0 + 1, frames - 1);
    if (held) return { row0: first + f0, row1: first + f0, fr: 0 }; // no blend across a step
    return { row0: first + f0, row1: first + f1, fr: fpos - f0 };
}

// The two rows of an instance's four numbers (instanceData's) at `time`, checked against the palette.
function checkedFrame(pal, inst, time, bone) {
    const h = pal.header;
    if (!Number.isInteger(bone) || bone < 0 || bone >= h.bone_count)
        throw new Error(`bone ${bone} is not one of the palette's ${h.bone_count} bones`);
    if (!inst.every(Number.isFinite) || !Number.isFinite(time) || !Number.isFinite(time * inst[2] + inst[3]))
        throw new Error(`time ${time} or instance numbers ${inst} are not finite numbers`);
    const first = inst[0] < 0 ? -inst[0] - 1 : inst[0], cells = Math.abs(inst[1]);
    if (inst[2] < 0 && !(Number.isInteger(first) && Number.isInteger(cells) && cells >= 1 &&
                         first >= Math.ceil(cells / h.row_texels) && first < h.rows))
        throw new Error(`instance numbers ${inst}: a timed clip's map rows (before row ${first}, ${cells} cells) lie outside ` +
                        `the palette's ${h.rows} rows`);
    const frame = instanceFrame(inst, time, pal);
    if (frame.row1 >= h.rows || frame.row0 >= h.rows)
        throw new Error(`rows ${frame.row0}, ${frame.row1} lie past the palette's ${h.rows} rows`);
    return frame;
}

// A bone's texels blended between two rows, texel by texel (a qpos rotation the shorter way: cb:hemisphere).
function blendedTexels(pal, { row0, row1, fr }, bone) {
    const t = [];
    for (let k = 0; k < pal.header.texels_per_bone; ++k) {
        const a = decodeTexel(pal, row0, bone, k), b = decodeTexel(pal, row1, bone, k);
        const flip = pal.header.layout === 2 && k === 0 && a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0 ? -1 : 1;
        t.push(a.map((x, c) => x + (flip * b[c] - x) * fr));
    }
    return t;
}

// ---- qpos poses { q: [x, y, z, w] unit, p: [3], s }: v' = p + s rotate(q, v - b) ----

const normalized = (q) => {
    const n = Math.hypot(q[0], q[1], q[2], q[3]);
    return [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
};
const qposOf = (t) => ({ q: normalized(t[0]), p: t[1].slice(0, 3), s: t[1][3] });

// a + (b - a) w for two poses, the rotation the shorter way and renormalised: the blend of two rows, and of two clips'
// blended poses in a cross-fade.
function mixPose(a, b, w) {
    const flip = a.q[0] * b.q[0] + a.q[1] * b.q[1] + a.q[2] * b.q[2] + a.q[3] * b.q[3] < 0 ? -1 : 1;
    return { q: normalized(a.q.map((x, c) => x + (flip * b.q[c] - x) * w)), p: a.p.map((x, c) => x + (b.p[c] - x) * w),
             s: a.s + (b.s - a.s) * w };
}

const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

// rotate(q, v) = v + 2 w (u x v) + 2 u x (u x v), u = q.xyz.
function rotate(q, v) {
    const u = [q[0], q[1], q[2]], c = cross(u, v), cc = cross(u, c);
    return [0, 1, 2].map((k) => v[k] + 2 * (q[3] * c[k] + cc[k]));
}

// a · b (Hamilton product, xyzw).
const quatMul = (a, b) => [
    a[3] * b[0] + b[3] * a[0] + a[1] * b[2] - a[2] * b[1],
    a[3] * b[1] + b[3] * a[1] + a[2] * b[0] - a[0] * b[2],
    a[3] * b[2] + b[3] * a[2] + a[0] * b[1] - a[1] * b[0],
    a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]];

// A child's local pose composed under its parent's composed pose (b_p: the parent's bind position):
// q = q_p q_L, s = s_p s_L, p = p_p + s_p rotate(q_p, p_L - b_p); q renormalised (it drifts down a chain).
function composePose(parent, local, parentBind) {
    const offset = rotate(parent.q, local.p.map((x, k) => x - parentBind[k]));
    return { q: normalized(quatMul(parent.q, local.q)), p: parent.p.map((x, k) => x + parent.s * offset[k]),
             s: parent.s * local.s };
}

// A bone's pose composed from its chain's root down: localAt(j) gives bone j's blended local pose. The reader
// refuses a parent table with a loop, so the walk ends; a parent may come after its child in the table.
function composedPose(pal, bone, localAt) {
    const chain = [];
    for (let j = bone; j >= 0; j = pal.bones[j].parent) chain.push(j);
    let pose = localAt(chain[chain.length - 1]);
    for (let i = chain.length - 2; i >= 0; --i)
        pose = composePose(pose, localAt(chain[i]), pal.bones[chain[i + 1]].bind_position);
    return pose;
}

// The column-major matrix of a qpos pose of `bone`: s R(q) (v - b) + p, with p + the bone's position offset.
function qposMatrix(pal, bone, { q: [x, y, z, w], p, s }, out) {
    const r = [1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),
               2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
               2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]; // columns
    out.fill(0);
    out[15] = 1;
    for (let k = 0; k < 9; ++k) out[Math.floor(k / 3) * 4 + (k % 3)] = s * r[k];
    return placed(pal, bone, p, true, out);
}

// The translation of A (v - b) + p (or A v + p), with p stored less the bone's position offset.
function placed(pal, bone, p, aboutBind, out) {
    const { bind_position: bp, position_offset: off } = pal.bones[bone];
    for (let k = 0; k < 3; ++k)
        out[12 + k] = p[k] + off[k] - (aboutBind ? out[k] * bp[0] + out[4 + k] * bp[1] + out[8 + k] * bp[2] : 0);
    return out;
}

// The column-major matrix of a bone's blended texels (every layout, global rows).
function texelMatrix(pal, bone, t, out) {
    const h = pal.header;
    if (h.layout === 2) return qposMatrix(pal, bone, qposOf(t), out);
    out.fill(0);
    out[15] = 1;
    const affine = h.layout === 1; // affine: texel k is row k; mat4: texel k is column k
    for (let c = 0; c < 3; ++c) for (let r = 0; r < 3; ++r) out[c * 4 + r] = affine ? t[r][c] : t[c][r];
    const p = affine ? [t[0][3], t[1][3], t[2][3]] : t[3].slice(0, 3);
    return placed(pal, bone, p, (h.flags & FLAG_POSITIONS_RELATIVE) !== 0, out);
}

// The bone's skinning matrix (column-major, 16 numbers: the glTF joint matrix, bind space to the
// posed model) for an instance's four numbers (instanceData's) at `time` seconds. A prop on the
// bone is placed at boneMatrix x the prop's bind-space transform (a roster socket's bind_transform).
// Local rows (version 6): every bone of the chain blended in its parent's frame, then composed from the root.
export function instanceBoneMatrix(pal, inst, time, bone, out = new Array(16)) {
    return frameBoneMatrix(pal, checkedFrame(pal, inst, time, bone), bone, out);
}

// The bone's skinning matrix at two rows blended ({ row0, row1, fr }, instanceFrame's).
function frameBoneMatrix(pal, frame, bone, out) {
    if (!hasLocalRows(pal.header)) return texelMatrix(pal, bone, blendedTexels(pal, frame, bone), out);
    return qposMatrix(pal, bone, composedPose(pal, bone, (j) => qposOf(blendedTexels(pal, frame, j))), out);
}

// The bone's skinning matrix at one baked row (`row` of the texture), no blend: a pose the bake stored, whatever
// the clip's rows' times (the LOD's measure spreads its poses over the rows).
export function rowBoneMatrix(pal, row, bone, out = new Array(16)) {
    if (!Number.isInteger(row) || row < 0 || row >= pal.header.rows || !Number.isInteger(bone) || bone < 0 ||
        bone >= pal.header.bone_count)
        throw new Error(`row ${row} or bone ${bone} is not one of the palette's ${pal.header.rows} rows and ` +
                        `${pal.header.bone_count} bones`);
    return frameBoneMatrix(pal, { row0: row, row1: row, fr: 0 }, bone, out);
}

// The same for an instance cross-fading from `fromInst` to `inst` (fade 0 -> 1), as the shaders blend it:
// global rows mix the two bone matrices; local rows blend each bone's two blended local poses, then compose.
export function instanceBoneMatrixCrossfade(pal, fromInst, inst, fade, time, bone, out = new Array(16)) {
    const to = checkedFrame(pal, inst, time, bone), from = checkedFrame(pal, fromInst, time, bone);
    if (hasLocalRows(pal.header)) {
        const localAt = (j) => mixPose(qposOf(blendedTexels(pal, from, j)), qposOf(blendedTexels(pal, to, j)), fade);
        return qposMatrix(pal, bone, composedPose(pal, bone, localAt), out);
    }
    const a = texelMatrix(pal, bone, blendedTexels(pal, from, bone), new Array(16));
    texelMatrix(pal, bone, blendedTexels(pal, to, bone), out);
    for (let k = 0; k < 16; ++k) out[k] = a[k] + (out[k] - a[k]) * fade;
    return out;
}

// The bone's skinning matrix `time` seconds into clip `clip` (an index into pal.clips): loops
// wrap, one-shots clamp; the same numbers as cbpal_bone_matrix in include/crowdbake_pal.h.
export function boneMatrix(pal, clip, time, bone, out) {
    const c = pal.clips[clip];
    if (!Number.isInteger(clip) || !c) throw new Error(`clip ${clip} is not one of the palette's ${pal.clips.length} clips`);
    return instanceBoneMatrix(pal, clipInstance(c), time, bone, out);
}
