// crowdbake_pal.mjs - reader for crowdbake .pal bone-matrix palettes and the roster manifest.
// An ES module with no third-party dependencies (beside it: crowdbake_pose.mjs, crowdbake_xxh64.mjs), for browsers
// and Node. Public domain / MIT-0.
//
//     import { readPal, readRoster } from './crowdbake_pal.mjs';
//     const pal = readPal(new Uint8Array(await (await fetch('goat.pal')).arrayBuffer()),
//                         { name: 'goat.pal', verifyChecksum: true });
//     gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA16UI, pal.header.width, pal.header.height, 0,
//                   gl.RGBA_INTEGER, gl.UNSIGNED_SHORT, pal.texels);
//
// It makes exactly the checks of the C reader include/crowdbake_pal.h (the format is specified in
// docs/pal-format.md): every size and offset is checked against the file length before it is used,
// so hostile bytes give an Error with a one-line message naming the file, the field and its byte
// offset, never an out-of-range read or an allocation the file asks for.
//
// zstd payloads (bake --zstd) are decoded by a function the caller passes as options.decompress
// (bytes, rawSize) -> Uint8Array, e.g. `decompress: (b, n) => fzstd.decompress(b, new Uint8Array(n))`
// with the npm package fzstd: this module stays dependency-free, and runtimes that never load
// compressed palettes ship no decoder. Without one, such a file is refused with the fix.

export const PAL_VERSION = 7; // newest known; writers write the oldest version that holds what a file says
export const HEADER_SIZE = 256;
export const CLIP_SIZE = 80;
export const BONE_SIZE = 32;
export const PAYLOAD_ALIGN = 4096;
export const CHECKSUM_OFFSET = 176;

export const LAYOUTS = ['mat4', 'affine', 'qpos'];
export const PRECISIONS = ['float', 'half', 'u16'];
export const FLAG_ZSTD = 1;
export const FLAG_IN_PLACE = 2;
// versions 2 and 3: qpos positions are stored less the bone's position_offset (version 3: its offset table; version 2:
// the bind position)
export const FLAG_POSITIONS_RELATIVE = 4;
export const FLAG_FITTED_ROWS = 8; // every clip's rows fitted to the linear blend between them, not sampled
// Version 5: a per-row travel offset table (header byte 192, one f32 a row): an instance moved at its clip's ground
// speed is drawn at its position plus travelOffset (the planted feet then stay still). Files without it read 0.
export const FLAG_ROW_TRAVEL = 16;
// Version 6: local rows (docs/pal-format.md): row r of bone j holds its transform in its parent's frame (qpos, u16 or
// float), and a bone range table (header byte 200, 32 bytes a bone) gives each bone's u16 position box and scale.
// Runtimes blend each bone's rows, then compose from the root (crowdbake_pose.mjs).
export const FLAG_LOCAL_ROWS = 32;
export const BONE_RANGE_SIZE = 32;
export const CLIP_LOOPS = 1;
export const CLIP_FITTED = 2; // this clip's rows fitted to the linear blend (before it: header flag bit 3, every clip)
// Version 4: this clip's rows are held, not blended (a STEP-keyed clip baked at its key times): the row at or before
// the time alone. Its instance numbers say so with a negative first row, -first_row - 1 (instanceFirstRow).
export const CLIP_STEP = 4;
// Version 7: timed rows (docs/pal-format.md "Timed rows"): a timed clip's rows lie on cells of a grid, and its map (one
// texel a cell, in the rows just before its first) says which two rows each cell blends and with what weight. The
// timed clip table (header byte 208, 16 bytes a clip) gives each clip's cells, cell_rate and map_rows. Its instance
// numbers say so with a negative rate (clipInstance); instanceFrame reads the map.
export const FLAG_TIMED_ROWS = 64;
export const CLIP_TIMED = 8;
export const TIMED_CLIP_SIZE = 16;

import { xxh64 } from './crowdbake_xxh64.mjs';
import { texelIndex, timedMapTexel } from './crowdbake_pose.mjs';

export { xxh64 } from './crowdbake_xxh64.mjs';
export { texelIndex, hasLocalRows, hasTimedRows, instanceFirstRow, clipInstance, instanceFrame, timedMapTexel,
         instanceBoneMatrix, instanceBoneMatrixCrossfade, boneMatrix, rowBoneMatrix } from './crowdbake_pose.mjs';

const MAGIC = [0x43, 0x42, 0x50, 0x41, 0x4c, 0x0d, 0x0a, 0x1a]; // "CBPAL\r\n\x1a"
const TEXELS_PER_BONE = [4, 3, 2]; // by layout
const TEXEL_BYTES = [16, 8, 8]; // by precision
// Decompressed payloads larger than this are refused unless the caller raises it: the size comes
// from the file, so a hostile file must not choose how much memory the reader asks for.
const DEFAULT_MAX_DECOMPRESSED_BYTES = 1 << 30;
// Typed arrays use the host's byte order; the texels are little-endian, as on every engine in use.
const HOST_IS_LITTLE_ENDIAN = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

// ---- .pal ----

function asBytes(data, where) {
    if (data instanceof Uint8Array) return data;
    if (data instanceof ArrayBuffer) return new Uint8Array(data);
    if (ArrayBuffer.isView(data)) return new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    throw new Error(`${where}: expected an ArrayBuffer or Uint8Array, got ${data === null ? 'null' : typeof data}`);
}

// begin + count * size <= limit, on BigInt so no u64 field can wrap.
const fits = (begin, count, size, limit) => begin <= limit && BigInt(count) * BigInt(size) <= limit - begin;

// The header fields, named as in docs/pal-format.md; u64 fields as BigInt until validated.
function parseHeader(view) {
    const u32 = (o) => view.getUint32(o, true);
    const f32 = (o) => view.getFloat32(o, true);
    const u64 = (o) => view.getBigUint64(o, true);
    const vec3 = (o) => [f32(o), f32(o + 4), f32(o + 8)];
    return {
        version: u32(8), flags: u32(12), header_size: u32(16), layout: u32(20), precision: u32(24),
        texels_per_bone: u32(28), bone_count: u32(32), row_texels: u32(36), rows: u32(40), width: u32(44),
        height: u32(48), blocks: u32(52), texel_bytes: u32(56), clip_count: u32(60),
        fps: f32(64), speed_reference: f32(68), linear_range: f32(72), bounds_min: vec3(76), bounds_max: vec3(88),
        max_error: f32(100), model_height: f32(104), visible_error: f32(108),
        input_hash: u64(112), clip_table_offset: u64(120), bone_table_offset: u64(128), strings_offset: u64(136),
        strings_size: u64(144), payload_offset: u64(152), payload_size: u64(160), payload_raw_size: u64(168),
        checksum: u64(176), offset_table_offset: u32(8) >= 3 ? u64(184) : 0n,
        travel_table_offset: u32(8) >= 5 && (u32(12) & FLAG_ROW_TRAVEL) ? u64(192) : 0n,
        range_table_offset: u32(8) >= 6 && (u32(12) & FLAG_LOCAL_ROWS) ? u64(200) : 0n,
        timed_table_offset: u32(8) >= 7 && (u32(12) & FLAG_TIMED_ROWS) ? u64(208) : 0n,
    };
}

// A name's bytes [off, off + len) and its NUL lie inside the string table (as the C reader checks).
function readName(bytes, view, h, entry) {
    const off = view.getUint32(entry, true), len = view.getUint32(entry + 4, true);
    const strings = Number(h.strings_offset), size = Number(h.strings_size);
    if (off + len >= size || bytes[strings + off + len] !== 0) return null;
    return new TextDecoder('utf-8').decode(bytes.subarray(strings + off, strings + off + len));
}

function validateHeader(bytes, view, fail) {
    const size = bytes.length, n = BigInt(size);
    if (size < 8 || MAGIC.some((m, i) => bytes[i] !== m))
        fail('not a crowdbake palette (wrong magic at byte 0; expected "CBPAL\\r\\n\\x1a")');
    if (size < 12) fail(`truncated: ${size} bytes, shorter than the ${HEADER_SIZE}-byte header`);
    const version = view.getUint32(8, true);
    if (version > PAL_VERSION)
        fail(`palette format version ${version} (byte 8) is newer than this reader (version ${PAL_VERSION}); update the reader`);
    if (version < 1) fail(`unknown palette format version ${version} (byte 8)`);
    if (size < HEADER_SIZE) fail(`truncated: ${size} bytes, shorter than the ${HEADER_SIZE}-byte header`);
    const h = parseHeader(view);
    if (h.header_size !== HEADER_SIZE) fail(`bad header_size ${h.header_size} (byte 16), expected ${HEADER_SIZE}`);
    if (h.layout > 2 || h.precision > 2)
        fail(`unknown layout ${h.layout} (byte 20) or precision ${h.precision} (byte 24)`);
    if (h.texels_per_bone !== TEXELS_PER_BONE[h.layout] || h.texel_bytes !== TEXEL_BYTES[h.precision])
        fail(`texels_per_bone ${h.texels_per_bone} (byte 28) or texel_bytes ${h.texel_bytes} (byte 56) do not match ` +
             `layout ${LAYOUTS[h.layout]} and precision ${PRECISIONS[h.precision]}`);
    const B = BigInt;
    if (h.bone_count === 0 || B(h.bone_count) * B(h.texels_per_bone) !== B(h.row_texels) || h.blocks === 0 ||
        B(h.blocks) * B(h.row_texels) !== B(h.width) || h.height === 0 || B(h.height) * B(h.blocks) < B(h.rows) ||
        B(h.blocks - 1) * B(h.height) >= B(h.rows) ||
        B(h.width) * B(h.height) * B(h.texel_bytes) !== h.payload_raw_size)
        fail(`inconsistent texture geometry (bytes 32-56, 168: ${h.bone_count} bones, ${h.row_texels} texels a row, ` +
             `${h.rows} rows, ${h.width}x${h.height} in ${h.blocks} blocks, payload_raw_size ${h.payload_raw_size})`);
    if (!fits(h.clip_table_offset, h.clip_count, CLIP_SIZE, n) || h.clip_table_offset < B(HEADER_SIZE))
        fail(`clip table (clip_table_offset ${h.clip_table_offset} at byte 120, ${h.clip_count} clips at byte 60) ` +
             `lies outside the ${size}-byte file`);
    if (!fits(h.bone_table_offset, h.bone_count, BONE_SIZE, n) || h.bone_table_offset < B(HEADER_SIZE))
        fail(`bone table (bone_table_offset ${h.bone_table_offset} at byte 128, ${h.bone_count} bones) ` +
             `lies outside the ${size}-byte file`);
    if (h.version >= 3 && (h.flags & FLAG_POSITIONS_RELATIVE) &&
        (!fits(h.offset_table_offset, h.bone_count, 12, n) || h.offset_table_offset < B(HEADER_SIZE)))
        fail(`position offset table (offset_table_offset ${h.offset_table_offset} at byte 184, ${h.bone_count} bones) ` +
             `lies outside the ${size}-byte file`);
    if (h.version >= 5 && (h.flags & FLAG_ROW_TRAVEL) &&
        (!fits(h.travel_table_offset, h.rows, 4, n) || h.travel_table_offset < B(HEADER_SIZE)))
        fail(`travel offset table (travel_table_offset ${h.travel_table_offset} at byte 192, ${h.rows} rows) ` +
             `lies outside the ${size}-byte file`);
    const local = (h.flags & FLAG_LOCAL_ROWS) !== 0;
    if (local && h.version < 6) fail(`flags bit 5 (local rows, byte 12) in a version ${h.version} file; local rows are version 6`);
    if (local && (!fits(h.range_table_offset, h.bone_count, BONE_RANGE_SIZE, n) ||
                  h.range_table_offset < B(HEADER_SIZE) || h.range_table_offset % 4n !== 0n))
        fail(`bone range table (range_table_offset ${h.range_table_offset} at byte 200, ${h.bone_count} bones) ` +
             `lies outside the ${size}-byte file`);
    if (local && (h.layout !== 2 || h.precision === 1 || h.flags & FLAG_POSITIONS_RELATIVE))
        fail(`local rows (flags bit 5, byte 12) with layout ${LAYOUTS[h.layout]} and precision ${PRECISIONS[h.precision]}` +
             `${h.flags & FLAG_POSITIONS_RELATIVE ? ' and relative positions' : ''}: local rows need qpos and u16 or float`);
    const timed = (h.flags & FLAG_TIMED_ROWS) !== 0;
    if (timed && h.version < 7) fail(`flags bit 6 (timed rows, byte 12) in a version ${h.version} file; timed rows are version 7`);
    if (timed && (!fits(h.timed_table_offset, h.clip_count, TIMED_CLIP_SIZE, n) ||
                  h.timed_table_offset < B(HEADER_SIZE) || h.timed_table_offset % 4n !== 0n))
        fail(`timed clip table (timed_table_offset ${h.timed_table_offset} at byte 208, ${h.clip_count} clips) ` +
             `lies outside the ${size}-byte file`);
    if (!fits(h.strings_offset, h.strings_size, 1, n) || h.strings_offset < B(HEADER_SIZE))
        fail(`string table (strings_offset ${h.strings_offset} at byte 136, strings_size ${h.strings_size} at byte 144) ` +
             `lies outside the ${size}-byte file`);
    if (h.payload_offset % B(PAYLOAD_ALIGN) !== 0n || !fits(h.payload_offset, h.payload_size, 1, n) ||
        h.payload_offset < B(HEADER_SIZE))
        fail(`truncated or bad payload: payload_offset ${h.payload_offset} (byte 152) + payload_size ` +
             `${h.payload_size} (byte 160) bytes, the file has ${size}`);
    if (!(h.flags & FLAG_ZSTD) && h.payload_size !== h.payload_raw_size)
        fail(`payload_size ${h.payload_size} (byte 160) is not the ${h.payload_raw_size} bytes the texture needs`);
    // Every offset and size now lies inside the file: exact as Numbers.
    for (const k of ['clip_table_offset', 'bone_table_offset', 'strings_offset', 'strings_size', 'payload_offset',
                     'payload_size', 'offset_table_offset', 'travel_table_offset', 'range_table_offset', 'timed_table_offset'])
        h[k] = Number(h[k]);
    return h;
}

function readClips(bytes, view, h, fail) {
    const clips = [];
    for (let i = 0; i < h.clip_count; ++i) {
        const c = h.clip_table_offset + i * CLIP_SIZE;
        const f32 = (o) => view.getFloat32(c + o, true);
        const first_row = view.getUint32(c + 8, true), frames = view.getUint32(c + 12, true);
        const name = readName(bytes, view, h, c);
        if (name === null || frames === 0 || first_row > h.rows || frames > h.rows - first_row)
            fail(`clip ${i} (byte ${c}) has a bad name or rows ${first_row}..${first_row + frames} outside the ${h.rows} rows`);
        const flags = view.getUint32(c + 28, true);
        clips.push({
            name, first_row, frames, fps: f32(16), duration: f32(20), start: f32(24), flags,
            loops: (flags & CLIP_LOOPS) !== 0,
            fitted: (flags & CLIP_FITTED) !== 0 || (h.flags & FLAG_FITTED_ROWS) !== 0,
            step: (flags & CLIP_STEP) !== 0,
            root_velocity: [f32(32), f32(36), f32(40)],
            bounds_min: [f32(44), f32(48), f32(52)], bounds_max: [f32(56), f32(60), f32(64)],
            // version 5: the direction its rows' travel offsets lie along (0 where it has none)
            travel_heading: h.travel_table_offset ? [f32(68), f32(72), f32(76)] : [0, 0, 0],
            ...readTimed(view, h, i, flags, first_row, fail),
        });
    }
    return clips;
}

// A clip's entry in the timed clip table (version 7): { timed, cells, cell_rate, map_rows }, all 0 for an untimed
// clip. Checked as docs/pal-format.md says: clip flag bit 3 exactly when the entry is not all 0, cells >= 1, cell_rate
// > 0 and finite, map_rows = ceil(cells / row_texels), at most first_row (the map lies before the clip's rows),
// reserved 0 (as the C reader, include/crowdbake_pal.h).
function readTimed(view, h, i, flags, first_row, fail) {
    const timed = (flags & CLIP_TIMED) !== 0;
    if (!h.timed_table_offset) {
        if (timed) fail(`clip ${i} (byte ${h.clip_table_offset + i * CLIP_SIZE}) is timed (clip flag bit 3) in a file ` +
                        'without timed rows (header flags bit 6, byte 12)');
        return { timed: false, cells: 0, cell_rate: 0, map_rows: 0 };
    }
    const at = h.timed_table_offset + i * TIMED_CLIP_SIZE, u32 = (o) => view.getUint32(at + o, true);
    const cells = u32(0), cell_rate = view.getFloat32(at + 4, true), map_rows = u32(8);
    const zero = cells === 0 && u32(4) === 0 && map_rows === 0 && u32(12) === 0;
    if (!timed) {
        if (!zero) fail(`timed clip entry ${i} (byte ${at}) is not all 0 for a clip without clip flag bit 3 (timed)`);
        return { timed: false, cells: 0, cell_rate: 0, map_rows: 0 };
    }
    if (cells < 1 || !(cell_rate > 0) || !Number.isFinite(cell_rate) || map_rows !== Math.ceil(cells / h.row_texels) ||
        map_rows > first_row || u32(12) !== 0)
        fail(`timed clip entry ${i} (byte ${at}): cells ${cells}, cell_rate ${cell_rate}, map_rows ${map_rows}, reserved ` +
             `${u32(12)} with ${h.row_texels} texels a row and first row ${first_row}: needs cells >= 1, cell_rate > 0 and ` +
             'finite, map_rows = ceil(cells / row_texels) <= first row, reserved 0');
    return { timed: true, cells, cell_rate, map_rows };
}

// Every timed clip's map texel: rows whole and below its clip's rows, weights within [0, 1], f0 <= f1 (once the texels
// are in hand).
function checkMaps(pal, fail) {
    pal.clips.forEach((c, i) => {
        if (!c.timed) return;
        for (let cell = 0; cell < c.cells; ++cell) {
            const [r0, r1, f0, f1] = timedMapTexel(pal, c.first_row, c.cells, cell);
            const row = (r) => Number.isInteger(r) && r >= 0 && r < c.frames;
            if (!(row(r0) && row(r1) && f0 >= 0 && f0 <= f1 && f1 <= 1))
                fail(`clip ${i} (${c.name}): map texel of cell ${cell} (row ${c.first_row - c.map_rows + Math.floor(cell / pal.header.row_texels)}) ` +
                     `holds rows ${r0}, ${r1} and weights ${f0}, ${f1}: needs whole rows below its ${c.frames} and 0 <= f0 <= f1 <= 1`);
        }
    });
}

function readBones(bytes, view, h, fail) {
    const bones = [];
    for (let i = 0; i < h.bone_count; ++i) {
        const b = h.bone_table_offset + i * BONE_SIZE;
        const parent = view.getInt32(b + 8, true);
        const name = readName(bytes, view, h, b);
        if (name === null || parent < -1 || parent >= h.bone_count)
            fail(`bone ${i} (byte ${b}) has a bad name or parent ${parent}`);
        const bind_position = [0, 4, 8].map((o) => view.getFloat32(b + 16 + o, true));
        // What CB_POSITIONS_RELATIVE adds to a qpos position texel (0 without the flag).
        const relative = (h.flags & FLAG_POSITIONS_RELATIVE) !== 0;
        const position_offset = !relative ? [0, 0, 0] : h.version >= 3
            ? [0, 4, 8].map((o) => view.getFloat32(h.offset_table_offset + i * 12 + o, true)) : bind_position.slice();
        bones.push({ name, parent, bind_position, position_offset });
        if (h.range_table_offset) bones[i].range = readRange(view, h.range_table_offset + i * BONE_RANGE_SIZE, i, fail);
    }
    if (h.range_table_offset) checkChains(bones, h, fail);
    return bones;
}

// A bone's entry in the range table (version 6, local rows): the box of its stored positions and its largest scale,
// what its u16 texels decode into (written for float files too).
function readRange(view, at, bone, fail) {
    const f32 = (o) => view.getFloat32(at + o, true);
    const range = { pos_min: [f32(0), f32(4), f32(8)], scale_max: f32(12), pos_max: [f32(16), f32(20), f32(24)] };
    const finite = [...range.pos_min, ...range.pos_max, range.scale_max].every(Number.isFinite);
    if (!finite || range.pos_min.some((v, k) => v > range.pos_max[k]) || !(range.scale_max > 0) || view.getUint32(at + 28, true))
        fail(`bone range ${bone} (byte ${at}) is not finite, has a min above its max, a scale_max <= 0 or a non-zero ` +
             'reserved word');
    return range;
}

// Local rows compose each bone under its parent: every chain must reach a root (a loop would never end).
function checkChains(bones, h, fail) {
    for (let i = 0; i < bones.length; ++i) {
        let j = i, steps = 0;
        for (; j >= 0 && steps <= bones.length; ++steps) j = bones[j].parent;
        if (j >= 0) fail(`bone ${i} (byte ${h.bone_table_offset + i * BONE_SIZE}): its parents loop, and local rows ` +
                         'compose each bone under its parent');
    }
}

function checksumOf(bytes, end) {
    return xxh64([bytes.subarray(0, CHECKSUM_OFFSET), new Uint8Array(8), bytes.subarray(CHECKSUM_OFFSET + 8, end)]);
}

function decodePayload(bytes, h, options, fail) {
    const payload = bytes.subarray(h.payload_offset, h.payload_offset + h.payload_size);
    if (!(h.flags & FLAG_ZSTD)) return payload;
    if (typeof options.decompress !== 'function')
        fail('payload is zstd-compressed (flags bit 0, byte 12); bake without --zstd, or pass options.decompress ' +
             '(e.g. fzstd\'s decompress)');
    const limit = options.maxDecompressedBytes ?? DEFAULT_MAX_DECOMPRESSED_BYTES;
    if (h.payload_raw_size > BigInt(limit))
        fail(`payload_raw_size ${h.payload_raw_size} (byte 168) is over the ${limit}-byte limit for decompression ` +
             '(options.maxDecompressedBytes)');
    const rawSize = Number(h.payload_raw_size);
    let out;
    try {
        out = options.decompress(payload, rawSize);
    } catch (e) {
        fail(`compressed payload (byte ${h.payload_offset}) does not decompress: ${String(e?.message ?? e).split('\n')[0]}`);
    }
    if (!(out instanceof Uint8Array) || out.length !== rawSize)
        fail(`compressed payload (byte ${h.payload_offset}) does not decompress to ${rawSize} bytes`);
    return out;
}

// Texel components as the GPU takes them: Float32Array for float, Uint16Array for half and u16.
function texelView(raw, precision) {
    const Type = precision === 0 ? Float32Array : Uint16Array;
    if (raw.byteOffset % Type.BYTES_PER_ELEMENT !== 0) raw = raw.slice(); // a caller's unaligned view: copy
    return new Type(raw.buffer, raw.byteOffset, raw.byteLength / Type.BYTES_PER_ELEMENT);
}

// Parses a .pal held in `data` (ArrayBuffer or Uint8Array; kept, not copied: the texels are a view
// into it). options: name (for messages), verifyChecksum, decompress, maxDecompressedBytes.
// Returns { header, clips, bones, texels, texelBytes, rowTravel }: header has the fields of docs/pal-format.md
// by name (input_hash and checksum as BigInt) plus layout_name and precision_name; clips and bones
// what cbpal_get_clip / cbpal_get_bone give (and loops); texelBytes the payload's raw bytes.
// rowTravel: version 5's travel offsets (Float32Array, one a row) or null (crowdbake_travel.mjs).
// Local rows (version 6, hasLocalRows(header)): each bone also has `range` { pos_min, pos_max, scale_max }, its entry of
// the bone range table (u16 decodes with it), and boneMatrix composes each bone down its chain (crowdbake_pose.mjs).
// Timed rows (version 7, hasTimedRows(header)): every clip has timed, cells, cell_rate and map_rows (0 untimed), its
// map checked; clipInstance gives its instance numbers and instanceFrame reads its map.
// Beyond the C reader's checks: a zstd payload over options.maxDecompressedBytes (1 GiB) is refused,
// and one whose checksum does not match is refused before it is decoded, verifyChecksum or not.
export function readPal(data, options = {}) {
    const name = options.name ?? 'palette';
    const fail = (message) => { throw new Error(`${name}: ${message}`); };
    if (!HOST_IS_LITTLE_ENDIAN) fail('this reader needs a little-endian host (the texels are little-endian)');
    const bytes = asBytes(data, name);
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const h = validateHeader(bytes, view, fail);
    const clips = readClips(bytes, view, h, fail);
    const bones = readBones(bytes, view, h, fail);
    // A zstd payload is checked whatever options.verifyChecksum says: a decoder in JavaScript trusts
    // its frame (fzstd 0.1.1 spends 13 s on a damaged 5 KB one, copying sequences past its output's
    // end), and the compressed bytes are few.
    if ((options.verifyChecksum || (h.flags & FLAG_ZSTD)) && checksumOf(bytes, h.payload_offset + h.payload_size) !== h.checksum)
        fail(`checksum mismatch (checksum at byte ${CHECKSUM_OFFSET}): the file is corrupted` +
             (options.verifyChecksum ? '' : ' (a compressed payload is always checked before it is decoded)'));
    const texelBytes = decodePayload(bytes, h, options, fail);
    h.payload_raw_size = Number(h.payload_raw_size); // now the length of a buffer in hand
    h.layout_name = LAYOUTS[h.layout];
    h.precision_name = PRECISIONS[h.precision];
    const at = h.travel_table_offset; // copied: a Node Buffer's slice is a view into a shared pool
    const rowTravel = at ? new Float32Array(new Uint8Array(bytes.subarray(at, at + 4 * h.rows)).buffer) : null;
    const pal = { header: h, clips, bones, texelBytes, texels: texelView(texelBytes, h.precision), rowTravel };
    checkMaps(pal, fail);
    return pal;
}


// ---- roster.json (docs/roster.md, docs/roster.schema.json) ----

// Parses a roster manifest (its text, or the object JSON.parse made) and checks what a runtime
// uses. Returns { generator, catalog, types: { NAME: { palette, palette_exr, shares_palette_of,
// layout, precision, bones, rows, width, height, blocks, speed_reference, default_state, clips (with contacts),
// states: { STATE: { clip, first_row, frame_count, rate, rate_per_speed, phase } }, lods, sockets, animation_lod } },
// failed }.
// Paths stay relative to the manifest's directory.
export function readRoster(json, options = {}) {
    const name = options.name ?? 'roster.json';
    const fail = (where, message) => { throw new Error(`${name}: ${where}: ${message}`); };
    let doc = json;
    if (typeof json === 'string') {
        try {
            doc = JSON.parse(json);
        } catch (e) {
            throw new Error(`${name}: not JSON: ${String(e?.message ?? e).split('\n')[0]}`);
        }
    }
    const isObject = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);
    // Names come from the file: "constructor" or "toString" must not find Object.prototype's members, and
    // "__proto__" must be a name like any other, not the object's prototype.
    const has = (obj, key) => Object.prototype.hasOwnProperty.call(obj, key);
    const put = (obj, key, value) => Object.defineProperty(obj, key, { value, enumerable: true, writable: true, configurable: true });
    const need = (obj, where, key, check, what) => {
        if (!isObject(obj)) fail(where, 'expected an object');
        if (!has(obj, key)) fail(`${where}.${key}`, `missing (${what})`);
        if (!check(obj[key])) fail(`${where}.${key}`, `expected ${what}, got ${JSON.stringify(obj[key])}`);
        return obj[key];
    };
    const optional = (obj, where, key, check, what) => (has(obj, key) ? need(obj, where, key, check, what) : undefined);
    const isString = (v) => typeof v === 'string';
    const isCount = (v) => Number.isInteger(v) && v >= 1;
    const isIndex = (v) => Number.isInteger(v) && v >= 0;
    const isNonNegative = (v) => typeof v === 'number' && Number.isFinite(v) && v >= 0;
    const isNumber = (v) => typeof v === 'number' && Number.isFinite(v);
    const timedRows = (t, where) => t && {
        cells: need(t, where, 'cells', isCount, 'an integer >= 1'),
        cell_rate: need(t, where, 'cell_rate', (v) => isNumber(v) && v > 0, 'a number > 0'),
        map_rows: need(t, where, 'map_rows', isCount, 'an integer >= 1'),
    };

    if (!isObject(doc)) fail('top level', 'expected an object');
    const schema = need(doc, 'top level', 'schema', isString, 'a string');
    if (schema !== 'crowdbake-roster/1')
        fail('schema', `"${schema}" is not crowdbake-roster/1; update the reader or re-bake with a matching crowdbake`);
    const types = need(doc, 'top level', 'types', isObject, 'an object');
    const out = {
        generator: need(doc, 'top level', 'generator', isString, 'a string'),
        catalog: need(doc, 'top level', 'catalog', isString, 'a string'),
        types: {}, failed: {},
    };
    for (const [typeName, t] of Object.entries(types)) {
        const at = `types.${typeName}`;
        if (!isObject(t)) fail(at, 'expected an object');
        const type = {
            model: need(t, at, 'model', isString, 'a string'),
            palette: optional(t, at, 'palette', isString, 'a string'),
            palette_exr: optional(t, at, 'palette_exr', isString, 'a string'),
            shares_palette_of: optional(t, at, 'shares_palette_of', isString, 'a string'),
            layout: need(t, at, 'layout', (v) => LAYOUTS.includes(v), `one of ${LAYOUTS.join(', ')}`),
            precision: need(t, at, 'precision', (v) => PRECISIONS.includes(v), `one of ${PRECISIONS.join(', ')}`),
            bones: need(t, at, 'bones', isCount, 'an integer >= 1'),
            texels_per_bone: need(t, at, 'texels_per_bone', (v) => [2, 3, 4].includes(v), '2, 3 or 4'),
            rows: need(t, at, 'rows', isCount, 'an integer >= 1'),
            width: need(t, at, 'width', isCount, 'an integer >= 1'),
            height: need(t, at, 'height', isCount, 'an integer >= 1'),
            blocks: need(t, at, 'blocks', isCount, 'an integer >= 1'),
            speed_reference: need(t, at, 'speed_reference', isNonNegative, 'a number >= 0'),
            default_state: need(t, at, 'default_state', isString, 'a string'),
            clips: [], states: {}, lods: [], sockets: [],
        };
        if (type.palette === undefined && type.palette_exr === undefined)
            fail(at, 'has neither palette nor palette_exr');
        need(t, at, 'clips', Array.isArray, 'an array').forEach((c, i) => {
            const w = `${at}.clips[${i}]`;
            type.clips.push({
                name: need(c, w, 'name', isString, 'a string'),
                first_row: need(c, w, 'first_row', isIndex, 'an integer >= 0'),
                frame_count: need(c, w, 'frame_count', isCount, 'an integer >= 1'),
                step_rows: optional(c, w, 'step_rows', (v) => typeof v === 'boolean', 'true or false') ?? false,
                // Timed rows (.pal version 7; older manifests: none): its map's cells, their rate and its map rows.
                timed_rows: timedRows(optional(c, w, 'timed_rows', isObject, 'an object'), `${w}.timed_rows`),
                fps: need(c, w, 'fps', (v) => typeof v === 'number' && v > 0, 'a number > 0'),
                duration: need(c, w, 'duration', isNonNegative, 'a number >= 0'),
                loops: need(c, w, 'loops', (v) => typeof v === 'boolean', 'true or false'),
                ground_speed: need(c, w, 'ground_speed', isNonNegative, 'a number >= 0'),
                // Footsteps (older manifests: none): when each foot lands (time) and lifts, seconds into the clip.
                contacts: (optional(c, w, 'contacts', Array.isArray, 'an array') ?? []).map((k, j) => ({
                    foot: need(k, `${w}.contacts[${j}]`, 'foot', isString, 'a string'),
                    bone: need(k, `${w}.contacts[${j}]`, 'bone', (v) => isIndex(v) && v < type.bones, `a bone index below ${type.bones}`),
                    time: need(k, `${w}.contacts[${j}]`, 'time', isNonNegative, 'a number >= 0'),
                    lift: need(k, `${w}.contacts[${j}]`, 'lift', isNonNegative, 'a number >= 0'),
                })),
            });
            const last = type.clips[i];
            if (last.first_row + last.frame_count > type.rows)
                fail(w, `rows ${last.first_row}..${last.first_row + last.frame_count} outside the type's ${type.rows} rows`);
        });
        for (const [stateName, s] of Object.entries(need(t, at, 'states', isObject, 'an object'))) {
            const w = `${at}.states.${stateName}`;
            const clip = need(s, w, 'clip', isString, 'a string');
            if (!type.clips.some((c) => c.name === clip)) fail(`${w}.clip`, `"${clip}" is not one of the type's clips`);
            const inst = need(s, w, 'instance', isObject, 'an object');
            const wi = `${w}.instance`;
            const state = {
                clip,
                // < 0: held rows (a STEP-keyed clip), the first -first_row - 1
                first_row: need(inst, wi, 'first_row', Number.isInteger, 'an integer'),
                frame_count: need(inst, wi, 'frame_count', (v) => Number.isInteger(v) && v !== 0, 'a non-zero integer'),
                // < 0: a timed clip (its cells per second, and per unit of speed, negated: docs/roster.md)
                rate: need(inst, wi, 'rate', isNumber, 'a number'),
                rate_per_speed: need(inst, wi, 'rate_per_speed', isNumber, 'a number'),
                phase: need(inst, wi, 'phase', (v) => v === 'golden_ratio' || v === 'zero', '"golden_ratio" or "zero"'),
            };
            const timed = type.clips.find((c) => c.name === clip).timed_rows;
            if ((state.rate < 0) !== (timed !== undefined) || state.rate_per_speed * state.rate < 0)
                fail(`${wi}.rate`, timed ? `clip "${clip}" has timed rows: rate and rate_per_speed must be negative`
                                         : 'expected a number >= 0, and rate_per_speed too');
            if (timed && Math.abs(state.frame_count) !== timed.cells)
                fail(`${wi}.frame_count`, `clip "${clip}" has ${timed.cells} cells, got ${state.frame_count}`);
            const first = state.first_row < 0 ? -state.first_row - 1 : state.first_row;
            const rows = timed ? type.clips.find((c) => c.name === clip).frame_count : Math.abs(state.frame_count);
            if (first + rows > type.rows || (timed && timed.map_rows > first))
                fail(wi, `rows ${first}..${first + rows} outside the type's ${type.rows} rows`);
            put(type.states, stateName, state);
        }
        need(t, at, 'lods', Array.isArray, 'an array').forEach((l, i) => {
            const w = `${at}.lods[${i}]`;
            const joint_remap = need(l, w, 'joint_remap', (v) => Array.isArray(v) && v.every((j) => isIndex(j) && j < type.bones),
                                     `an array of bone indices below ${type.bones}`);
            type.lods.push({ model: need(l, w, 'model', isString, 'a string'), joint_remap });
        });
        // Where props attach (older manifests: none): a prop's world is instance x bone matrix x bind_transform.
        (optional(t, at, 'sockets', Array.isArray, 'an array') ?? []).forEach((k, i) => {
            const w = `${at}.sockets[${i}]`;
            type.sockets.push({
                name: need(k, w, 'name', isString, 'a string'),
                bone: need(k, w, 'bone', (v) => isIndex(v) && v < type.bones, `a bone index below ${type.bones}`),
                bind_transform: need(k, w, 'bind_transform', (v) => Array.isArray(v) && v.length === 16 && v.every(Number.isFinite),
                                     '16 numbers'),
            });
        });
        // What the animation LOD's fewer influences cost (older manifests: none): lod 'auto' takes its thresholds from it.
        const lod = optional(t, at, 'animation_lod', isObject, 'an object');
        if (lod) {
            const w = `${at}.animation_lod`;
            type.animation_lod = {
                two_influences_error: need(lod, w, 'two_influences_error', isNonNegative, 'a number >= 0'),
                one_influence_error: need(lod, w, 'one_influence_error', isNonNegative, 'a number >= 0'),
                frames: need(lod, w, 'frames', isIndex, 'an integer >= 0'),
            };
        }
        // A type without states (a catalog animal that names none: every clip baked) has default_state "".
        const stateless = Object.keys(type.states).length === 0 && type.default_state === '';
        if (!stateless && !has(type.states, type.default_state))
            fail(`${at}.default_state`, `"${type.default_state}" is not one of the type's states`);
        put(out.types, typeName, type);
    }
    for (const [typeName, f] of Object.entries(optional(doc, 'top level', 'failed', isObject, 'an object') ?? {})) {
        const at = `failed.${typeName}`;
        put(out.failed, typeName,
            { model: need(f, at, 'model', isString, 'a string'), error: need(f, at, 'error', isString, 'a string') });
    }
    return out;
}

// The rate a timed clip's instance plays at standstill: its rate must stay negative to mark it timed (a rate of -0
// reads as an untimed clip's, its cells taken for rows), and this one moves it a cell in 3e22 years.
export const TIMED_STILL_RATE = 1e-30;

// The four per-instance floats of docs/roster.md for an instance in `state` (from readRoster, or made from a clip's
// clipInstance numbers: a negative rate, a timed clip's cells per second, keeps its sign), moving at `groundSpeed`
// model units/s, with instance index `index`; a one-shot started at `startTime` seconds.
export function instanceData(state, groundSpeed = 0, index = 0, startTime = 0) {
    const speed = state.rate_per_speed !== 0 ? Math.abs(state.rate_per_speed) * groundSpeed : Math.abs(state.rate);
    const rate = state.rate < 0 ? -Math.max(speed, TIMED_STILL_RATE) : speed;
    const frames = Math.abs(state.frame_count);
    const golden = index * 0.6180339887;
    const phase = state.phase === 'golden_ratio' ? golden - Math.floor(golden) : (-startTime * speed) / frames;
    return [state.first_row, state.frame_count, rate, phase];
}

