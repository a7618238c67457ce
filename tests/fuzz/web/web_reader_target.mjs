// web_reader_target.mjs - what the web reader's fuzzer checks on each input, shared by the
// Jazzer.js entry (fuzz_web.mjs) and the regression replay in `make check`
// (runtimes/web/test/fuzz_regressions.test.mjs).
//
// Every input is read as a .pal (with and without the checksum, zstd through the caller's
// decoder) and as a roster.json, as a page would read untrusted files. Each read must end in a
// returned value a runtime can use as it is - every row of every clip and every bone inside the
// texels, every state a real one - or in one thrown Error whose message names the file; a
// RangeError or TypeError from a typed array, a DataView or a missing member is a finding.
import { readPal, readRoster, texelIndex, boneMatrix } from '../../../runtimes/web/crowdbake_pal.mjs';

// Decompressed payloads the fuzzer may ask for: enough for every seed, small enough that a
// header asking for more is refused before anything is allocated.
const MAX_DECOMPRESSED = 16 << 20;

function finding(message) {
    const e = new Error(`web reader finding: ${message}`);
    e.name = 'WebReaderFinding';
    throw e;
}

// A thrown error must be the reader's own: a plain Error naming the file first.
function checkRefusal(e, name) {
    if (e?.name === 'WebReaderFinding') throw e;
    if (!(e instanceof Error) || e.constructor !== Error) throw e; // RangeError, TypeError, ...
    if (!e.message.startsWith(`${name}: `)) finding(`error without the file's name: ${e.message}`);
    if (e.message.includes('\n')) finding(`multi-line error: ${JSON.stringify(e.message)}`);
}

// What a runtime does with an opened palette: sample every row of every clip for every bone, and
// ask where each bone is (sockets).
function usePal(pal) {
    const h = pal.header, texels = pal.texels;
    const expect = h.width * h.height * 4;
    if (texels.length !== expect) finding(`texels hold ${texels.length} components, the header says ${expect}`);
    let sink = 0;
    const touchRow = (row) => {
        for (let bone = 0; bone < h.bone_count; ++bone) {
            const at = texelIndex(h, row, bone);
            const end = at + h.texels_per_bone * 4;
            if (!(at >= 0 && end <= texels.length)) finding(`row ${row} bone ${bone}: texels [${at}, ${end}) of ${texels.length}`);
            sink += texels[at] + texels[end - 1];
        }
    };
    for (const c of pal.clips) {
        if (c.first_row + c.frames > h.rows) finding(`clip ${c.name}: rows past ${h.rows}`);
        for (let f = 0; f < c.frames; ++f) touchRow(c.first_row + f);
    }
    for (let row = 0; row < h.rows; ++row) touchRow(row);
    for (const b of pal.bones) {
        if (!(b.parent >= -1 && b.parent < h.bone_count)) finding(`bone ${b.name}: parent ${b.parent}`);
        sink += b.position_offset[0] + b.bind_position[0];
    }
    // A socket's matrix in every clip for every bone (the first 10,000 pairs): 16 numbers, or a plain
    // Error where the file's fps makes the time meaningless.
    for (let c = 0; c < pal.clips.length; ++c)
        for (let bone = 0; bone < h.bone_count && c * h.bone_count + bone < 10000; ++bone)
            for (const time of [-1, 0.3, 1e6]) {
                try {
                    const m = boneMatrix(pal, c, time, bone);
                    if (m.length !== 16) finding(`boneMatrix(${c}, ${time}, ${bone}): ${m.length} numbers`);
                    sink += m[15];
                } catch (e) {
                    if (e?.name === 'WebReaderFinding' || !(e instanceof Error) || e.constructor !== Error) throw e;
                }
            }
    return sink;
}

// What a runtime does with a roster: start every type in its default state and every state. Every
// type and state of the file (`doc`, JSON.parse's) is in it, by its own name.
function useRoster(roster, doc) {
    const own = (o, k) => o !== null && typeof o === 'object' && Object.prototype.hasOwnProperty.call(o, k);
    for (const [typeName, t] of Object.entries(doc.types)) {
        if (!own(roster.types, typeName)) finding(`type ${typeName} of the file is not in the roster`);
        for (const stateName of Object.keys(t.states))
            if (!own(roster.types[typeName].states, stateName)) finding(`state ${typeName}.${stateName} is lost`);
    }
    for (const [typeName, type] of Object.entries(roster.types)) {
        if (!own(roster.types, typeName)) finding(`type ${typeName} is not the roster's own`);
        if (!own(type.states, type.default_state)) finding(`type ${typeName}: default_state ${type.default_state} is no state`);
        for (const [stateName, s] of Object.entries(type.states)) {
            const clip = type.clips.find((c) => c.name === s.clip);
            if (!clip) finding(`${typeName}.${stateName}: clip ${s.clip} is not the type's`);
            if (!(Number.isInteger(s.first_row) && s.first_row + Math.abs(s.frame_count) <= type.rows))
                finding(`${typeName}.${stateName}: rows outside ${type.rows}`);
        }
        for (const l of type.lods)
            for (const j of l.joint_remap) if (!(Number.isInteger(j) && j >= 0 && j < type.bones)) finding(`lod joint ${j}`);
    }
}

// decompress: (bytes, rawSize) -> Uint8Array, as a page passes fzstd's.
export function checkInput(data, decompress) {
    const bytes = data instanceof Uint8Array ? data : new Uint8Array(data);
    for (const verifyChecksum of [false, true]) {
        const name = 'fuzz.pal';
        try {
            usePal(readPal(bytes, { name, verifyChecksum, decompress, maxDecompressedBytes: MAX_DECOMPRESSED }));
        } catch (e) {
            checkRefusal(e, name);
        }
    }
    // TextDecoder as fetch().text() would give it (invalid UTF-8 replaced).
    const name = 'roster.json';
    try {
        const text = new TextDecoder('utf-8').decode(bytes);
        useRoster(readRoster(text, { name }), JSON.parse(text));
    } catch (e) {
        checkRefusal(e, name);
    }
}
