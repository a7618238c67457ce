// The animation LOD's thresholds (lodThresholds, the runtimes' lod 'auto') against the C side: `crowdbake mesh
// --max-influences 1|2 --json` states each tier's worst extra vertex error over every frame of every clip at 30 fps,
// from the model's own poses in double precision (an independent measure). Measured at every row of a 30 fps palette
// (the same times), the web runtime must find the same worst error within the palette's own, and its thresholds must
// put that error at one pixel. A roster's animation_lod (the bake's measure) gives the same errors, and lod 'auto'
// takes it when the herd is given it.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { readPal, readRoster } from '../crowdbake_pal.mjs';
import { lodThresholds, lodThresholdsMeasured, resolveLod, LOD_POSES } from '../crowdbake_bones.mjs';
import { CROWDBAKE, tmpDir, bake } from './support.mjs';

const COW = '../shared/assets/quaternius-cow/Cow.glb';
const dir = tmpDir('lod');

// POSITION, JOINTS_0 and WEIGHTS_0 of every skinned primitive of a .glb, one after another (float positions and
// weights, u8 or u16 joints: what the shared models hold), as { positions, joints, weights }.
function skinnedMesh(file) {
    const data = readFileSync(file), jsonLength = data.readUInt32LE(12);
    const gltf = JSON.parse(data.subarray(20, 20 + jsonLength).toString('utf8'));
    const bin = data.subarray(20 + jsonLength + 8);
    const read = (index, components) => {
        const a = gltf.accessors[index], view = gltf.bufferViews[a.bufferView];
        const size = { 5126: 4, 5123: 2, 5121: 1 }[a.componentType], stride = view.byteStride ?? size * components;
        const out = new Float64Array(a.count * components), base = (view.byteOffset ?? 0) + (a.byteOffset ?? 0);
        for (let i = 0; i < a.count; ++i)
            for (let c = 0; c < components; ++c) {
                const at = base + i * stride + c * size;
                out[i * components + c] = size === 4 ? bin.readFloatLE(at) : size === 2 ? bin.readUInt16LE(at) : bin.readUInt8(at);
            }
        return out;
    };
    const parts = { positions: [], joints: [], weights: [] };
    gltf.nodes.filter((n) => n.skin !== undefined && n.mesh !== undefined).forEach((n) => gltf.meshes[n.mesh].primitives.forEach((p) => {
        parts.positions.push(...read(p.attributes.POSITION, 3));
        parts.joints.push(...read(p.attributes.JOINTS_0, 4));
        parts.weights.push(...read(p.attributes.WEIGHTS_0, 4));
    }));
    return { positions: Float32Array.from(parts.positions), joints: Int32Array.from(parts.joints), weights: Float32Array.from(parts.weights) };
}

// The C tool's worst extra vertex error (model units) of a mesh keeping `influences` weights.
function meshError(influences) {
    const out = path.join(dir, `cow-${influences}.glb`);
    return JSON.parse(execFileSync(CROWDBAKE, ['mesh', COW, '-o', out, '--max-influences', String(influences), '--json'],
                                   { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] })).error;
}

test('Cow: lod auto measures the 1- and 2-influence tiers as crowdbake mesh does, and puts their worst at a pixel', () => {
    const file = path.join(dir, 'cow.pal');
    const pal = readPal(bake(COW, file));
    const mesh = skinnedMesh(COW), rows = pal.clips.reduce((n, c) => n + c.frames, 0);
    const every = lodThresholds(pal, mesh, 1, { poses: rows }); // size 1: the worst errors in model units
    const height = JSON.parse(execFileSync(CROWDBAKE, ['mesh', COW, '-o', path.join(dir, 'cow-4.glb'), '--json'],
                                           { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] })).model_height;
    const budget = 1e-3 * height; // the palette's default error (1 mm/m), which both tiers' vertices carry
    for (const [tier, influences] of [['one', 1], ['two', 2]]) {
        const want = meshError(influences);
        assert.ok(Math.abs(every.worst[tier] - want) <= 2 * budget,
                  `${influences} influence(s): worst ${every.worst[tier]} against crowdbake mesh's ${want} (within ${2 * budget})`);
    }
    assert.ok(every.worst.one > 10 * budget && every.worst.two > 10 * budget, 'the tiers move vertices well past the bake error');
    assert.equal(every.one, 1 / every.worst.one);
    assert.equal(every.two, Math.max(1 / every.worst.two, every.one));
    // The default samples LOD_POSES rows: it can miss the worst row, never find worse than every row does. An
    // animal twice as large (size 2) is off by half as large a share of itself: twice the pixels.
    const sampled = lodThresholds(pal, mesh, 2);
    assert.equal(sampled.poses, LOD_POSES);
    for (const tier of ['one', 'two']) {
        const found = sampled.worst[tier] * 2;
        assert.ok(found <= every.worst[tier] * (1 + 1e-12) && found >= 0.8 * every.worst[tier],
                  `${LOD_POSES} poses find ${found} of the ${tier} tier's ${every.worst[tier]}`);
    }
    assert.ok(Math.abs(sampled.one - 1 / sampled.worst.one) < 1e-9);
});

test("Cow: lod 'auto' from a roster's animation_lod takes the bake's errors, which crowdbake mesh states, at a pixel", () => {
    // A catalog of Cow with every clip: its roster measures each tier over every clip at 30 fps.
    const catalog = path.join(dir, 'cow.toml');
    writeFileSync(catalog, `[bake]\nout_dir = "roster"\n[animal.cow]\nmodel = "${path.resolve(COW)}"\n`);
    execFileSync(CROWDBAKE, ['bake', catalog, '-q'], { stdio: ['ignore', 'ignore', 'pipe'] });
    const text = readFileSync(path.join(dir, 'roster', 'roster.json'), 'utf8'), measured = JSON.parse(text).types.cow.animation_lod;
    assert.deepEqual(readRoster(text).types.cow.animation_lod, measured); // what CrowdbakeHerd takes from its type
    for (const [tier, influences] of [['one', 1], ['two', 2]]) {
        const want = meshError(influences), got = measured[tier === 'one' ? 'one_influence_error' : 'two_influences_error'];
        assert.ok(Math.abs(got - want) <= 1e-6 * want, `${tier}: the roster's ${got} against crowdbake mesh's ${want}`);
    }
    const size = 13.5, t = lodThresholdsMeasured(measured, size);
    assert.equal(t.one, size / measured.one_influence_error);
    assert.equal(t.two, Math.max(size / measured.two_influences_error, t.one));
    assert.equal(t.poses, measured.frames);
    // resolveLod prefers it under 'auto' and says so; a given lod and false still override it; none: measured here.
    const auto = resolveLod('auto', null, null, size, measured);
    assert.deepEqual(auto.lod, { two: t.two, one: t.one });
    assert.match(auto.reason, /the roster's animation_lod, \d+ frames/);
    assert.deepEqual(resolveLod({ two: 30, one: 10 }, null, null, size, measured).lod, { two: 30, one: 10 });
    assert.equal(resolveLod(false, null, null, size, measured).lod, false);
    assert.equal(lodThresholdsMeasured(undefined, size), null);
});
