// The per-row travel offset (.pal version 5) in the web reader: the table and each clip's heading
// read as the format says (docs/pal-format.md, read here from the bytes), blended between rows as
// the shaders blend rows, refused exactly where the C reader refuses a corrupted table offset, and
// zero for files without it.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { readPal } from '../crowdbake_pal.mjs';
import { travelOffset } from '../crowdbake_travel.mjs';
import { SAMPLES, tmpDir, bake, cReaderAccepts } from './support.mjs';

const dir = tmpDir('travel');
const HUSKY = '../shared/assets/quaternius-husky/Husky.glb';

// The table and headings straight from the bytes: header byte 192 (u64), one f32 a row; clip entry byte 68.
function fromBytes(bytes) {
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const table = Number(view.getBigUint64(192, true)), clips = Number(view.getBigUint64(120, true));
    return {
        row: (r) => view.getFloat32(table + 4 * r, true),
        heading: (c) => [0, 4, 8].map((o) => view.getFloat32(clips + 80 * c + 68 + o, true)),
    };
}

test('Husky: the gallops carry offsets along their heading, the walk none; blended as the rows blend', () => {
    const bytes = bake(HUSKY, path.join(dir, 'husky.pal'), ['--fps', 'auto']);
    const pal = readPal(bytes, { name: 'husky.pal', verifyChecksum: true });
    assert.equal(pal.header.version, 5);
    assert.ok(pal.header.flags & 16);
    const raw = fromBytes(bytes);
    const index = (name) => pal.clips.findIndex((c) => c.name === `AnimalArmature|${name}`);
    for (const name of ['Gallop', 'Gallop_Jump', 'Walk']) {
        const c = index(name), clip = pal.clips[c], d = raw.heading(c);
        assert.deepEqual(clip.travel_heading, d);
        const applied = d.some((x) => x !== 0);
        assert.equal(applied, name !== 'Walk', name);
        let span = 0;
        for (let f = 0; f < clip.frames; ++f) {
            const o = travelOffset(pal, c, f / clip.fps), want = raw.row(clip.first_row + f);
            for (let k = 0; k < 3; ++k) assert.ok(Math.abs(o[k] - want * d[k]) <= 1e-6, `${name} row ${f}`);
            const next = raw.row(clip.first_row + ((f + 1) % clip.frames)), mid = travelOffset(pal, c, (f + 0.5) / clip.fps);
            for (let k = 0; k < 3; ++k) assert.ok(Math.abs(mid[k] - 0.5 * (want + next) * d[k]) <= 1e-6, `${name} mid ${f}`);
            span = Math.max(span, Math.abs(want));
        }
        // A gallop's body surges by a visible part of its height within the cycle; a walk's rows read 0.
        if (applied) assert.ok(span > 0.002 * pal.header.model_height, `${name}: offsets up to ${span}`);
        else assert.equal(span, 0);
    }
});

test('a file without the table (older versions) reads every offset as 0', () => {
    const pal = readPal(bake(path.join(SAMPLES, 'fish.glb'), path.join(dir, 'fish.pal')));
    assert.ok(pal.header.version < 5);
    assert.equal(pal.rowTravel, null);
    assert.deepEqual(travelOffset(pal, 0, 0.3), [0, 0, 0]);
});

test('corruptions of the travel table offset and its flag: refused exactly when the C reader refuses them', () => {
    const source = readFileSync(path.join(dir, 'husky.pal'));
    const file = path.join(dir, 'corrupt.pal');
    let refused = 0;
    const cases = [0n, 1n, 255n, 4097n, BigInt(source.length - 3), 0x7fffffffffffffffn, 0xffffffffffffffffn]
        .map((v) => [192, 8, v]).concat([[12, 4, 0], [8, 4, 4]]); // the flag cleared; version 4 (no table)
    for (const [offset, width, value] of cases) {
        const bytes = new Uint8Array(source), view = new DataView(bytes.buffer);
        if (width === 8) view.setBigUint64(offset, value, true);
        else view.setUint32(offset, value, true);
        writeFileSync(file, bytes);
        let js = true;
        try {
            readPal(bytes, { name: 'c.pal' });
        } catch (e) {
            assert.equal(e.constructor, Error);
            assert.ok(!e.message.includes('\n'));
            js = false;
        }
        assert.equal(js, cReaderAccepts(file), `byte ${offset} = ${value}`);
        refused += !js;
    }
    assert.ok(refused >= 5, `${refused} refused`);
});
