// Timed rows (.pal version 7, docs/pal-format.md "Timed rows") in the web runtime. A small timed palette made here by
// hand, its map written from the spec's words (not from the runtime's code): instanceFrame must give the rows and
// weight the spec defines from the rows' cells - inside cells, at their starts, across a loop's seam, past a
// one-shot's ends, held - in float, half and u16, its map wrapped into a second column block. A baked file turned
// timed by hand (version 7, the timed clip table at header byte 208): a clip whose rows sit on every second cell of a
// grid twice its rate plays exactly as the same rows untimed, and every check the spec asks of a reader refuses
// the file with a clear message.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { readPal, xxh64, clipInstance, instanceFrame, boneMatrix, hasTimedRows, instanceData, PAL_VERSION,
         TIMED_STILL_RATE } from '../crowdbake_pal.mjs';
import { travelOffset } from '../crowdbake_travel.mjs';
import { contactsCrossed } from '../crowdbake_contacts.mjs';
import { readVat, vatLayout } from '../crowdbake_vat.mjs';
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import { CROWDBAKE, FOX, SAMPLES, tmpDir, bake, cReaderAccepts } from './support.mjs';

const dir = tmpDir('timed');

// IEEE binary16 of a number in [0, 1] or a small integer, rounded to nearest (what a half file's map holds).
function toHalf(v) {
    if (v === 0) return 0;
    const e = Math.floor(Math.log2(v)), m = Math.round((v / 2 ** e - 1) * 1024);
    return m === 1024 ? ((e + 16) << 10) : ((e + 15) << 10) | m;
}

// Two clips of rows on cells: a loop of 8 cells (rows at 0, 1, 3, 6; its last interval wraps to row 0 at cell 8)
// and a one-shot of 5 cells (rows at 0, 2, 5). Two bones of qpos (4 texels a row); map rows before each clip. With
// `height` rows a block the texture wraps into blocks. Returns the palette as readPal would, and the rows' cells.
function handMade(precision, height = 64) {
    const rowTexels = 4, clipsCells = [{ cells: 8, rowCells: [0, 1, 3, 6], loops: true, rate: 8 },
                                       { cells: 5, rowCells: [0, 2, 5], loops: false, rate: 2.5 }];
    const clips = [];
    let rows = 0;
    for (const c of clipsCells) {
        const map_rows = Math.ceil(c.cells / rowTexels), first_row = rows + map_rows;
        clips.push({ name: `clip${clips.length}`, first_row, frames: c.rowCells.length, loops: c.loops, timed: true,
                     cells: c.cells, cell_rate: c.rate, map_rows, step: false, rowCells: c.rowCells });
        rows = first_row + c.rowCells.length;
    }
    const blocks = Math.ceil(rows / height), width = blocks * rowTexels;
    const header = { version: 7, flags: 64, layout: 2, precision, texels_per_bone: 2, bone_count: 2, row_texels: rowTexels,
                     rows, width, height, blocks };
    const texels = precision === 0 ? new Float32Array(width * height * 4) : new Uint16Array(width * height * 4);
    // The spec: cell c is texel c mod row_texels of row first_row - map_rows + c / row_texels; it lies in one row
    // interval [c_k, c_k+1) and holds (k, k + 1 or 0 in a loop's last, (c - c_k) / len, (c + 1 - c_k) / len).
    for (const c of clips) {
        for (let cell = 0; cell < c.cells; ++cell) {
            let k = 0;
            while (k + 1 < c.frames && c.rowCells[k + 1] <= cell) ++k;
            const wraps = k + 1 >= c.frames, start = c.rowCells[k], end = wraps ? c.cells : c.rowCells[k + 1];
            const v = [k, wraps ? 0 : k + 1, (cell - start) / (end - start), (cell + 1 - start) / (end - start)];
            const row = c.first_row - c.map_rows + Math.floor(cell / rowTexels), x = cell % rowTexels;
            const at = ((row % height) * width + Math.floor(row / height) * rowTexels + x) * 4;
            for (let i = 0; i < 4; ++i)
                texels[at + i] = precision === 0 ? v[i] : precision === 1 ? toHalf(v[i]) : i < 2 ? v[i] : Math.round(v[i] * 65535);
        }
    }
    return { header, clips, bones: [], texels, rowTravel: null };
}

// What the spec says a time gives, from the rows' cells alone: the interval [c_k, c_k+1) holding u (u wrapped or
// clamped as the spec says) and the weight (u - c_k) / (c_k+1 - c_k).
function expected(clip, u) {
    const n = clip.cells;
    u = clip.loops ? u - n * Math.floor(u / n) : Math.min(Math.max(u, 0), n);
    let k = 0;
    while (k + 1 < clip.frames && clip.rowCells[k + 1] <= u) ++k;
    if (!clip.loops && k === clip.frames - 1) return { row0: clip.first_row + k - 1, row1: clip.first_row + k, fr: 1 }; // u = n
    const end = k + 1 < clip.frames ? clip.rowCells[k + 1] : n;
    return { row0: clip.first_row + k, row1: clip.first_row + (k + 1 < clip.frames ? k + 1 : 0),
             fr: (u - clip.rowCells[k]) / (end - clip.rowCells[k]) };
}

// Cell interiors and starts, the loop seam and beyond it, before and past a one-shot's ends (u in cells).
const POSITIONS = [0, 0.25, 0.5, 1, 1.5, 2, 2.75, 3, 4.5, 5.999, 6, 7.25, 7.9, 7.999999, 8, 8.5, 9.25, 17.3, -0.5, -3.2, 4.9999, 5, 5.2, 40];

for (const [precision, name, tolerance] of [[0, 'float', 1e-6], [1, 'half', 1e-3], [2, 'u16', 2e-5]]) {
    for (const height of [64, 3]) {
        test(`a hand-made timed palette (${name}${height < 64 ? ', its map rows in column blocks of 3 rows' : ''}): ` +
             'instanceFrame gives the spec\'s rows and weight', () => {
            const pal = handMade(precision, height);
            if (height < 64) assert.ok(pal.header.blocks >= 3);
            for (const clip of pal.clips) {
                const inst = clipInstance(clip); // rate 1: u = time x cell_rate
                assert.deepEqual(inst, [clip.first_row, clip.loops ? clip.cells : -clip.cells, -clip.cell_rate, 0]);
                for (const u of POSITIONS) {
                    if (!clip.loops && u > clip.cells + 1) continue;
                    const got = instanceFrame(inst, u / clip.cell_rate, pal), want = expected(clip, u);
                    const where = `${clip.name} u ${u}: got ${JSON.stringify(got)}, want ${JSON.stringify(want)}`;
                    // A weight of 1 on row1 is the same pose as row1 with weight 0 from it: compare poses, not names.
                    const same = (a, b) => (a.row0 === b.row0 && a.row1 === b.row1 && Math.abs(a.fr - b.fr) <= tolerance) ||
                        (Math.abs(a.fr - 1) <= tolerance && b.fr <= tolerance && a.row1 === b.row0) ||
                        (Math.abs(b.fr - 1) <= tolerance && a.fr <= tolerance && b.row1 === a.row0);
                    assert.ok(same(got, want), where);
                    // The phase moves u as time does: phase w adds w x cells.
                    const phased = instanceFrame([inst[0], inst[1], inst[2], 0.25], (u - 0.25 * clip.cells) / clip.cell_rate, pal);
                    assert.ok(same(phased, want) || !clip.loops, `${where} (phased: ${JSON.stringify(phased)})`);
                    // Held rows: the map's r0 alone, unblended.
                    const held = instanceFrame([-clip.first_row - 1, inst[1], inst[2], 0], u / clip.cell_rate, pal);
                    assert.equal(held.fr, 0);
                    assert.equal(held.row1, held.row0);
                }
                // Rate 1.37: the same positions at times 1.37 times shorter.
                const fast = clipInstance(clip, 1.37);
                assert.ok(Math.abs(fast[2] + 1.37 * clip.cell_rate) < 1e-12);
                const a = instanceFrame(fast, 2.3 / (1.37 * clip.cell_rate), pal), b = expected(clip, 2.3);
                assert.ok(a.row0 === b.row0 && Math.abs(a.fr - b.fr) <= tolerance, `${clip.name} at rate 1.37`);
            }
        });
    }
}

test('held timed rows take the map\'s r0 alone: the row whose interval holds the time', () => {
    const pal = handMade(2), clip = pal.clips[0], held = [-clip.first_row - 1, clip.cells, -clip.cell_rate, 0];
    for (const [u, k] of [[0.5, 0], [1, 1], [2.9, 1], [3, 2], [5.5, 2], [6, 3], [7.99, 3]])
        assert.deepEqual(instanceFrame(held, u / clip.cell_rate, pal), { row0: clip.first_row + k, row1: clip.first_row + k, fr: 0 });
});

test('a timed instance without its palette is refused; at standstill it stays timed', () => {
    const pal = handMade(0), clip = pal.clips[0];
    assert.throws(() => instanceFrame(clipInstance(clip), 0.1), /timed instance \(a negative rate\) needs its palette/);
    const [first_row, frame_count, rate] = clipInstance(clip);
    const still = instanceData({ first_row, frame_count, rate, rate_per_speed: 0.5, phase: 'zero' }, 0);
    assert.equal(still[2], -TIMED_STILL_RATE); // -0 would read as an untimed clip's rows
    assert.ok(Math.fround(still[2]) < 0);
    assert.deepEqual(instanceData({ first_row, frame_count, rate, rate_per_speed: 0.5, phase: 'zero' }, 4).slice(0, 3),
                     [first_row, frame_count, -2]);
    // Footsteps count cells: a contact at 0.5 s of a 1 s, 8-cell loop sits at cell 4.
    const steps = contactsCrossed({ fps: 4, duration: 1, contacts: [{ foot: 'a', bone: 0, time: 0.5, lift: 0.75 }] }, 8, 3.5, 6.5, true);
    assert.deepEqual(steps.map((e) => [e.kind, e.at]), [['land', 4], ['lift', 6]]);
});

// ---- a baked file turned timed by hand ----

const u32 = (v, o) => v.getUint32(o, true);

// The quadruped at 30 fps (qpos, `precision`), rewritten as version 7: clip 0 gives its last row to clip 1's map
// (one row: 2 x frames cells fit in a row of 82 texels), and clip 1 becomes timed on a grid of twice its rate, its
// row k at cell 2k - the same poses at the same times as before. Returns { bytes, untimed } (untimed: the original).
function timedQuadruped(precision) {
    const untimed = bake(path.join(SAMPLES, 'quadruped.glb'), path.join(dir, `quadruped-${precision}.pal`),
                         ['--layout', 'qpos', '--precision', precision]);
    const bytes = new Uint8Array(untimed), view = new DataView(bytes.buffer);
    const pal = readPal(untimed);
    const h = pal.header, clip = pal.clips[1], cells = 2 * clip.frames, clips = h.clip_table_offset;
    assert.ok(cells <= h.row_texels && clip.loops && pal.clips[0].frames > 1 && !(h.flags & 1));
    // The timed clip table in the padding before the payload.
    const table = h.payload_offset - 16 * h.clip_count;
    assert.ok(table >= h.strings_offset + h.strings_size && table >= clips + 80 * h.clip_count);
    view.setUint32(8, 7, true);
    view.setUint32(12, u32(view, 12) | 64, true);
    view.setBigUint64(208, BigInt(table), true);
    bytes.fill(0, table, table + 16 * h.clip_count);
    view.setUint32(table + 16, cells, true);
    view.setFloat32(table + 20, 2 * clip.fps, true);
    view.setUint32(table + 24, 1, true);
    view.setUint32(clips + 12, pal.clips[0].frames - 1, true); // clip 0 frames - 1
    view.setUint32(clips + 80 + 28, u32(view, clips + 80 + 28) | 8, true); // clip 1: flag bit 3
    // The map row: row first_row - 1, texel c = (k, k + 1 or 0, (c mod 2) / 2, (c mod 2 + 1) / 2) with k = c / 2.
    const row = clip.first_row - 1, tb = h.texel_bytes / 4;
    const x = Math.floor(row / h.height) * h.row_texels, y = row % h.height;
    bytes.fill(0, h.payload_offset + (y * h.width + x) * h.texel_bytes, h.payload_offset + (y * h.width + x + h.row_texels) * h.texel_bytes);
    for (let c = 0; c < cells; ++c) {
        const k = c >> 1, v = [k, k + 1 < clip.frames ? k + 1 : 0, (c % 2) / 2, (c % 2 + 1) / 2];
        for (let i = 0; i < 4; ++i) {
            const at = h.payload_offset + (y * h.width + x + c) * h.texel_bytes + i * tb;
            if (precision === 'float') view.setFloat32(at, v[i], true);
            else view.setUint16(at, precision === 'half' ? toHalf(v[i]) : i < 2 ? v[i] : Math.round(v[i] * 65535), true);
        }
    }
    return { bytes: sealed(bytes), untimed: pal };
}

// The bytes with their checksum (header byte 176) made again.
function sealed(bytes) {
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const end = Number(view.getBigUint64(152, true) + view.getBigUint64(160, true));
    view.setBigUint64(176, xxh64([bytes.subarray(0, 176), new Uint8Array(8), bytes.subarray(184, end)]), true);
    return bytes;
}

for (const precision of ['float', 'half', 'u16']) {
    test(`a baked ${precision} file turned timed (rows on every second cell): read as version 7, plays as the rows untimed`, () => {
        const { bytes, untimed } = timedQuadruped(precision);
        const pal = readPal(bytes, { name: 'timed.pal', verifyChecksum: true });
        assert.equal(PAL_VERSION, 7);
        assert.ok(hasTimedRows(pal.header));
        const clip = pal.clips[1];
        assert.deepEqual([clip.timed, clip.cells, clip.cell_rate, clip.map_rows], [true, 2 * untimed.clips[1].frames,
                         Math.fround(2 * untimed.clips[1].fps), 1]);
        assert.deepEqual([pal.clips[0].timed, pal.clips[0].cells, pal.clips[2].timed], [false, 0, false]);
        let worst = 0;
        const period = clip.frames / untimed.clips[1].fps;
        for (const t of [0, 0.013, 0.31, period * 0.5, period - 0.004, period + 0.05, 2.7 * period, -0.2])
            for (let j = 0; j < pal.header.bone_count; ++j) {
                const a = boneMatrix(pal, 1, t, j), b = boneMatrix(untimed, 1, t, j);
                for (let k = 0; k < 16; ++k) worst = Math.max(worst, Math.abs(a[k] - b[k]));
            }
        assert.ok(worst < 2e-5, `timed vs untimed bone matrices differ by ${worst}`);
        assert.deepEqual(travelOffset(pal, 1, 0.37), [0, 0, 0]);
    });
}

test('every check the spec asks of a timed file refuses it with a clear message, as the C reader refuses it', () => {
    const { bytes } = timedQuadruped('u16');
    const view = new DataView(bytes.buffer), table = Number(view.getBigUint64(208, true));
    const pal = readPal(bytes), row = pal.clips[1].first_row - 1, h = pal.header;
    const mapTexel = h.payload_offset + ((row % h.height) * h.width + Math.floor(row / h.height) * h.row_texels + 3) * 8;
    const file = path.join(dir, 'bad.pal');
    writeFileSync(file, bytes);
    assert.ok(cReaderAccepts(file), 'the C reader opens the good file');
    const broken = (change, message) => {
        const b = bytes.slice(), v = new DataView(b.buffer);
        change(v);
        assert.throws(() => readPal(sealed(b), { name: 'bad.pal' }), (e) => e.message.startsWith('bad.pal: ') &&
                      message.test(e.message) && !e.message.includes('\n'), message.source);
        writeFileSync(file, b);
        assert.ok(!cReaderAccepts(file), `the C reader opens what readPal refuses (${message.source})`);
    };
    broken((v) => v.setUint32(8, 6, true), /flags bit 6 \(timed rows, byte 12\) in a version 6 file/);
    broken((v) => v.setBigUint64(208, BigInt(bytes.length - 8), true), /timed clip table .* lies outside/);
    broken((v) => v.setBigUint64(208, BigInt(table + 2), true), /timed clip table .* lies outside/);
    broken((v) => v.setUint32(table + 28, 1, true), /timed clip entry 1 .*reserved 1/);
    broken((v) => v.setBigUint64(208, 100n, true), /timed clip table .* lies outside/);
    broken((v) => v.setUint32(table + 24, 2, true), /timed clip entry 1 .*map_rows 2/);
    broken((v) => v.setFloat32(table + 20, 0, true), /timed clip entry 1 .*cell_rate 0/);
    broken((v) => v.setFloat32(table + 20, Infinity, true), /timed clip entry 1 .*cell_rate Infinity/);
    broken((v) => v.setUint32(table + 16, 0, true), /timed clip entry 1 .*cells 0/);
    broken((v) => v.setUint32(table + 4, 1, true), /timed clip entry 0 .* not all 0 for a clip without clip flag bit 3/);
    broken((v) => v.setUint32(h.clip_table_offset + 80 + 28, u32(v, h.clip_table_offset + 80 + 28) & ~8, true),
           /timed clip entry 1 .* not all 0/);
    broken((v) => v.setUint32(h.clip_table_offset + 28, u32(v, h.clip_table_offset + 28) | 8, true),
           /timed clip entry 0 .*cells 0/);
    broken((v) => v.setUint16(mapTexel, 999, true), /clip 1 \(.*\): map texel of cell 3 .*rows 999, 2/);
    broken((v) => v.setUint16(mapTexel + 2, pal.clips[1].frames, true), /map texel of cell 3 .*needs whole rows below/);
    broken((v) => { v.setUint16(mapTexel + 4, 60000, true); v.setUint16(mapTexel + 6, 100, true); }, /map texel of cell 3 .*f0 <= f1/);
    // A timed clip in a file without flag bit 6 (nor the table): refused, not played as rows.
    const plain = bytes.slice(), pv = new DataView(plain.buffer);
    pv.setUint32(12, u32(pv, 12) & ~64, true);
    assert.throws(() => readPal(sealed(plain), { name: 'bad.pal' }), /clip 1 .* is timed \(clip flag bit 3\) in a file without timed rows/);
    writeFileSync(file, plain);
    assert.ok(!cReaderAccepts(file));
});

test('a float map\'s rows must be whole numbers (refused as the C reader refuses them)', () => {
    const { bytes } = timedQuadruped('float');
    const pal = readPal(bytes), h = pal.header, row = pal.clips[1].first_row - 1;
    const at = h.payload_offset + ((row % h.height) * h.width + Math.floor(row / h.height) * h.row_texels + 3) * 16;
    new DataView(bytes.buffer).setFloat32(at, 1.5, true);
    assert.throws(() => readPal(sealed(bytes), { name: 'float.pal' }), /^Error: float.pal: clip 1 .*map texel of cell 3 .*rows 1.5, 2/);
    const file = path.join(dir, 'fraction.pal');
    writeFileSync(file, bytes);
    assert.ok(!cReaderAccepts(file));
});

// Frame F of a VAT (readVat's): its vertices' half-float positions, in vertex order (VAT_MAIN's vat_fetch).
function vatFrame(vat, f) {
    const out = [];
    for (let v = 0; v < vat.vertices; ++v) {
        const row = f * vat.rowsPerFrame + Math.floor(v / vat.frameWidth), block = Math.floor(row / vat.height);
        const t = ((row - block * vat.height) * vat.width + block * vat.frameWidth + v % vat.frameWidth) * 4;
        out.push(vat.positions[t], vat.positions[t + 1], vat.positions[t + 2]);
    }
    return out;
}

// The VAT beside a timed palette (the viewer's): `crowdbake vat --like` bakes Fox's timed Run at its cells' rate, one
// frame a cell. Judged against VATs of one clip each (`vat --clip NAME --fps RATE`, the clip's rows' or cells' rate):
// the frames vatLayout gives a clip's instance (its first, its count, at |rate| a second) hold the same positions, bit
// for bit, as that clip's own VAT.
test('vatLayout: the VAT of a timed palette, frame for cell', () => {
    const palPath = path.join(dir, 'fox_local.pal'), vatPath = path.join(dir, 'fox_local.exr'), onePath = path.join(dir, 'one.exr');
    const pal = readPal(bake(FOX, palPath, ['--fps', 'auto', '--bone-space', 'local']));
    const vatOf = (args, out) => {
        execFileSync(CROWDBAKE, ['vat', FOX, ...args, '-o', out, '--exr-compression', 'none'], { stdio: 'ignore' });
        return readVat(readFileSync(out));
    };
    const vat = vatOf(['--like', palPath], vatPath), layout = vatLayout(pal);
    assert.ok(pal.clips.some((c) => c.timed));
    assert.equal(layout.frames, vat.frames);
    for (const c of pal.clips) {
        const fps = c.timed ? c.cell_rate : c.fps, one = vatOf(['--clip', c.name, '--fps', String(fps)], onePath);
        const [first, count, rate, phase] = layout.instanceOf(clipInstance(c, 1.5, 0.25));
        assert.deepEqual([Math.abs(count), rate, phase], [one.frames, fps * 1.5, 0.25], c.name);
        for (let f = 0; f < one.frames; ++f) assert.deepEqual(vatFrame(vat, first + f), vatFrame(one, f), `${c.name} frame ${f}`);
    }
    assert.deepEqual(vatLayout(readPal(bake(FOX, path.join(dir, 'fox.pal')))).instanceOf([1, 2, 3, 0.5]), [1, 2, 3, 0.5]);
});
