// Local rows (.pal version 6) made by hand from a global qpos/float bake, by the spec's formulas in double precision
// (/work/plan/notes8/local_spec.md, docs/pal-format.md), so the reader and its composition can be checked before and
// apart from the C writer. Not a test file itself (node --test runs it and finds no tests).
import { xxh64 } from '../crowdbake_xxh64.mjs';

const HEADER = 256, ALIGN = 4096, RANGE = 32;

const qmul = (a, b) => [
    a[3] * b[0] + b[3] * a[0] + a[1] * b[2] - a[2] * b[1],
    a[3] * b[1] + b[3] * a[1] + a[2] * b[0] - a[0] * b[2],
    a[3] * b[2] + b[3] * a[2] + a[0] * b[1] - a[1] * b[0],
    a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]];
const conj = (q) => [-q[0], -q[1], -q[2], q[3]];
// rotate(q, v) as the sandwich q v conj(q) (a different form from the runtime's cross products).
const rotate = (q, v) => qmul(qmul(q, [...v, 0]), conj(q)).slice(0, 3);

// Bone j's global qpos in `row` of a qpos/float palette: { q (unit), p, s }.
function globalQpos(pal, row, j) {
    const h = pal.header;
    const x = Math.floor(row / h.height) * h.row_texels + j * 2, y = row % h.height, i = (y * h.width + x) * 4;
    const t = pal.texels, q = [t[i], t[i + 1], t[i + 2], t[i + 3]], n = Math.hypot(...q);
    return { q: q.map((c) => c / n), p: [t[i + 4], t[i + 5], t[i + 6]], s: t[i + 7] };
}

// Every row's local qpos of every bone: q_L = conj(q_p) q_j, s_L = s_j / s_p, p_L = b_p + rotate(conj(q_p), p_j - p_p) / s_p;
// a root keeps its global. Each bone's sign kept continuous from row to row.
export function localRows(pal) {
    const { rows, bone_count: n } = pal.header, out = [];
    for (let r = 0; r < rows; ++r) {
        const row = [];
        for (let j = 0; j < n; ++j) {
            const g = globalQpos(pal, r, j), parent = pal.bones[j].parent;
            let local = g;
            if (parent >= 0) {
                const gp = globalQpos(pal, r, parent), bp = pal.bones[parent].bind_position;
                const d = rotate(conj(gp.q), g.p.map((v, k) => v - gp.p[k]));
                local = { q: qmul(conj(gp.q), g.q), p: d.map((v, k) => bp[k] + v / gp.s), s: g.s / gp.s };
            }
            const before = r > 0 ? out[r - 1][j].q : null;
            if (before && local.q.reduce((a, c, k) => a + c * before[k], 0) < 0) local.q = local.q.map((c) => -c);
            row.push(local);
        }
        out.push(row);
    }
    return out;
}

// Each bone's range over every row: the box of its positions and its largest scale.
export function boneRanges(rows, n) {
    const ranges = [];
    for (let j = 0; j < n; ++j) {
        const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
        let scale = 0;
        for (const row of rows) {
            row[j].p.forEach((v, k) => { lo[k] = Math.min(lo[k], Math.fround(v)); hi[k] = Math.max(hi[k], Math.fround(v)); });
            scale = Math.max(scale, Math.fround(row[j].s));
        }
        ranges.push({ lo, hi, scale });
    }
    return ranges;
}

const unorm = (v, lo, hi) => (hi > lo ? Math.round(((v - lo) / (hi - lo)) * 65535) : 0);
const snorm = (v) => Math.round(Math.min(Math.max(v, -1), 1) * 32767) & 0xffff;

// The texels of the local rows (bones in `order`: new bone i is old bone order[i]), float or u16.
function localTexels(pal, rows, ranges, order, u16) {
    const h = pal.header, texels = u16 ? new Uint16Array(h.width * h.height * 4) : new Float32Array(h.width * h.height * 4);
    rows.forEach((row, r) => order.forEach((old, j) => {
        const x = Math.floor(r / h.height) * h.row_texels + j * 2, y = r % h.height, i = (y * h.width + x) * 4;
        const { q, p, s } = row[old], g = ranges[old];
        const values = u16 ? [...q.map(snorm), ...p.map((v, k) => unorm(v, g.lo[k], g.hi[k])), unorm(s, 0, g.scale)]
            : [...q, ...p, s];
        texels.set(values, i);
    }));
    return new Uint8Array(texels.buffer);
}

// A version 6 file of local rows from `source` (the bytes of a global qpos/float bake, `pal` read from them): its
// tables kept, the bone range table after them, the payload at the next 4096-byte boundary. options.u16: u16 texels;
// options.reversed: bones in reverse order, so every parent comes after its children.
export function makeLocalPal(source, pal, { u16 = false, reversed = false } = {}) {
    const h = pal.header, n = h.bone_count;
    const order = Array.from({ length: n }, (_, i) => (reversed ? n - 1 - i : i)), where = new Map(order.map((o, i) => [o, i]));
    const rows = localRows(pal), ranges = boneRanges(rows, n), payload = localTexels(pal, rows, ranges, order, u16);
    const rangeAt = h.payload_offset, payloadAt = Math.ceil((rangeAt + n * RANGE) / ALIGN) * ALIGN;
    const bytes = new Uint8Array(payloadAt + payload.length), view = new DataView(bytes.buffer);
    bytes.set(source.subarray(0, h.payload_offset));
    bytes.set(payload, payloadAt);
    order.forEach((old, j) => {
        const at = h.bone_table_offset + j * 32;
        bytes.set(source.subarray(h.bone_table_offset + old * 32, h.bone_table_offset + old * 32 + 32), at);
        const parent = pal.bones[old].parent;
        view.setInt32(at + 8, parent < 0 ? -1 : where.get(parent), true);
        const g = ranges[old], e = rangeAt + j * RANGE;
        [...g.lo, g.scale, ...g.hi].forEach((v, k) => view.setFloat32(e + 4 * k, v, true));
    });
    view.setUint32(8, 6, true);
    view.setUint32(12, view.getUint32(12, true) | 32, true);
    if (u16) view.setUint32(24, 2, true), view.setUint32(56, 8, true);
    view.setBigUint64(152, BigInt(payloadAt), true);
    view.setBigUint64(160, BigInt(payload.length), true);
    view.setBigUint64(168, BigInt(payload.length), true);
    view.setBigUint64(200, BigInt(rangeAt), true);
    for (let k = 0; k < 3; ++k) { // informative: the union of the bone boxes, the largest scale
        view.setFloat32(76 + 4 * k, Math.min(...ranges.map((g) => g.lo[k])), true);
        view.setFloat32(88 + 4 * k, Math.max(...ranges.map((g) => g.hi[k])), true);
    }
    view.setFloat32(72, Math.max(...ranges.map((g) => g.scale)), true);
    view.setBigUint64(176, 0n, true);
    view.setBigUint64(176, xxh64(bytes), true);
    return { bytes, order, rows };
}

// The column-major 4x4 of a qpos pose about bind position b: v -> p + s R(q) (v - b).
export function poseMatrix({ q, p, s }, b) {
    const cols = [[1, 0, 0], [0, 1, 0], [0, 0, 1]].map((e) => rotate(q, e).map((v) => v * s));
    const t = p.map((v, k) => v - (cols[0][k] * b[0] + cols[1][k] * b[1] + cols[2][k] * b[2]));
    return [...cols[0], 0, ...cols[1], 0, ...cols[2], 0, ...t, 1];
}

export function matMul(a, b) {
    const out = new Array(16).fill(0);
    for (let c = 0; c < 4; ++c) for (let r = 0; r < 4; ++r) for (let k = 0; k < 4; ++k) out[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
    return out;
}
