// Sockets in the web reader: boneMatrix at the baked rows equals `crowdbake sample` (the exact joint
// matrices) within the encoding for every layout x precision; between rows it is the GLSL's blend of
// the two rows (decoded independently by support.mjs's jointMatrix); bad clips, bones, times throw.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { readPal, boneMatrix, hasLocalRows, instanceFrame, LAYOUTS, PRECISIONS, CLIP_STEP } from '../crowdbake_pal.mjs';
import { CROWDBAKE, FOX, tmpDir, bake, jointMatrix } from './support.mjs';

const dir = tmpDir('sockets');
const sampled = JSON.parse(execFileSync(CROWDBAKE, ['sample', FOX, '--fps', '30', '--json'],
                                        { encoding: 'utf8', maxBuffer: 1 << 28 }));

// The farthest two matrices move the bone's bind position or a point a tenth of the height off it.
function pointDistance(a, b, bind, reach) {
    let worst = 0;
    for (let i = 0; i < 7; ++i) {
        const p = bind.slice();
        if (i) p[(i - 1) >> 1] += i % 2 ? reach : -reach;
        const apply = (m) => [0, 1, 2].map((k) => m[12 + k] + m[k] * p[0] + m[4 + k] * p[1] + m[8 + k] * p[2]);
        const x = apply(a), y = apply(b);
        worst = Math.max(worst, Math.hypot(x[0] - y[0], x[1] - y[1], x[2] - y[2]));
    }
    return worst;
}

for (const layout of LAYOUTS) {
    for (const precision of PRECISIONS) {
        test(`boneMatrix at the rows equals crowdbake sample: ${layout} ${precision}`, () => {
            const file = path.join(dir, `${layout}-${precision}.pal`);
            const pal = readPal(bake(FOX, file, ['--layout', layout, '--precision', precision, '--max-error', '1000']));
            const h = pal.header, reach = 0.1 * h.model_height;
            let worst = 0;
            pal.clips.forEach((clip, c) => {
                const samples = sampled.clips[c].samples;
                assert.equal(samples.length, clip.frames);
                for (const s of samples)
                    for (let j = 0; j < h.bone_count; ++j)
                        worst = Math.max(worst, pointDistance(boneMatrix(pal, c, s.frame / clip.fps, j), s.joints[j],
                                                              pal.bones[j].bind_position, reach));
            });
            // float32 rounding; half's 2^-11 and u16's steps as the bake measured them (max_error), with room for
            // points a tenth of the height off the skinned vertices.
            const bound = precision === 'float' ? 1e-5 * h.model_height : 2 * h.max_error + 1e-4 * h.model_height;
            assert.ok(worst <= bound, `${layout} ${precision}: ${worst} over ${bound}`);
        });
    }
}

// Local rows (bake --bone-space local): each bone's rows hold it in its parent's frame; boneMatrix composes the chain,
// and at the rows that must give the exact joint matrices as well as a global bake does.
for (const precision of ['u16', 'float']) {
    test(`local rows: boneMatrix composes to crowdbake sample at the rows: qpos ${precision}`, () => {
        const pal = readPal(bake(FOX, path.join(dir, `local-${precision}.pal`), ['--layout', 'qpos', '--precision', precision,
                                                                                  '--bone-space', 'local', '--max-error', '1000']));
        const h = pal.header, reach = 0.1 * h.model_height;
        assert.ok(hasLocalRows(h), 'baked as local rows');
        let worst = 0;
        pal.clips.forEach((clip, c) => {
            for (const s of sampled.clips[c].samples)
                for (let j = 0; j < h.bone_count; ++j)
                    worst = Math.max(worst, pointDistance(boneMatrix(pal, c, s.frame / clip.fps, j), s.joints[j],
                                                          pal.bones[j].bind_position, reach));
        });
        const bound = precision === 'float' ? 1e-5 * h.model_height : 2 * h.max_error + 1e-4 * h.model_height;
        assert.ok(worst <= bound, `local ${precision}: ${worst} over ${bound}`);
        console.log(`  local ${precision}: sockets within ${worst.toExponential(2)} of crowdbake sample (height ${h.model_height})`);
    });
}

test('boneMatrix between rows is the blend of the two rows the GLSL computes', () => {
    for (const layout of LAYOUTS) {
        const pal = readPal(bake(FOX, path.join(dir, `blend-${layout}.pal`), ['--layout', layout, '--precision', 'u16',
                                                                             '--max-error', '1000']));
        const clip = pal.clips[1], c = 1, h = pal.header;
        for (let r = 0; r < clip.frames; ++r) {
            const next = (r + 1) % clip.frames; // a loop's last row blends into its first
            for (let j = 0; j < h.bone_count; ++j) {
                const a = jointMatrix(pal, clip.first_row + r, j), b = jointMatrix(pal, clip.first_row + next, j);
                const m = boneMatrix(pal, c, (r + 0.25) / clip.fps, j);
                const bind = pal.bones[j].bind_position;
                if (layout !== 'qpos') { // matrices blend term by term
                    a.forEach((x, e) => assert.ok(Math.abs(m[e] - (0.75 * x + 0.25 * b[e])) < 1e-4 * (1 + Math.abs(x)),
                                                  `${layout} row ${r} bone ${j} [${e}]`));
                } else { // the joint's position blends linearly; the rotation by normalized lerp keeps it orthonormal
                    const at = (mm) => [0, 1, 2].map((k) => mm[12 + k] + mm[k] * bind[0] + mm[4 + k] * bind[1] + mm[8 + k] * bind[2]);
                    const pm = at(m), pa = at(a), pb = at(b);
                    for (let k = 0; k < 3; ++k) assert.ok(Math.abs(pm[k] - (0.75 * pa[k] + 0.25 * pb[k])) < 1e-3, `qpos position ${k}`);
                    const col = (mm, i) => Math.hypot(mm[4 * i], mm[4 * i + 1], mm[4 * i + 2]);
                    const s = 0.75 * col(a, 0) + 0.25 * col(b, 0);
                    for (let i = 0; i < 3; ++i) assert.ok(Math.abs(col(m, i) - s) < 1e-3 * s, 'qpos scale');
                }
            }
        }
    }
});

// The independent reference's joint matrices of clip 0 (../shared/reference: a JavaScript implementation of the glTF
// rules that shares no code with crowdbake): [{ t, joints: [16 numbers per joint] }] by frame.
function referenceFrames(csv) {
    const frames = [];
    for (const line of readFileSync(csv, 'utf8').split('\n')) {
        if (!line || line.startsWith('#') || line.startsWith('clip,')) continue;
        const v = line.split(','), frame = Number(v[2]), joint = Number(v[6]);
        frames[frame] ??= { t: Number(v[4]), joints: [] };
        frames[frame].joints[joint] = v.slice(7, 23).map(Number);
    }
    return frames;
}

// Half a reference frame past each of the STEP-keyed SimpleSkin's reference times with no key between (its keys lie
// every 0.5 s), the palette's matrices are the reference's: a STEP channel holds its value there.
function stepReferenceHeld(pal) {
    let worst = 0, compared = 0;
    for (const f of referenceFrames('../shared/reference/gltf_simple_skin_step.fps30.csv')) {
        const t = f.t + 1 / 60;
        if (Math.floor(f.t * 2 + 1e-6) !== Math.floor(t * 2 - 1e-6)) continue;
        f.joints.forEach((ref, j) => boneMatrix(pal, 0, t, j).forEach((x, e) => { worst = Math.max(worst, Math.abs(x - ref[e])); }));
        ++compared;
    }
    assert.ok(compared > 100 && worst < 1e-4, `${compared} times, worst ${worst}`);
    return { compared, worst };
}

test('a STEP-keyed clip (version 4) holds its rows: its row alone between rows, and the reference between its keys', () => {
    const model = '../shared/assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf';
    const pal = readPal(bake(model, path.join(dir, 'step.pal'), ['--fps', 'auto'])); // auto: rows at its key times
    const clip = pal.clips[0];
    assert.equal(pal.header.version, 4);
    assert.ok(clip.step && (clip.flags & CLIP_STEP) !== 0 && clip.fps === 2);
    for (let r = 0; r < clip.frames; ++r) {
        assert.deepEqual(instanceFrame([-clip.first_row - 1, clip.frames, clip.fps, 0], (r + 0.75) / clip.fps),
                         { row0: clip.first_row + r, row1: clip.first_row + r, fr: 0 });
        for (let j = 0; j < pal.header.bone_count; ++j) { // support.mjs decodes the row on its own
            const row = jointMatrix(pal, clip.first_row + r, j), m = boneMatrix(pal, 0, (r + 0.75) / clip.fps, j);
            row.forEach((x, e) => assert.ok(Math.abs(m[e] - x) < 1e-6, `row ${r} bone ${j} [${e}]`));
        }
    }
    stepReferenceHeld(pal);
});

test('local rows hold a STEP-keyed clip\'s rows too: the reference between its keys, composed', () => {
    const model = '../shared/assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf';
    const pal = readPal(bake(model, path.join(dir, 'step-local.pal'), ['--fps', 'auto', '--bone-space', 'local']));
    const clip = pal.clips[0];
    assert.ok(hasLocalRows(pal.header) && clip.step);
    const { compared, worst } = stepReferenceHeld(pal);
    console.log(`  held local rows: ${compared} times between keys within ${worst.toExponential(2)} of the reference`);
});

test('boneMatrix refuses a clip, bone or time that does not exist', () => {
    const pal = readPal(bake(FOX, path.join(dir, 'bad.pal'), ['--max-error', '1000']));
    assert.equal(boneMatrix(pal, 0, 0.1, 0).length, 16);
    assert.throws(() => boneMatrix(pal, pal.clips.length, 0.1, 0), /clip/);
    assert.throws(() => boneMatrix(pal, 0, 0.1, pal.header.bone_count), /bone/);
    assert.throws(() => boneMatrix(pal, 0, NaN, 0), /time/);
    // One-shots clamp, loops wrap: a loop one period on is where it began.
    const loop = pal.clips.findIndex((c) => c.loops);
    const period = pal.clips[loop].frames / pal.clips[loop].fps;
    boneMatrix(pal, loop, 0.3, 3).forEach((x, e, m0) => assert.ok(Math.abs(boneMatrix(pal, loop, 0.3 + period, 3)[e] - x) < 1e-4 * (1 + Math.abs(x)), `${m0}`));
});
