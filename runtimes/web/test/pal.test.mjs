// The web reader against the C side: real bakes of every layout x precision, zstd, wrapped rows,
// and hostile files (the fuzz regressions, truncations, single-field corruptions).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { readPal, xxh64, texelIndex, LAYOUTS, PRECISIONS } from '../crowdbake_pal.mjs';
import { SAMPLES, FOX, tmpDir, bake, inspect, cReaderAccepts, zstdDecompress, fzstd, jointMatrix } from './support.mjs';

const dir = tmpDir('pal');
const QUADRUPED = path.join(SAMPLES, 'quadruped.glb');
const decompress = fzstd; // the decoder a page would use (npm fzstd)

// Asserts `fn` throws a plain Error with a one-line message starting with the file's name.
function assertRefused(fn, name, what) {
    let error = null;
    try {
        fn();
    } catch (e) {
        error = e;
    }
    assert.ok(error, `${what}: accepted`);
    assert.equal(error.constructor, Error, `${what}: threw ${error.constructor.name}: ${error.message}`);
    assert.ok(error.message.startsWith(`${name}: `) && !error.message.includes('\n'), `${what}: message "${error.message}"`);
    return error.message;
}

function assertNear(actual, expected, tolerance, what) {
    assert.equal(actual.length, expected.length, what);
    for (let i = 0; i < expected.length; ++i)
        assert.ok(Math.abs(actual[i] - expected[i]) <= tolerance * (1 + Math.abs(expected[i])),
                  `${what}[${i}]: ${actual[i]} vs crowdbake's ${expected[i]}`);
}

// The reader's view of `file` against what `crowdbake inspect` reports of it.
function checkAgainstC(file, pal, framesPerClip = 2) {
    const c = inspect(file);
    const h = pal.header;
    assert.equal(h.version, c.version);
    assert.equal(LAYOUTS[h.layout], c.layout);
    assert.equal(PRECISIONS[h.precision], c.precision);
    for (const k of ['texels_per_bone', 'rows', 'width', 'height', 'blocks', 'payload_offset'])
        assert.equal(h[k], c[k], k);
    assert.equal(h.bone_count, c.bones.length);
    assert.equal(h.payload_size, c.payload_bytes);
    assert.equal((h.flags & 1) !== 0, c.zstd);
    assert.equal(h.fps, c.fps);
    assert.equal(h.input_hash.toString(16).padStart(16, '0'), c.input_hash);
    assert.equal(Math.fround(c.max_error), h.max_error);
    assert.deepEqual(pal.bones.map((b) => b.name), c.bones);
    assert.deepEqual(pal.clips.map((k) => ({ name: k.name, first_row: k.first_row, frames: k.frames, fps: k.fps,
                                             duration: k.duration, loops: k.loops, fitted_rows: k.fitted,
                                             root_velocity: k.root_velocity })),
                     c.clips.map((k) => ({ ...k, fps: Math.fround(k.fps), duration: Math.fround(k.duration),
                                           root_velocity: k.root_velocity.map(Math.fround) })));
    // Texels: a few frames of every clip decoded by the format's rules, against the C reader's matrices.
    const tolerance = h.precision === 2 ? 1e-4 : 1e-5;
    for (const clip of pal.clips) {
        const frames = framesPerClip === 1 ? [clip.frames - 1] : [0, clip.frames - 1];
        for (const frame of frames) {
            const joints = inspect(file, ['--clip', clip.name, '--frame', String(frame)]).joints;
            for (let j = 0; j < h.bone_count; ++j)
                assertNear(jointMatrix(pal, clip.first_row + frame, j), joints[j], tolerance,
                           `${path.basename(file)} ${clip.name}[${frame}] bone ${j}`);
        }
    }
}

test('XXH64 matches the specification\'s values', () => {
    assert.equal(xxh64(new Uint8Array(0)), 0xef46db3751d8e999n);
    assert.equal(xxh64(new TextEncoder().encode('a')), 0xd24ec4f1a98c6e5bn);
    assert.equal(xxh64(new TextEncoder().encode('abc')), 0x44bc2cf5ad770999n);
    // 39 bytes: one 32-byte stripe, then the 4-byte and the 1-byte tail steps (python-xxhash's example).
    assert.equal(xxh64(new TextEncoder().encode('Nobody inspects the spammish repetition')), 0xfbcea83c8a378bf1n);
    // Split anywhere, the same hash: the checksum hashes the file in three parts. (Files' checksums
    // against the C writer's are checked by verifyChecksum in the bake tests below.)
    const bytes = new Uint8Array(100).map((_, i) => (i * 37) & 255);
    const whole = xxh64(bytes);
    for (const cut of [0, 1, 7, 31, 32, 33, 64, 99, 100])
        assert.equal(xxh64([bytes.subarray(0, cut), bytes.subarray(cut)]), whole, `cut at ${cut}`);
});

for (const layout of LAYOUTS) {
    for (const precision of PRECISIONS) {
        test(`quadruped ${layout}/${precision}: header, tables and texels as the C reader has them`, () => {
            const file = path.join(dir, `quadruped-${layout}-${precision}.pal`);
            const bytes = bake(QUADRUPED, file, ['--layout', layout, '--precision', precision]);
            const pal = readPal(bytes, { name: file, verifyChecksum: true });
            assert.equal(pal.texels.constructor, precision === 'float' ? Float32Array : Uint16Array);
            assert.equal(pal.texels.byteLength, pal.header.width * pal.header.height * pal.header.texel_bytes);
            // Byte-identical with the payload at the header's offset (a view, not a copy).
            const payload = bytes.subarray(pal.header.payload_offset, pal.header.payload_offset + pal.header.payload_size);
            assert.ok(Buffer.from(pal.texels.buffer, pal.texels.byteOffset, pal.texels.byteLength).equals(payload));
            assert.equal(pal.texels.buffer, bytes.buffer);
            checkAgainstC(file, pal, layout === 'qpos' || precision === 'u16' ? 2 : 1);
        });
    }
}

test('Fox (third-party): qpos/half is version 3 with relative positions and offsets; mat4/float', () => {
    for (const [layout, precision, version] of [['qpos', 'half', 3], ['mat4', 'float', 1]]) {
        const file = path.join(dir, `fox-${layout}-${precision}.pal`);
        // Without the per-row travel offsets its Walk and Run would carry (version 5, travel.test.mjs).
        const args = ['--layout', layout, '--precision', precision, '--row-travel', 'off'];
        const pal = readPal(bake(FOX, file, args), { name: file, verifyChecksum: true });
        assert.equal(pal.header.version, version);
        assert.equal((pal.header.flags & 4) !== 0, version === 3);
        // Version 3's offsets are each bone's own, not its bind position (which version 2 used).
        const moved = pal.bones.filter((b) => b.position_offset.some((v, k) => Math.abs(v - b.bind_position[k]) > 1e-3));
        assert.ok(version === 1 ? pal.bones.every((b) => b.position_offset.every((v) => v === 0))
            : moved.length > pal.bones.length / 2, `${moved.length} of ${pal.bones.length} offsets differ from the bind`);
        assert.deepEqual(pal.clips.map((c) => c.name), ['Survey', 'Walk', 'Run']);
        checkAgainstC(file, pal);
    }
});

test('zstd: refused with the fix without a decoder; with one, the texels of the uncompressed bake', () => {
    for (const [model, args] of [[QUADRUPED, ['--layout', 'qpos', '--precision', 'u16']], [FOX, ['--layout', 'mat4', '--precision', 'float']]]) {
        const plainFile = path.join(dir, `zstd-plain-${path.basename(model)}.pal`);
        const zstdFile = path.join(dir, `zstd-${path.basename(model)}.pal`);
        const plain = readPal(bake(model, plainFile, args), { name: plainFile });
        const bytes = bake(model, zstdFile, [...args, '--zstd']);
        const message = assertRefused(() => readPal(bytes, { name: zstdFile }), zstdFile, 'zstd without a decoder');
        assert.match(message, /zstd-compressed.*bake without --zstd/);
        const pal = readPal(bytes, { name: zstdFile, verifyChecksum: true, decompress });
        assert.ok(pal.header.payload_size < pal.header.payload_raw_size);
        assert.ok(Buffer.from(pal.texelBytes).equals(Buffer.from(plain.texelBytes)));
        const payload = bytes.subarray(pal.header.payload_offset, pal.header.payload_offset + pal.header.payload_size);
        assert.ok(Buffer.from(zstdDecompress(payload)).equals(Buffer.from(pal.texelBytes)), 'fzstd agrees with zstd(1)');
        assert.equal(pal.texels.constructor, plain.texels.constructor);
        checkAgainstC(zstdFile, pal, 1);
        // A decompressed size the file did not promise, a decoder that throws, a size over the limit.
        assertRefused(() => readPal(bytes, { name: 'x.pal', decompress: (b, n) => decompress(b, n).subarray(8) }), 'x.pal', 'short');
        assertRefused(() => readPal(bytes, { name: 'x.pal', decompress: () => { throw new TypeError('bad frame'); } }), 'x.pal', 'throws');
        assertRefused(() => readPal(bytes, { name: 'x.pal', decompress, maxDecompressedBytes: 1024 }), 'x.pal', 'limit');
    }
});

test('zstd: a damaged payload is refused by its checksum before a decoder sees it, verifyChecksum or not', () => {
    // The fuzz finding that kept fzstd 0.1.1 busy 13 s (its sequences copy past the output's end),
    // and a real bake's compressed payload with one byte flipped.
    const flipped = new Uint8Array(readFileSync(path.join(dir, `zstd-${path.basename(FOX)}.pal`)));
    flipped[flipped.length - 5] ^= 1;
    const finding = readFileSync('tests/fuzz/regressions/web/pal-zstd-frame-fzstd-copies-past-its-output.pal');
    for (const [what, bytes] of [['flipped', flipped], ['finding', finding]]) {
        let decoded = 0;
        const counting = (b, n) => (++decoded, decompress(b, n));
        for (const verifyChecksum of [false, true])
            assert.match(assertRefused(() => readPal(bytes, { name: 'z.pal', verifyChecksum, decompress: counting }), 'z.pal', what),
                         /checksum mismatch/);
        assert.equal(decoded, 0, `${what}: the decoder was called`);
    }
});

test('rows wrapped into column blocks (--max-texture-size) are addressed as the C reader does', () => {
    const file = path.join(dir, 'wrapped.pal');
    const pal = readPal(bake(QUADRUPED, file, ['--layout', 'qpos', '--precision', 'float', '--max-texture-size', '200']),
                        { name: file, verifyChecksum: true });
    assert.equal(pal.header.blocks, 2);
    assert.equal(pal.header.height, 133);
    // Row 200 lies in the second block: texel x = 1 * 82 + bone * 2, y = 67.
    assert.equal(texelIndex(pal.header, 200, 3), (67 * pal.header.width + 82 + 6) * 4);
    checkAgainstC(file, pal);
});

test('a file whose bytes start at an unaligned offset still gives aligned texel views', () => {
    const bytes = readFileSync(path.join(dir, 'quadruped-mat4-float.pal'));
    const shifted = new Uint8Array(bytes.length + 1);
    shifted.set(bytes, 1);
    const pal = readPal(shifted.subarray(1), { verifyChecksum: true });
    assert.deepEqual(Array.from(pal.texels.subarray(0, 64)),
                     Array.from(readPal(bytes).texels.subarray(0, 64)));
});

test('checksum: one flipped payload byte is refused with verifyChecksum', () => {
    const bytes = new Uint8Array(readFileSync(path.join(dir, 'quadruped-qpos-u16.pal')));
    bytes[bytes.length - 3] ^= 1;
    assert.match(assertRefused(() => readPal(bytes, { name: 'f.pal', verifyChecksum: true }), 'f.pal', 'flip'),
                 /checksum mismatch/);
    readPal(bytes, { name: 'f.pal' }); // the structure is intact
});

test('every fuzz regression is refused with a clean Error, as the C reader refuses it', () => {
    const regressions = 'tests/fuzz/regressions/pal';
    const files = readdirSync(regressions);
    let refused = 0;
    for (const f of files) {
        const bytes = readFileSync(path.join(regressions, f));
        // A valid file kept there as the fuzzer's seed (timed-held.pal, a timed file): opened where the C reader opens it.
        if (cReaderAccepts(path.join(regressions, f))) readPal(bytes, { name: f, verifyChecksum: true, decompress });
        else assertRefused(() => readPal(bytes, { name: f, verifyChecksum: true, decompress }), f, f), ++refused;
    }
    assert.ok(refused >= 8);
});

test('truncations at every 64-byte boundary are refused', () => {
    for (const source of ['quadruped-qpos-u16.pal', `zstd-${path.basename(FOX)}.pal`]) {
        const bytes = readFileSync(path.join(dir, source));
        for (let end = 0; end < bytes.length; end += 64)
            assertRefused(() => readPal(bytes.subarray(0, end), { name: 't.pal', decompress }), 't.pal', `${source} cut at ${end}`);
    }
});

// Every header field (offset, byte width) and hostile values for it.
const U32 = [0, 1, 3, 0x7fffffff, 0x80000000, 0xffffffff];
const U64 = [0n, 1n, 255n, 4097n, 0x7fffffffffffffffn, 0x8000000000000000n, 0xffffffffffffffffn];
const FIELDS = [
    ['magic', 0, 8], ['version', 8, 4], ['flags', 12, 4], ['header_size', 16, 4], ['layout', 20, 4],
    ['precision', 24, 4], ['texels_per_bone', 28, 4], ['bone_count', 32, 4], ['row_texels', 36, 4], ['rows', 40, 4],
    ['width', 44, 4], ['height', 48, 4], ['blocks', 52, 4], ['texel_bytes', 56, 4], ['clip_count', 60, 4],
    ['fps', 64, 4], ['speed_reference', 68, 4], ['linear_range', 72, 4], ['bounds_min', 76, 4], ['bounds_max', 88, 4],
    ['max_error', 100, 4], ['model_height', 104, 4], ['visible_error', 108, 4], ['input_hash', 112, 8],
    ['clip_table_offset', 120, 8], ['bone_table_offset', 128, 8], ['strings_offset', 136, 8], ['strings_size', 144, 8],
    ['payload_offset', 152, 8], ['payload_size', 160, 8], ['payload_raw_size', 168, 8], ['checksum', 176, 8],
];

// The checked fields of the first and last clip and bone table entries (read from the source's header).
function tableFields(source) {
    const view = new DataView(source.buffer, source.byteOffset, source.byteLength);
    const clips = Number(view.getBigUint64(120, true)), bones = Number(view.getBigUint64(128, true));
    const last = (count, size) => (count - 1) * size;
    const out = [];
    for (const [table, base, count, size, fields] of [
        ['clip', clips, view.getUint32(60, true), 80, [['name', 0], ['name length', 4], ['first_row', 8], ['frames', 12]]],
        ['bone', bones, view.getUint32(32, true), 32, [['name', 0], ['name length', 4], ['parent', 8]]]])
        for (const at of [0, last(count, size)])
            for (const [field, offset] of fields) out.push([`${table} entry at byte ${base + at}: ${field}`, base + at + offset, 4]);
    return out;
}

test('single-field corruptions of every header field and table entry: refused exactly when the C reader refuses them', () => {
    const source = readFileSync(path.join(dir, 'quadruped-qpos-u16.pal'));
    const file = path.join(dir, 'corrupt.pal');
    let refusedByBoth = 0;
    for (const [field, offset, width] of [...FIELDS, ...tableFields(source)]) {
        const values = width === 8 ? U64 : U32;
        for (const value of values) {
            const bytes = new Uint8Array(source);
            const view = new DataView(bytes.buffer);
            if (width === 8) view.setBigUint64(offset, value, true);
            else view.setUint32(offset, value, true);
            if (Buffer.from(bytes).equals(source)) continue;
            const what = `${field} (byte ${offset}) = ${value}`;
            // With the checksum verified, every change is refused.
            assertRefused(() => readPal(bytes, { name: 'c.pal', verifyChecksum: true }), 'c.pal', what);
            // Without it, the structural checks are the C reader's.
            writeFileSync(file, bytes);
            const cAccepts = cReaderAccepts(file);
            let jsAccepts = true;
            try {
                readPal(bytes, { name: 'c.pal' });
            } catch (e) {
                assert.equal(e.constructor, Error, `${what}: ${e.constructor.name}: ${e.message}`);
                jsAccepts = false;
            }
            assert.equal(jsAccepts, cAccepts, `${what}: the web reader ${jsAccepts ? 'accepts' : 'refuses'}, the C reader does not`);
            if (!cAccepts) ++refusedByBoth;
        }
    }
    assert.ok(refusedByBoth > 100, `${refusedByBoth} structural corruptions refused`);
});

test('rows that would fit in fewer column blocks are refused (geometry), as by the C reader', () => {
    // The wrapped bake (2 blocks of 133 rows for 265 rows) made 265 rows high: one block would hold them all.
    const source = readFileSync(path.join(dir, 'wrapped.pal'));
    const h = readPal(source).header;
    const raw = BigInt(h.width * 265 * h.texel_bytes);
    const bytes = new Uint8Array(h.payload_offset + Number(raw));
    bytes.set(source);
    const view = new DataView(bytes.buffer);
    view.setUint32(48, 265, true);
    view.setBigUint64(160, raw, true);
    view.setBigUint64(168, raw, true);
    const file = path.join(dir, 'too-many-blocks.pal');
    writeFileSync(file, bytes);
    assert.equal(cReaderAccepts(file), false);
    assert.match(assertRefused(() => readPal(bytes, { name: 'b.pal' }), 'b.pal', 'blocks'), /inconsistent texture geometry/);
    view.setUint32(52, 1, true); // one block, twice as wide rows: the width check then refuses it
    assertRefused(() => readPal(bytes, { name: 'b.pal' }), 'b.pal', 'width');
});

test('anything but bytes is refused with an Error', () => {
    assertRefused(() => readPal('CBPAL', { name: 's.pal' }), 's.pal', 'a string');
    assertRefused(() => readPal(null, { name: 's.pal' }), 's.pal', 'null');
});
