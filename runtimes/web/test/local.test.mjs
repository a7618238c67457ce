// Local rows (.pal version 6, flag bit 5) in the web reader: the bone range table read and checked, u16 decoded with
// each bone's ranges, and boneMatrix composing each bone's blended local rows from the root (a parent may come after
// its child). The files are made here from a global bake by the spec's formulas (local_support.mjs); the expected
// matrices are the global bake's at the rows, and 4x4 products of the blended local poses between them.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { writeFileSync } from 'node:fs';
import { readPal, boneMatrix, instanceBoneMatrix, instanceBoneMatrixCrossfade, hasLocalRows, xxh64 } from '../crowdbake_pal.mjs';
import { SAMPLES, tmpDir, bake, inspect, cReaderAccepts } from './support.mjs';
import { makeLocalPal, poseMatrix, matMul } from './local_support.mjs';

const dir = tmpDir('local');
const source = bake(path.join(SAMPLES, 'quadruped.glb'), path.join(dir, 'global.pal'), ['--layout', 'qpos', '--precision', 'float']);
const global = readPal(source, { verifyChecksum: true });
const height = global.header.model_height;
const made = {
    float: makeLocalPal(source, global),
    reversed: makeLocalPal(source, global, { reversed: true }),
    u16: makeLocalPal(source, global, { u16: true }),
};

// The largest difference of two matrices' entries, translations in model heights.
function difference(a, b) {
    let worst = 0;
    for (let k = 0; k < 16; ++k) worst = Math.max(worst, Math.abs(a[k] - b[k]) / (k >= 12 ? height : 1));
    return worst;
}

// Every clip's first, middle and last row, at rate 1 (time = the row: no rounding of time x fps).
function eachRow(fn) {
    for (const clip of global.clips)
        for (const f of [0, Math.floor(clip.frames / 2), clip.frames - 1])
            fn([clip.first_row, clip.loops ? clip.frames : -clip.frames, 1, 0], f, clip.first_row + f);
}

test('a local file reads as version 6 with each bone\'s ranges; at the rows it composes to the global bake', () => {
    for (const [what, { bytes, order }] of Object.entries(made)) {
        const pal = readPal(bytes, { name: `${what}.pal`, verifyChecksum: true });
        assert.equal(pal.header.version, 6);
        assert.ok(hasLocalRows(pal.header) && !hasLocalRows(global.header));
        assert.ok(pal.bones.every((b) => b.range && b.range.scale_max > 0) && global.bones.every((b) => !b.range));
        if (what === 'reversed')
            assert.ok(pal.bones.every((b, j) => b.parent < 0 || b.parent > j), 'every parent after its child');
        let worst = 0;
        eachRow((inst, f) => order.forEach((old, j) => {
            worst = Math.max(worst, difference(instanceBoneMatrix(pal, inst, f, j), instanceBoneMatrix(global, inst, f, old)));
        }));
        // float: the local rows' own float rounding compounded down a chain; u16: 16-bit steps of each bone's box
        const tolerance = what === 'u16' ? 1e-3 : 2e-6;
        assert.ok(worst < tolerance, `${what}: ${worst} from the global bake (tolerance ${tolerance})`);
        console.log(`  ${what}: composed local rows within ${worst.toExponential(2)} (model heights) of the global bake's`);
    }
});

const nlerp = (a, b, w) => {
    const flip = a.q.reduce((s, c, k) => s + c * b.q[k], 0) < 0 ? -1 : 1;
    const q = a.q.map((c, k) => c + (flip * b.q[k] - c) * w), n = Math.hypot(...q);
    return { q: q.map((c) => c / n), p: a.p.map((c, k) => c + (b.p[k] - c) * w), s: a.s + (b.s - a.s) * w };
};

// Bone j's matrix as the product of its chain's local 4x4s, root first, each local pose from localAt(j).
function chainMatrix(pal, j, localAt) {
    const local = poseMatrix(localAt(j), pal.bones[j].bind_position);
    const parent = pal.bones[j].parent;
    return parent < 0 ? local : matMul(chainMatrix(pal, parent, localAt), local);
}

test('between rows and in a cross-fade: each bone\'s local rows blended, then composed (not the global blend)', () => {
    const { bytes, order, rows } = made.reversed, pal = readPal(bytes);
    const back = new Map(order.map((old, j) => [j, old]));
    const clip = global.clips.find((c) => c.loops && c.frames > 8), other = global.clips.find((c) => c !== clip);
    const inst = [clip.first_row, clip.frames, 1, 0], from = [other.first_row, other.loops ? other.frames : -other.frames, 1, 0];
    let worst = 0, chord = 0;
    for (const [f, fade] of [[2.37, 1], [clip.frames - 0.5, 1], [3.61, 0.3]]) { // mid-row, the loop seam, a cross-fade
        const r0 = clip.first_row + Math.floor(f), r1 = clip.first_row + (Math.floor(f) + 1) % clip.frames;
        const o0 = other.first_row + Math.floor(f), o1 = Math.min(o0 + 1, other.first_row + other.frames - 1);
        const fr = f - Math.floor(f);
        const localAt = (j) => {
            const to = nlerp(rows[r0][back.get(j)], rows[r1][back.get(j)], fr);
            return fade < 1 ? nlerp(nlerp(rows[o0][back.get(j)], rows[o1][back.get(j)], fr), to, fade) : to;
        };
        for (let j = 0; j < pal.header.bone_count; ++j) {
            const got = fade < 1 ? instanceBoneMatrixCrossfade(pal, from, inst, fade, f, j) : instanceBoneMatrix(pal, inst, f, j);
            worst = Math.max(worst, difference(got, chainMatrix(pal, j, localAt)));
            if (fade === 1) chord = Math.max(chord, difference(got, instanceBoneMatrix(global, inst, f, back.get(j))));
        }
    }
    assert.ok(worst < 2e-6, `${worst} from the blended local poses composed as 4x4 products`);
    assert.ok(chord > 10 * worst, `the global rows' blend differs by ${chord}: the test tells the two apart`);
    console.log(`  between rows: ${worst.toExponential(2)} from the 4x4 products; the global blend differs by ${chord.toExponential(2)}`);
});

// The bytes of `bytes` with fn(view) applied and the checksum made again (so only the structure is judged).
function changed(bytes, fn) {
    const copy = new Uint8Array(bytes), view = new DataView(copy.buffer);
    fn(view);
    view.setBigUint64(176, 0n, true);
    view.setBigUint64(176, xxh64(copy), true);
    return copy;
}

test('a damaged range table, parent loop or layout is refused with a one-line message', () => {
    const { bytes } = made.u16, view = new DataView(bytes.buffer, bytes.byteOffset);
    const at = Number(view.getBigUint64(200, true)), bones = view.getUint32(32, true), boneTable = Number(view.getBigUint64(128, true));
    const last = at + (bones - 1) * 32;
    const cases = {
        'offset 0': (v) => v.setBigUint64(200, 0n, true),
        'offset past the end': (v) => v.setBigUint64(200, BigInt(bytes.length - 64), true),
        'offset huge': (v) => v.setBigUint64(200, 0xffffffffffffffffn, true),
        'NaN pos_min': (v) => v.setFloat32(at + 4, NaN, true),
        'infinite pos_max': (v) => v.setFloat32(last + 20, Infinity, true),
        'min above max': (v) => v.setFloat32(last, v.getFloat32(last + 16, true) + 1, true),
        'scale_max 0': (v) => v.setFloat32(at + 12, 0, true),
        'scale_max negative': (v) => v.setFloat32(last + 12, -1, true),
        'reserved': (v) => v.setUint32(last + 28, 1, true),
        'precision half': (v) => v.setUint32(24, 1, true),
        'relative positions': (v) => v.setUint32(12, v.getUint32(12, true) | 4, true),
        'version 5 (no bit 5 then)': (v) => v.setUint32(8, 5, true),
        'offset not 4-byte aligned': (v) => v.setBigUint64(200, v.getBigUint64(200, true) + 2n, true),
        'a parent loop': (v) => { // the root's parent made one of its descendants
            const root = Array.from({ length: bones }, (_, j) => j).find((j) => v.getInt32(boneTable + j * 32 + 8, true) === -1);
            const child = Array.from({ length: bones }, (_, j) => j).find((j) => v.getInt32(boneTable + j * 32 + 8, true) === root);
            v.setInt32(boneTable + root * 32 + 8, child, true);
        },
    };
    for (const [what, fn] of Object.entries(cases)) {
        let error = null;
        try {
            readPal(changed(bytes, fn), { name: 'l.pal', verifyChecksum: true });
        } catch (e) {
            error = e;
        }
        assert.ok(error, `${what}: accepted`);
        assert.ok(error.constructor === Error && error.message.startsWith('l.pal: ') && !error.message.includes('\n'), error.message);
    }
});

// ---- the C writer's local bakes (crowdbake bake --bone-space local) ----

const bakedU16 = path.join(dir, 'baked-local-u16.pal');
const baked = bake(path.join(SAMPLES, 'quadruped.glb'), bakedU16, ['--layout', 'qpos', '--precision', 'u16', '--bone-space', 'local']);

test('a local bake of the C writer: its composed bones as crowdbake inspect --frame gives them (the C reader composes)', () => {
    for (const [file, bytes] of [[bakedU16, baked],
        [path.join(dir, 'baked-local-float.pal'), bake(path.join(SAMPLES, 'quadruped.glb'), path.join(dir, 'baked-local-float.pal'),
                                                       ['--layout', 'qpos', '--precision', 'float', '--bone-space', 'local'])]]) {
        const pal = readPal(bytes, { name: file, verifyChecksum: true });
        assert.ok(hasLocalRows(pal.header) && pal.header.version === 6);
        let worst = 0;
        for (const [c, clip] of pal.clips.entries())
            for (const f of [0, clip.frames - 1]) {
                const joints = inspect(file, ['--clip', clip.name, '--frame', String(f)]).joints;
                for (let j = 0; j < pal.header.bone_count; ++j)
                    worst = Math.max(worst, difference(instanceBoneMatrix(pal, [clip.first_row, clip.loops ? clip.frames : -clip.frames, 1, 0], f, j), joints[j]));
            }
        assert.ok(worst < 2e-5, `${path.basename(file)}: ${worst} from the C reader's composed matrices`);
        console.log(`  ${path.basename(file)}: within ${worst.toExponential(2)} of crowdbake inspect --frame`);
    }
});

test('single-field corruptions of a local bake\'s range table and its offset: refused exactly when the C reader refuses them', () => {
    const view = new DataView(baked.buffer, baked.byteOffset, baked.byteLength);
    const at = Number(view.getBigUint64(200, true)), last = at + (view.getUint32(32, true) - 1) * 32;
    const file = path.join(dir, 'corrupt-local.pal');
    const f32 = [0, -1, 1e30, NaN, Infinity, -Infinity];
    const cases = [...[0n, 1n, 255n, 4097n, BigInt(at + 2), BigInt(baked.length - 8), 0xffffffffffffffffn].map((v) => ['offset', 200, 'u64', v]),
        ['flags', 12, 'u32', view.getUint32(12, true) & ~32], ['flags', 12, 'u32', view.getUint32(12, true) | 4], ['version', 8, 'u32', 5],
        ['precision', 24, 'u32', 1]];
    for (const base of [at, last])
        for (let k = 0; k < 8; ++k) for (const v of k === 7 ? [1, 0xffffffff] : f32) cases.push([`entry ${base} word ${k}`, base + 4 * k, k === 7 ? 'u32' : 'f32', v]);
    let refused = 0;
    for (const [what, offset, type, value] of cases) {
        const bytes = new Uint8Array(baked), v = new DataView(bytes.buffer);
        if (type === 'u64') v.setBigUint64(offset, value, true);
        else if (type === 'u32') v.setUint32(offset, value, true);
        else v.setFloat32(offset, value, true);
        writeFileSync(file, bytes);
        let js = true;
        try {
            readPal(bytes, { name: 'c.pal' });
        } catch (e) {
            assert.ok(e.constructor === Error && !e.message.includes('\n'), e.message);
            js = false;
        }
        assert.equal(js, cReaderAccepts(file), `${what} = ${value}: the web reader ${js ? 'accepts' : 'refuses'}, the C reader does not`);
        refused += !js;
    }
    assert.ok(refused > 30, `${refused} of ${cases.length} refused by both`);
    console.log(`  ${cases.length} corruptions, ${refused} refused by both readers, the rest read by both`);
});
