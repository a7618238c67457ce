// viewer.mjs - the page `crowdbake view` serves: a herd walking about, a button per state
// (cross-fading), up to 100,000 instances in one draw call, the palette and the VAT of the same
// frames side by side with the VRAM of each, frame time and draw calls on screen.
// It reads /view.json (written by the command): { roster, types: [{ name, model, palette?, vat }] }.
// Test hooks: window.crowdbakeViewer (ready, renderAt(t), setCount(n), setState(name), stats()).
// ?paused stops the clock (tests render chosen times); ?count=N starts with N instances, any
// whole number from 0 to 100,000 (more is capped there, anything else keeps 1000, and the panel
// says so).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { decompress } from 'fzstd';
import { readPal, readRoster, instanceData, clipInstance, hasLocalRows } from '../web/crowdbake_pal.mjs';
import { Crowd, GLSL_URL, loadPaletteGLSL } from '../web/crowdbake_crowd.mjs';
import { VatCrowd, readVat, vatLayout } from '../web/crowdbake_vat.mjs';
import { meshFromGLTF } from '../web/crowdbake_three.mjs';

const MAX = 100000;
const params = new URLSearchParams(location.search);
const $ = (id) => document.getElementById(id);
const canvas = $('view');
const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
const kib = (n) => (n >= 1 << 20 ? `${(n / (1 << 20)).toFixed(1)} MiB` : `${(n / 1024).toFixed(1)} KiB`);

async function bytesOf(url) {
    const r = await fetch(url);
    if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
    return new Uint8Array(await r.arrayBuffer());
}

// One animal type: its palette crowd, its VAT crowd (or null), states and the herd's motion.
async function loadType(view, entry, glsl) {
    let rosterType = null, palUrl = entry.palette;
    if (view.roster) {
        const roster = readRoster(await (await fetch(`/${view.roster}`)).text(), { name: view.roster });
        rosterType = roster.types[entry.name];
        palUrl = `${view.roster.replace(/[^/]*$/, '')}${rosterType.palette}`;
    }
    const pal = readPal(await bytesOf(`/${palUrl}`), { name: palUrl, verifyChecksum: true,
                                                        decompress: (b, n) => decompress(b, new Uint8Array(n)) });
    const gltf = await new GLTFLoader().loadAsync(`/${entry.model}`);
    const mesh = meshFromGLTF(gltf);
    // lodTiers: false - one draw call per herd, as the panel states and compares with the VAT's (the tiers drawn
    // apart would add one a tier).
    const crowd = new Crowd(gl, { pal, glsl, mesh, capacity: MAX, color: [0.86, 0.78, 0.62], lodTiers: false,
                                  animationLod: rosterType?.animation_lod });
    let vat = null, vatNote = 'no VAT for this type';
    const vatFrames = vatLayout(pal); // a timed clip's VAT frames are its cells
    if (entry.vat) {
        try {
            const v = readVat(await bytesOf(`/${entry.vat}`), entry.vat);
            if (v.frames !== vatFrames.frames) throw new Error(`${v.frames} VAT frames, the palette's clips make ${vatFrames.frames}`);
            vat = new VatCrowd(gl, { pal, vat: v, glsl, mesh, capacity: MAX, color: [0.62, 0.74, 0.86] });
        } catch (e) {
            vatNote = `VAT not shown: ${e.message}`;
        }
    }
    const states = rosterType ? rosterType.states : Object.fromEntries(pal.clips.map((c) => {
        const [first_row, frame_count, rate] = clipInstance(c); // a timed clip: its cells, a negative rate
        return [c.name, { clip: c.name, first_row, frame_count, rate, rate_per_speed: 0, phase: c.loops ? 'golden_ratio' : 'zero' }];
    }));
    // Ground speed of a state: its clip's (roster), so locomotion plays with planted feet.
    const speedOf = (s) => (s.rate_per_speed !== 0 ? (rosterType.clips.find((c) => c.name === s.clip)?.ground_speed ?? 0) : 0);
    // The skinned size (the clips' bounds): the mesh's own units may differ (a scaled skeleton).
    const lo = [0, 1, 2].map((k) => Math.min(...pal.clips.map((c) => c.bounds_min[k])));
    const hi = [0, 1, 2].map((k) => Math.max(...pal.clips.map((c) => c.bounds_max[k])));
    const size = Math.max(hi[0] - lo[0], hi[2] - lo[2], hi[1] - lo[1]);
    return { name: entry.name, pal, crowd, vat, vatNote, vatInstanceOf: vatFrames.instanceOf, states, speedOf, size, height: hi[1] - lo[1],
             defaultState: rosterType?.default_state ?? Object.keys(states)[0] };
}

// ?count=TEXT as a number of instances and what the panel says about it ('' when taken as is).
function countFromQuery(text) {
    if (!/^\d+$/.test(text.trim())) return { n: 1000, note: `?count=${text}: not a whole number of instances; showing 1000` };
    const n = Number(text);
    if (n > MAX) return { n: MAX, note: `?count=${text}: capped at ${MAX} instances, the viewer's capacity` };
    return { n, note: '' };
}

// The count selector holds n: the menu's own values, or n added in its place among them.
function selectCount(select, n) {
    if (![...select.options].some((o) => +o.value === n)) {
        const after = [...select.options].find((o) => +o.value > n) ?? null;
        select.insertBefore(Object.assign(document.createElement('option'), { textContent: String(n) }), after);
    }
    select.value = String(n);
}

// The herd: positions, headings and states in typed arrays, moved on the CPU each frame.
class Herd {
    constructor(type) {
        this.type = type;
        this.x = new Float32Array(MAX), this.z = new Float32Array(MAX), this.heading = new Float32Array(MAX);
        this.turn = new Float32Array(MAX), this.speed = new Float32Array(MAX), this.state = new Array(MAX);
        this.count = 0;
        this.time = 0;
    }

    setCount(n) {
        n = Math.max(0, Math.min(MAX, Math.floor(n) || 0)); // the typed arrays and crowds hold MAX
        const t = this.type, spacing = t.size * 1.6;
        this.side = Math.ceil(Math.sqrt(n)) * spacing;
        for (let i = 0; i < n; ++i) { // a jittered grid, deterministic
            const g = Math.ceil(Math.sqrt(n)), r1 = (i * 0.7548776662) % 1, r2 = (i * 0.5698402910) % 1;
            this.x[i] = ((i % g) + r1 * 0.8 - g / 2) * spacing;
            this.z[i] = (Math.floor(i / g) + r2 * 0.8 - g / 2) * spacing;
            this.heading[i] = (i * 2.399963) % (2 * Math.PI);
            this.turn[i] = ((i * 0.618034) % 1 - 0.5) * 0.6;
        }
        this.count = n;
        for (const c of [t.crowd, t.vat]) if (c) c.setCount(n);
        for (let i = 0; i < n; ++i) this.setState(i, this.state[i] ?? t.defaultState, 0);
    }

    setState(i, name, fade = 0.3) {
        const t = this.type, s = t.states[name], speed = t.speedOf(s);
        const inst = instanceData(s, speed, i, this.time);
        const prev = this.state[i] && i < t.crowd.count ? t.crowd.instances.slice(i * 16 + 4, i * 16 + 8) : inst;
        this.state[i] = name;
        this.speed[i] = speed;
        const place = { position: [this.x[i], 0, this.z[i]], yaw: this.heading[i], fadeStart: this.time, fadeDuration: fade };
        t.crowd.setInstance(i, { ...place, inst, from: prev });
        t.vat?.setInstance(i, { ...place, inst: t.vatInstanceOf(inst), from: t.vatInstanceOf(prev) });
    }

    step(dt) {
        const half = this.side / 2, c = this.type.crowd;
        for (let i = 0; i < this.count; ++i) {
            if (this.speed[i] > 0) {
                this.heading[i] += this.turn[i] * dt;
                this.x[i] += Math.sin(this.heading[i]) * this.speed[i] * dt;
                this.z[i] += Math.cos(this.heading[i]) * this.speed[i] * dt;
                if (this.x[i] > half) this.x[i] -= 2 * half; else if (this.x[i] < -half) this.x[i] += 2 * half;
                if (this.z[i] > half) this.z[i] -= 2 * half; else if (this.z[i] < -half) this.z[i] += 2 * half;
            }
            const o = i * 16;
            c.instances[o] = this.x[i], c.instances[o + 2] = this.z[i], c.instances[o + 3] = this.heading[i];
        }
        c.dirty = true;
        const vat = this.type.vat;
        if (vat) { // the places move; each instance's numbers stay the VAT's own
            for (let i = 0; i < this.count; ++i) vat.instances.set(c.instances.subarray(i * 16, i * 16 + 4), i * 16);
            vat.dirty = true;
        }
    }
}

async function main() {
    const view = await (await fetch('/view.json')).json();
    const glsl = await loadPaletteGLSL(GLSL_URL); // the site's glsl/ (crowdbake view serves it)
    const types = [];
    for (const entry of view.types) types.push(await loadType(view, entry, glsl));
    let type = types[0], herd = new Herd(type);
    const frameTimes = [];
    let drawCalls = 0, last = performance.now();

    const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1e6);
    const viewProjection = new THREE.Matrix4();
    function render(time) {
        const w = canvas.clientWidth * devicePixelRatio, h = canvas.clientHeight * devicePixelRatio;
        if (canvas.width !== w || canvas.height !== h) canvas.width = w, canvas.height = h;
        const side = Boolean(type.vat) && $('vat').checked;
        const width = side ? Math.floor(w / 2) : w;
        const d = Math.max(herd.side * 0.4, type.size * 5), a = time * 0.05;
        camera.aspect = width / h;
        camera.position.set(Math.sin(a) * d, d * 0.45, Math.cos(a) * d);
        camera.lookAt(0, type.height * 0.3, 0);
        camera.updateProjectionMatrix();
        camera.updateMatrixWorld();
        viewProjection.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
        gl.enable(gl.DEPTH_TEST);
        gl.enable(gl.SCISSOR_TEST);
        drawCalls = 0;
        const draws = side ? [[type.crowd, 0], [type.vat, width]] : [[type.crowd, 0]];
        for (const [crowd, x] of draws) {
            gl.viewport(x, 0, width, h);
            gl.scissor(x, 0, width, h);
            gl.clearColor(0.13, 0.15, 0.17, 1);
            gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
            drawCalls += crowd.draw(viewProjection.elements, time);
        }
        $('label-vat').style.display = side ? '' : 'none';
        $('label-palette').style.left = side ? '25%' : '50%';
    }

    function stats() {
        const avg = frameTimes.length ? frameTimes.reduce((a, b) => a + b, 0) / frameTimes.length : 0;
        const p = type.crowd.textures.bytes, v = type.vat?.textures.bytes;
        return { frameMs: avg, drawCalls, instances: herd.count, paletteBytes: p, vatBytes: v ?? null,
                 text: `${herd.count} instances, ${drawCalls} draw call${drawCalls === 1 ? '' : 's'} (1 per herd)\n` +
                       (avg ? `frame ${avg.toFixed(2)} ms (${(1000 / avg).toFixed(0)} fps)\n` : 'frame time: paused (a test renders chosen times)\n') +
                       `palette ${type.pal.header.layout_name}/${type.pal.header.precision_name}` +
                       `${hasLocalRows(type.pal.header) ? ' local' : ''} ${kib(p)} VRAM` +
                       (v ? `\nVAT RGBA16F pos+normal ${kib(v)} VRAM (${(v / p).toFixed(1)}x)` : `\n${type.vatNote}`) };
    }

    function buildButtons() {
        $('title').textContent = `crowdbake view: ${type.name}`;
        $('states').replaceChildren(...Object.keys(type.states).map((name) => {
            const b = document.createElement('button');
            b.textContent = name;
            b.onclick = () => setState(name);
            return b;
        }), Object.assign(document.createElement('button'), { textContent: 'mixed', onclick: () => setState(null) }));
        $('types').replaceChildren(...(types.length > 1 ? types.map((t) => Object.assign(document.createElement('button'), {
            textContent: t.name, onclick: () => { type = t; herd = new Herd(t); herd.setCount(+$('count').value); buildButtons(); } }))
            : []));
    }

    // Every instance to `name`; null: a mix of the idle, walking and running states.
    function setState(name) {
        const names = Object.keys(type.states);
        const pick = names.filter((n) => /(^|_)(idle|walk|walking|gallop|run|running|wander|flee|graze)$/i.test(n));
        const pool = pick.length ? pick : names;
        for (let i = 0; i < herd.count; ++i) herd.setState(i, name ?? pool[(i * 7919) % pool.length]);
        for (const b of $('states').children) b.classList.toggle('on', b.textContent === (name ?? 'mixed'));
    }

    $('count').onchange = () => herd.setCount(+$('count').value);
    buildButtons();
    if (params.has('count')) {
        const { n, note } = countFromQuery(params.get('count'));
        selectCount($('count'), n);
        $('notice').textContent = note;
    }
    herd.setCount(+$('count').value);
    const paused = params.has('paused');
    const start = performance.now();
    function frame(now) {
        frameTimes.push(now - last);
        if (frameTimes.length > 60) frameTimes.shift();
        const dt = Math.min((now - last) / 1000, 0.1);
        last = now;
        herd.time = (now - start) / 1000;
        herd.step(dt);
        render(herd.time);
        $('stats').textContent = stats().text;
        requestAnimationFrame(frame);
    }
    window.crowdbakeViewer = {
        types, stats, setState, setCount: (n) => herd.setCount(n),
        renderAt(t) { // a frame at clock time t, the herd moved there from where it is
            herd.step(Math.max(0, t - herd.time));
            herd.time = t;
            render(t);
            $('stats').textContent = stats().text;
            gl.finish();
        },
    };
    if (!paused) requestAnimationFrame(frame);
}

window.crowdbakeReady = main().catch((e) => {
    $('error').textContent = String(e.stack ?? e);
    throw e;
});
