// The roster reader on a real bake of samples/catalog.toml, against the palettes it names, and
// on broken manifests.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { readPal, readRoster, instanceData, instanceBoneMatrix, boneMatrix } from '../crowdbake_pal.mjs';
import { CROWDBAKE, SAMPLES, tmpDir } from './support.mjs';

const dir = tmpDir('roster');
// The sample catalog, writing into this test's folder and naming the models by absolute path.
const catalog = readFileSync('samples/catalog.toml', 'utf8')
    .replace('out_dir = "../build/roster"', 'out_dir = "roster"')
    .replaceAll('"../build/samples/', `"${path.resolve(SAMPLES)}/`);
writeFileSync(path.join(dir, 'catalog.toml'), catalog);
execFileSync(CROWDBAKE, ['bake', path.join(dir, 'catalog.toml'), '-q'], { stdio: ['ignore', 'ignore', 'pipe'] });
const manifestPath = path.join(dir, 'roster', 'roster.json');
const manifestText = readFileSync(manifestPath, 'utf8');

test('each type\'s palette opens, and its states address the palette\'s clips', () => {
    const roster = readRoster(manifestText, { name: manifestPath });
    assert.deepEqual(Object.keys(roster.types).sort(), ['bird', 'fish', 'goat', 'sheep']);
    assert.equal(roster.types.sheep.shares_palette_of, 'goat');
    assert.equal(roster.types.sheep.palette, 'goat.pal');
    assert.equal(roster.types.goat.lods.length, 1);
    assert.ok(roster.types.goat.lods[0].joint_remap.length > 1);
    for (const [name, type] of Object.entries(roster.types)) {
        const file = path.join(path.dirname(manifestPath), type.palette);
        const pal = readPal(readFileSync(file), { name: file, verifyChecksum: true });
        for (const k of ['rows', 'width', 'height', 'blocks', 'texels_per_bone']) assert.equal(type[k], pal.header[k], `${name}.${k}`);
        assert.equal(type.bones, pal.header.bone_count);
        assert.equal(type.layout, pal.header.layout_name);
        assert.equal(type.precision, pal.header.precision_name);
        for (const clip of type.clips) {
            const c = pal.clips.find((p) => p.name === clip.name);
            assert.ok(c, `${name}: clip ${clip.name} not in ${type.palette}`);
            assert.deepEqual([clip.first_row, clip.frame_count, clip.loops], [c.first_row, c.frames, c.loops]);
            assert.equal(Math.fround(clip.fps), c.fps);
        }
        for (const [stateName, state] of Object.entries(type.states)) {
            const c = pal.clips.find((p) => p.name === state.clip);
            // docs/roster.md: x = first_row, y = the clip's rows, negative for a one-shot.
            assert.equal(state.first_row, c.first_row, `${name}.${stateName}`);
            assert.equal(state.frame_count, c.loops ? c.frames : -c.frames, `${name}.${stateName}`);
        }
    }
});

test('per-instance numbers follow docs/roster.md', () => {
    const goat = readRoster(JSON.parse(manifestText)).types.goat;
    const raw = JSON.parse(manifestText).types.goat;
    const clip = (name) => raw.clips.find((c) => c.name === name); // the clip table, beside the states
    assert.deepEqual(goat.states.wander, { clip: raw.states.wander.clip, ...raw.states.wander.instance });
    // Locomotion: rate_per_speed x ground speed; phase fract(i x golden ratio). At the walk's own
    // ground speed (1.2, the generator's) it plays at the walk's baked rate.
    const walk = clip('walk');
    const [x, y, z, w] = instanceData(goat.states.wander, 1.2, 3);
    assert.deepEqual([x, y], [walk.first_row, walk.frame_count]);
    assert.ok(Math.abs(z - raw.states.wander.instance.rate_per_speed * 1.2) < 1e-12 && Math.abs(z - walk.fps) < 1e-5);
    assert.ok(Math.abs(w - 0.8541019661) < 1e-9);
    // Not synced to speed: rate; a one-shot started at T: -T x rate / frames.
    assert.equal(instanceData(goat.states.graze, 5, 0)[2], clip('eat').fps);
    const death = clip('death'), die = instanceData(goat.states.die, 0, 7, 2);
    assert.deepEqual(die.slice(0, 3), [death.first_row, -death.frame_count, death.fps]);
    assert.ok(Math.abs(die[3] - (-2 * death.fps) / death.frame_count) < 1e-12);
});

test('a STEP-keyed clip\'s state holds its rows: a negative first row, played as the palette\'s clip', () => {
    const model = path.resolve('../shared/assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf');
    writeFileSync(path.join(dir, 'step.toml'), `[bake]\nout_dir = "step"\n[animal.skin]\nmodel = "${model}"\n` +
                  'states = { swing = ["animation"] }\n');
    execFileSync(CROWDBAKE, ['bake', path.join(dir, 'step.toml'), '-q'], { stdio: ['ignore', 'ignore', 'pipe'] });
    const raw = JSON.parse(readFileSync(path.join(dir, 'step', 'roster.json'), 'utf8')).types.skin;
    const type = readRoster(JSON.parse(readFileSync(path.join(dir, 'step', 'roster.json'), 'utf8'))).types.skin;
    assert.equal(raw.clips[0].step_rows, true);
    assert.equal(type.states.swing.first_row, -raw.clips[0].first_row - 1); // docs/roster.md: held rows
    const pal = readPal(readFileSync(path.join(dir, 'step', type.palette)));
    const inst = instanceData(type.states.swing, 0, 0);
    for (const t of [0.1, 0.6, 1.3, 2.9, 5.2])
        for (let j = 0; j < pal.header.bone_count; ++j)
            assert.deepEqual(instanceBoneMatrix(pal, [inst[0], inst[1], inst[2], 0], t, j), boneMatrix(pal, 0, t, j));
});

test('broken manifests are refused with the field that is wrong', () => {
    const good = JSON.parse(manifestText);
    const cases = [
        ['{"schema": ', /not JSON/],
        [[], /top level: expected an object/],
        [{ ...good, schema: 'crowdbake-roster/2' }, /schema: "crowdbake-roster\/2" is not crowdbake-roster\/1/],
        [{ ...good, types: 5 }, /top level\.types: expected an object/],
        [(d) => delete d.types.goat.rows, /types\.goat\.rows: missing/],
        [(d) => { d.types.fish.bones = 0; }, /types\.fish\.bones: expected an integer >= 1, got 0/],
        [(d) => { d.types.fish.layout = 'mat3'; }, /types\.fish\.layout: expected one of mat4, affine, qpos/],
        [(d) => { delete d.types.bird.palette; }, /types\.bird: has neither palette nor palette_exr/],
        [(d) => { d.types.goat.clips[1].first_row = 10000; }, /types\.goat\.clips\[1\]: rows 10000\.\./],
        [(d) => { d.types.goat.clips[2] = null; }, /types\.goat\.clips\[2\]: expected an object/],
        [(d) => { d.types.goat.states.die.clip = 'fly'; }, /types\.goat\.states\.die\.clip: "fly" is not one of/],
        [(d) => { d.types.goat.states.die.instance.frame_count = 0; }, /states\.die\.instance\.frame_count: expected a non-zero integer/],
        [(d) => { d.types.goat.states.die.instance.first_row = 240; },
            new RegExp(`states\\.die\\.instance: rows 240\\.\\.${240 + Math.abs(good.types.goat.states.die.instance.frame_count)} outside`)],
        [(d) => { d.types.goat.states.idle.instance.phase = 'random'; }, /states\.idle\.instance\.phase: expected/],
        [(d) => { d.types.goat.default_state = 'sleep'; }, /types\.goat\.default_state: "sleep" is not one of the type's states/],
        [(d) => { d.types.goat.default_state = ''; }, /types\.goat\.default_state: "" is not one of the type's states/],
        [(d) => { d.types.goat.animation_lod = { two_influences_error: -1, one_influence_error: 1, frames: 3 }; },
            /types\.goat\.animation_lod\.two_influences_error: expected a number >= 0/],
        [(d) => { d.types.goat.lods[0].joint_remap[2] = 41; }, /types\.goat\.lods\[0\]\.joint_remap: expected an array of bone indices below 41/],
        [(d) => { d.failed = { eel: { model: 'eel.glb' } }; }, /failed\.eel\.error: missing/],
        // Names from the file are not Object.prototype's members (the reader returned a type whose
        // default state was a function; tests/fuzz/regressions/web keeps the input).
        [(d) => { d.types.goat.default_state = 'constructor'; }, /types\.goat\.default_state: "constructor" is not one of/],
        [(d) => { d.types.goat.states.die.clip = 'toString'; }, /states\.die\.clip: "toString" is not one of/],
        [(d) => { d.types.goat.clips[0].hasOwnProperty = 1; delete d.types.goat.clips[0].name; }, /clips\[0\]\.name: missing/],
    ];
    for (const [mutation, expected] of cases) {
        let input = mutation;
        if (typeof mutation === 'function') {
            input = structuredClone(good);
            mutation(input);
        }
        let error = null;
        try {
            readRoster(input, { name: 'r.json' });
        } catch (e) {
            error = e;
        }
        assert.ok(error, `accepted: ${expected}`);
        assert.equal(error.constructor, Error);
        assert.ok(error.message.startsWith('r.json: ') && !error.message.includes('\n'), error.message);
        assert.match(error.message, expected);
    }
    // "__proto__" is a name like any other (JSON.parse makes it an own member): a type and a state so named
    // are read, not turned into the objects' prototypes.
    const proto = JSON.parse(manifestText.replace('"goat":', '"__proto__":').replace('"wander":', '"__proto__":')
        .replace('"default_state": "wander"', '"default_state": "__proto__"'));
    const read = readRoster(proto);
    assert.ok(Object.keys(read.types).includes('__proto__'), Object.keys(read.types).join());
    assert.equal(Object.getPrototypeOf(read.types), Object.prototype);
    assert.equal(read.types.__proto__.states.__proto__.first_row, JSON.parse(manifestText).types.goat.states.wander.instance.first_row);
    // A failed type is reported, not an error: the others still load.
    const withFailure = readRoster({ ...good, failed: { eel: { model: 'eel.glb', error: 'not a GLB file' } } });
    assert.deepEqual(withFailure.failed, { eel: { model: 'eel.glb', error: 'not a GLB file' } });
});

test('a type without states (a catalog animal naming none) reads with default_state "", its animation_lod kept', () => {
    const d = JSON.parse(manifestText);
    d.types.goat.states = {};
    d.types.goat.default_state = '';
    d.types.goat.animation_lod = { two_influences_error: 0.25, one_influence_error: 0.5, frames: 90 };
    const goat = readRoster(d).types.goat;
    assert.deepEqual(Object.keys(goat.states), []);
    assert.deepEqual(goat.animation_lod, { two_influences_error: 0.25, one_influence_error: 0.5, frames: 90 });
});

test('a timed clip\'s states count cells and play at a negative rate (docs/roster.md), standing still too', () => {
    const local = path.join(dir, 'timed.toml');
    writeFileSync(local, catalog.replace('out_dir = "roster"', 'out_dir = "timed"\nbone_space = "local"\ntimed_rows = "on"'));
    execFileSync(CROWDBAKE, ['bake', local, '-q'], { stdio: ['ignore', 'ignore', 'pipe'] });
    const file = path.join(dir, 'timed', 'roster.json');
    const roster = readRoster(readFileSync(file, 'utf8'), { name: file });
    let timedStates = 0;
    for (const type of Object.values(roster.types)) {
        const pal = readPal(readFileSync(path.join(dir, 'timed', type.palette)), { name: type.palette });
        for (const state of Object.values(type.states)) {
            const c = pal.clips.find((p) => p.name === state.clip);
            if (!c.timed) continue;
            timedStates++;
            const clip = type.clips.find((k) => k.name === state.clip);
            assert.deepEqual([clip.timed_rows.cells, Math.fround(clip.timed_rows.cell_rate), clip.timed_rows.map_rows],
                             [c.cells, c.cell_rate, c.map_rows]);
            assert.equal(Math.abs(state.frame_count), c.cells);
            assert.ok(state.rate < 0 && state.rate_per_speed <= 0);
            const still = instanceData(state, 0, 1), moving = instanceData(state, 2, 1);
            assert.ok(still[2] < 0 && moving[2] < 0, 'z < 0 marks a timed instance, standing still too');
            if (state.rate_per_speed !== 0) assert.ok(Math.abs(moving[2] + Math.abs(state.rate_per_speed) * 2) < 1e-9);
            else assert.equal(moving[2], state.rate);
        }
    }
    assert.ok(timedStates > 0, 'timed_rows = "on" gave no timed state');
    // A timed state's frame_count other than its clip's cells is refused.
    const doc = JSON.parse(readFileSync(file, 'utf8'));
    const [typeName, type] = Object.entries(doc.types).find(([, t]) => t.clips.some((c) => c.timed_rows));
    const timedClip = type.clips.find((c) => c.timed_rows).name;
    const [stateName] = Object.entries(type.states).find(([, s]) => s.clip === timedClip);
    const broken = structuredClone(doc);
    broken.types[typeName].states[stateName].instance.frame_count += 1;
    assert.throws(() => readRoster(JSON.stringify(broken), { name: 'broken.json' }), /cells/);
});
