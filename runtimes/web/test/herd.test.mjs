// CrowdbakeHerd's game hooks without a GPU (three.js objects only): footstep callbacks from the
// roster's contacts (every crossing, in order, across loop ends, big frames and rate changes, and
// the feet really are down when they land), boneMatrixAt through a cross-fade, and a placed
// gallop drawn at its place plus the palette's per-row travel offset.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { readPal, readRoster, boneMatrix } from '../crowdbake_pal.mjs';
import { contactsCrossed } from '../crowdbake_contacts.mjs';
import { CrowdbakeHerd } from '../crowdbake_three.mjs';
import { travelOffset } from '../crowdbake_travel.mjs';
import * as THREE from 'three';
import { CROWDBAKE, tmpDir } from './support.mjs';

const dir = tmpDir('herd');
const COW = path.resolve('../shared/assets/quaternius-cow/Cow.glb');
writeFileSync(path.join(dir, 'catalog.toml'), `[bake]
fps = 30
out_dir = "out"
[animal.cow]
model = "${COW}"
states = { idle = ["Idle"], walk = ["Walk"], gallop = ["Gallop"] }
default_state = "walk"
`);
execFileSync(path.resolve(CROWDBAKE), ['bake', 'catalog.toml', '-q', '-j', '1'], { cwd: dir, stdio: ['ignore', 'ignore', 'pipe'] });
const roster = readRoster(readFileSync(path.join(dir, 'out', 'roster.json'), 'utf8'));
const cow = roster.types.cow;
const pal = readPal(readFileSync(path.join(dir, 'out', cow.palette)));
const mesh = { positions: new Float32Array(9), normals: new Float32Array(9), joints: new Uint16Array(12),
               weights: new Float32Array(12).fill(0.25), indices: new Uint32Array([0, 1, 2]) };
const herdOf = (count) => new CrowdbakeHerd(mesh, pal, cow, { count, glsl: '// not compiled here' });
const walk = cow.clips.find((c) => c.name.endsWith('|Walk'));

test('the manifest gives Walk a landing and a lift per hoof, and Cow its sockets, as the schema says', () => {
    execFileSync('node', ['tests/tools/validator/validate_schema.mjs', 'docs/roster.schema.json', path.join(dir, 'out', 'roster.json')]);
    assert.equal(cow.sockets.length, 10); // not the 4 IK pole targets (rig helpers)
    const doc = JSON.parse(readFileSync(path.join(dir, 'out', 'roster.json'), 'utf8'));
    doc.types.cow.sockets[0].bone = 99;
    assert.throws(() => readRoster(doc), /types\.cow\.sockets\[0\]\.bone: expected a bone index below 42/);
    doc.types.cow.sockets[0].bone = 8;
    doc.types.cow.clips.find((c) => c.contacts).contacts[0].time = -1;
    assert.throws(() => readRoster(doc), /contacts\[0\]\.time: expected a number >= 0/);
    assert.equal(walk.contacts.length, 4);
    assert.deepEqual(walk.contacts.map((c) => c.foot).sort(), ['FF.L', 'FF.R', 'FFB.L', 'FFB.R']);
});

test('contactsCrossed: each contact once a cycle, in order, whatever the step', () => {
    const frames = walk.frame_count;
    const all = contactsCrossed(walk, frames, -1e-9, 3 * frames); // three whole cycles in one step
    assert.equal(all.length, 3 * 2 * walk.contacts.length);
    for (let i = 1; i < all.length; ++i) assert.ok(all[i].at >= all[i - 1].at);
    // The same span in 97 uneven steps gives the same crossings.
    const steps = [];
    let from = -1e-9;
    for (let k = 1; k <= 97; ++k) {
        const to = 3 * frames * Math.pow(k / 97, 1.3);
        steps.push(...contactsCrossed(walk, frames, from, to));
        from = to;
    }
    assert.deepEqual(steps.map((e) => [e.contact.foot, e.kind, e.at]), all.map((e) => [e.contact.foot, e.kind, e.at]));
    assert.equal(contactsCrossed(walk, frames, 5, 4).length, 0); // backwards: nothing
});

test('onContact: every instance and foot, crossing times on the clip, feet down when they land', () => {
    const herd = herdOf(3);
    const speed = walk.ground_speed;
    for (let i = 0; i < 3; ++i) herd.setState(i, 'walk', { speed: speed * (1 + i / 2), fade: 0 });
    const events = [];
    herd.onContact((e) => events.push(e));
    let t = 0;
    for (let frame = 0; frame < 240; ++frame) herd.update(t += frame % 7 === 0 ? 0.05 : 1 / 60); // uneven frames
    herd.update(t += 2.5); // a hitch: two cycles and more in one update
    const inst = herd.geometry.attributes.cb_inst.array;
    for (let i = 0; i < 3; ++i) {
        const mine = events.filter((e) => e.instance === i && e.kind === 'land');
        const rate = inst[i * 4 + 2], phase = inst[i * 4 + 3], frames = walk.frame_count;
        for (const c of walk.contacts) { // one landing per cycle the instance played through this contact
            const row = c.time * walk.fps, end = t * rate + phase * frames, start = phase * frames;
            const expected = Math.floor((end - row) / frames) - Math.floor((start - row) / frames);
            assert.equal(mine.filter((e) => e.foot === c.foot).length, expected, `instance ${i} ${c.foot}`);
        }
        for (const e of mine) { // the clip time at the event is the contact's
            const clipTime = (((e.time * rate + phase * frames) % frames) + frames) % frames / walk.fps;
            const c = walk.contacts.find((k) => k.foot === e.foot);
            assert.ok(Math.min(Math.abs(clipTime - c.time), walk.duration - Math.abs(clipTime - c.time)) < 1e-6);
        }
    }
    // The feet are really down: mid-stance the hoof's joint is in the lowest quarter of its lift, and at the landing
    // (where the hoof's sole, which crowdbake tracks, meets the ground: the joint above it still rolls down) in the
    // lower half.
    const clip = pal.clips.findIndex((c) => c.name === walk.name);
    for (const c of walk.contacts) {
        const b = pal.bones[c.bone].bind_position;
        const height = (s) => { const m = boneMatrix(pal, clip, s, c.bone); return m[1] * b[0] + m[5] * b[1] + m[9] * b[2] + m[13]; };
        const heights = Array.from({ length: 120 }, (_, k) => height((k / 120) * walk.duration));
        const lo = Math.min(...heights), hi = Math.max(...heights);
        assert.ok(height(c.time) < lo + 0.5 * (hi - lo), `${c.foot} lands at ${c.time}`);
        assert.ok(height((c.time + c.lift + (c.lift < c.time ? walk.duration : 0)) / 2) < lo + 0.25 * (hi - lo));
    }
});

test('onContact: a rate change keeps the clock (no repeated or lost steps)', () => {
    const herd = herdOf(1), events = [];
    herd.setState(0, 'walk', { speed: walk.ground_speed, fade: 0 });
    herd.onContact((e) => events.push(e));
    let t = 0;
    for (let k = 0; k < 300; ++k) {
        herd.update(t += 1 / 60);
        if (k % 40 === 39) herd.setSpeed(0, walk.ground_speed * (0.5 + (k % 80) / 80)); // speed changes mid-stride
    }
    const lands = events.filter((e) => e.kind === 'land');
    for (let k = 1; k < lands.length; ++k) assert.ok(lands[k].time >= lands[k - 1].time);
    // Each foot alternates land, lift, land...: no step raised twice or dropped.
    for (const foot of ['FF.L', 'FF.R', 'FFB.L', 'FFB.R']) {
        const kinds = events.filter((e) => e.foot === foot).map((e) => e.kind);
        for (let k = 1; k < kinds.length; ++k) assert.notEqual(kinds[k], kinds[k - 1], `${foot}: ${kinds.join(' ')}`);
    }
});

test('boneMatrixAt follows the instance through a cross-fade', () => {
    const herd = herdOf(1);
    herd.setState(0, 'idle', { fade: 0, phase: 0 });
    herd.update(1.0);
    const idle = herd.boneMatrixAt(0, 8).toArray();
    herd.setState(0, 'gallop', { fade: 0.5, phase: 0, speed: 1 });
    const start = herd.boneMatrixAt(0, 8).toArray(); // fade 0: still the idle pose
    start.forEach((x, k) => assert.ok(Math.abs(x - idle[k]) < 1e-9));
    herd.update(1.25);
    const mid = herd.boneMatrixAt(0, 8).toArray();
    herd.update(1.6);
    const after = herd.boneMatrixAt(0, 8).toArray(); // fade done: the gallop's own matrix at its clip time
    const g = pal.clips.findIndex((c) => c.name.endsWith('|Gallop')), inst = herd.geometry.attributes.cb_inst.array;
    const own = boneMatrix(pal, g, (1.6 * inst[2] + inst[3] * inst[1]) / pal.clips[g].fps, 8);
    own.forEach((x, k) => assert.ok(Math.abs(x - after[k]) < 1e-4 * (1 + Math.abs(x)), `[${k}] ${x} ${after[k]}`));
    assert.ok(mid.some((x, k) => Math.abs(x - idle[k]) > 1e-6 && Math.abs(x - after[k]) > 1e-6));
    assert.throws(() => herd.boneMatrixAt(0, pal.header.bone_count), /bone/);
});

test('a placed instance galloping at speed is drawn at its place plus the travel offset; a walk and a standstill at their place', () => {
    const herd = herdOf(3), g = pal.clips.findIndex((c) => c.name.endsWith('|Gallop'));
    assert.ok(pal.rowTravel && pal.clips[g].travel_heading.some((x) => x !== 0), 'the gallop carries offsets');
    const manifest = cow.clips.find((c) => c.name.endsWith('|Gallop'));
    assert.ok(manifest); // the manifest says so too (row_travel.applied), checked by the schema test above
    const yaw = 0.7, scale = 1.5, place = [3, 0, -2], m = new THREE.Matrix4(), p = new THREE.Vector3();
    herd.setState(0, 'gallop', { fade: 0, phase: 0.25, speed: 6 });
    herd.setState(1, 'walk', { fade: 0, phase: 0.25, speed: 2 });
    herd.setState(2, 'gallop', { fade: 0, phase: 0.25, speed: 0 });
    for (let i = 0; i < 3; ++i) herd.place(i, place, { yaw, scale });
    let moved = 0;
    for (const time of [0.1, 0.37, 0.52, 0.9]) {
        herd.update(time);
        const inst = herd.geometry.attributes.cb_inst.array;
        const o = new THREE.Vector3(...travelOffset(pal, g, (time * inst[2] + inst[3] * inst[1]) / pal.clips[g].fps));
        const want = o.multiplyScalar(scale).applyAxisAngle(new THREE.Vector3(0, 1, 0), yaw).add(new THREE.Vector3(...place));
        herd.getMatrixAt(0, m), p.setFromMatrixPosition(m);
        assert.ok(p.distanceTo(want) < 1e-5, `${time}: ${p.toArray()} vs ${want.toArray()}`);
        moved = Math.max(moved, p.distanceTo(new THREE.Vector3(...place)));
        for (const i of [1, 2]) { // no offsets (the walk) / at standstill: at its place
            herd.getMatrixAt(i, m), p.setFromMatrixPosition(m);
            assert.ok(p.distanceTo(new THREE.Vector3(...place)) < 1e-6, `instance ${i} at ${time}`);
        }
    }
    assert.ok(moved > 0.001 * pal.header.model_height, `offsets up to ${moved}`);
    herd.setMatrixAt(0, new THREE.Matrix4()); // the caller's matrix is left alone
    herd.update(1.2);
    herd.getMatrixAt(0, m);
    assert.equal(p.setFromMatrixPosition(m).length(), 0);
});
