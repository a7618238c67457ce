// Shared by the web reader's tests: baking with the C tool, asking its reader, decoding texels.
// Not a test file itself (node --test runs it and finds no tests).
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdirSync, readFileSync, rmSync } from 'node:fs';
import path from 'node:path';
import { decompress as fzstdDecompress } from 'fzstd';

export const CROWDBAKE = process.env.CROWDBAKE ?? 'build/crowdbake';
export const SAMPLES = process.env.SAMPLES ?? 'build/samples';
export const FOX = '../shared/assets/fox-bevy/Fox.glb';

// build/tmp-tests/web/NAME beside the crowdbake binary's build folder, emptied.
export function tmpDir(name) {
    const dir = path.join(path.dirname(CROWDBAKE), 'tmp-tests', 'web', name);
    rmSync(dir, { recursive: true, force: true });
    mkdirSync(dir, { recursive: true });
    return dir;
}

// A fixed 30 fps unless args say otherwise: these tests read files, and the quadruped's loops travel
// (root motion kept), which no rate bakes within the default error budget. Global rows unless args say
// otherwise: these tests compare texels with the joint matrices `crowdbake sample` gives (local rows, the
// default bake's: local.test.mjs and timed.test.mjs).
export function bake(model, out, args = []) {
    const rate = args.includes('--fps') ? [] : ['--fps', '30'];
    const space = args.includes('--bone-space') ? [] : ['--bone-space', 'global'];
    execFileSync(CROWDBAKE, ['bake', model, '-o', out, '-q', ...rate, ...space, ...args], { stdio: ['ignore', 'ignore', 'pipe'] });
    return readFileSync(out);
}

export function inspect(file, args = []) {
    return JSON.parse(execFileSync(CROWDBAKE, ['inspect', file, '--json', ...args], { encoding: 'utf8', stdio: ['ignore', 'pipe', 'ignore'] }));
}

// Whether the C reader (crowdbake inspect, checksum not verified) opens the file.
export function cReaderAccepts(file) {
    return spawnSync(CROWDBAKE, ['inspect', file, '--no-verify'], { stdio: 'ignore' }).status === 0;
}

// fzstd (npm, pinned in runtimes/web/package-lock.json) as the caller's decoder, as a page would pass it:
// the module itself carries none.
export function fzstd(bytes, size) {
    return fzstdDecompress(bytes, new Uint8Array(size));
}

// The zstd command-line tool: an independent decoder to check fzstd's output against.
export function zstdDecompress(bytes) {
    return new Uint8Array(execFileSync('zstd', ['-d', '-c', '-q'], { input: bytes, stdio: ['pipe', 'pipe', 'pipe'] }));
}

// IEEE 754 binary16 to a number (written from the definition, not from the module).
export function halfToFloat(h) {
    const sign = h & 0x8000 ? -1 : 1, exp = (h >> 10) & 31, frac = h & 1023;
    if (exp === 0) return sign * frac * 2 ** -24;
    if (exp === 31) return frac ? NaN : sign * Infinity;
    return sign * (1 + frac / 1024) * 2 ** (exp - 15);
}

// The joint matrix M_j (16 numbers, column-major, as `crowdbake inspect --frame` prints it) of bone
// `bone` in `row`, decoded from the reader's texels by docs/pal-format.md.
export function jointMatrix(pal, row, bone) {
    const h = pal.header;
    const x = Math.floor(row / h.height) * h.row_texels + bone * h.texels_per_bone, y = row % h.height;
    const texel = (k) => {
        const i = (y * h.width + x + k) * 4;
        return [0, 1, 2, 3].map((c) => pal.texels[i + c]);
    };
    const snorm = (u) => Math.max(((u << 16) >> 16) / 32767, -1);
    const unorm = (u, a) => h.bounds_min[a] + (h.bounds_max[a] - h.bounds_min[a]) * u / 65535;
    const value = (t) => (h.precision === 1 ? t.map(halfToFloat) : t);
    const m = new Array(16).fill(0);
    if (h.layout === 0) { // mat4: texel k = column k
        for (let k = 0; k < 4; ++k) {
            const t = texel(k);
            for (let r = 0; r < 3; ++r)
                m[k * 4 + r] = h.precision === 2 ? (k < 3 ? snorm(t[r]) * h.linear_range : unorm(t[r], r)) : value(t)[r];
        }
        m[15] = 1;
    } else if (h.layout === 1) { // affine: texel k = row k of the upper 3x4
        for (let k = 0; k < 3; ++k) {
            const t = texel(k);
            for (let c = 0; c < 4; ++c)
                m[c * 4 + k] = h.precision === 2 ? (c < 3 ? snorm(t[c]) * h.linear_range : unorm(t[c], k)) : value(t)[c];
        }
        m[15] = 1;
    }
    if (h.layout !== 2 && h.flags & 4) { // half: the translation holds p - o, the joint's position less the bone's offset
        const b = pal.bones[bone].bind_position, o = pal.bones[bone].position_offset;
        for (let r = 0; r < 3; ++r) m[12 + r] += o[r] - (m[r] * b[0] + m[4 + r] * b[1] + m[8 + r] * b[2]);
    } else if (h.layout === 2) { // qpos: v' = p + s * rotate(q, v - b)
        let q = texel(0), ps = texel(1);
        q = h.precision === 2 ? q.map(snorm) : value(q);
        ps = h.precision === 2 ? [unorm(ps[0], 0), unorm(ps[1], 1), unorm(ps[2], 2), h.linear_range * ps[3] / 65535]
            : value(ps);
        const b = pal.bones[bone].bind_position, o = pal.bones[bone].position_offset; // o: 0 without flag bit 2
        const p = [ps[0] + o[0], ps[1] + o[1], ps[2] + o[2]];
        const norm = Math.hypot(...q); // stored rounded; a runtime normalizes (as crowdbake inspect does)
        const [qx, qy, qz, qw] = q.map((v) => v / norm), s = ps[3];
        const R = [ // column-major rotation
            1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qz * qw), 2 * (qx * qz - qy * qw),
            2 * (qx * qy - qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz + qx * qw),
            2 * (qx * qz + qy * qw), 2 * (qy * qz - qx * qw), 1 - 2 * (qx * qx + qy * qy)];
        for (let c = 0; c < 3; ++c) for (let r = 0; r < 3; ++r) m[c * 4 + r] = s * R[c * 3 + r];
        for (let r = 0; r < 3; ++r) m[12 + r] = p[r] - (m[r] * b[0] + m[4 + r] * b[1] + m[8 + r] * b[2]);
        m[15] = 1;
    }
    return m;
}
