// bench_crowd.mjs - the crowd benchmark (make bench, bench/run.py): frame time of a herd drawn
// from its palette (runtimes/web/crowdbake_crowd.mjs) against the same herd drawn from a VAT of the same
// frames (runtimes/web/crowdbake_vat.mjs), in the same Chromium page, one instanced draw each.
//
//   node tests/runtimes/browser/bench_crowd.mjs DIR N1,N2,... [--frames K] [--gpu] [--methods palette,bones,vat,before]
//       [--before TREE]
//
// Methods: palette (per-vertex blending), bones (Crowd's bonePass: each instance's bones blended
// once, crowdbake_bones.mjs, every influence), lod (the bone pass with its animation LOD), auto (Crowd's
// default: bone pass or not by herd size, LOD on), local_palette, local_bones, local_lod, local_auto (the same four
// drawing DIR/model-local.pal, the model baked --bone-space local: each bone composed down its chain, per vertex
// and influence or once an instance and bone in the bone pass), vat, rest (the mesh unskinned: the floor every method
// pays), before (the palette runtime of another tree TREE - its runtimes/web
// and runtimes/glsl, or an older tree's web/ and samples/shaders/ - e.g. `git worktree add` of an
// older commit: a before/after in one page).
//
// DIR holds model.glb, model.pal and model.exr (the VAT, uncompressed). For each count, palette and
// VAT alternate (so a change in the machine's load hits both alike): each draws K frames of a
// 960x540 canvas, every instance walking, and a frame's time runs from its draw to a 1-pixel
// readPixels (which waits for the GPU). Prints JSON: per count and method, the median and min
// frame ms; the renderer's name (SwiftShader is software: a CPU renderer's absolute times say
// little; the ratio is what compares).
import fs from 'node:fs';
import path from 'node:path';
import { withPage, RUNTIMES, THREE_PAGE } from './driver.mjs';

const [dir, countsText] = process.argv.slice(2);

// CPU time (user + system, ms) of every process under this one: the browser and its GPU process, where
// SwiftShader rasterises. On a machine shared with other work a frame's wall time is as much the
// others' load as its own; the CPU time it took is its own (reported beside the wall time).
function cpuMs() {
    const children = new Map();
    for (const pid of fs.readdirSync('/proc').filter((d) => /^\d+$/.test(d))) {
        try {
            const stat = fs.readFileSync(`/proc/${pid}/stat`, 'utf8'), fields = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
            const list = children.get(fields[1]) ?? [];
            list.push({ pid, ticks: Number(fields[11]) + Number(fields[12]) });
            children.set(fields[1], list);
        } catch { /* the process ended meanwhile */ }
    }
    let ticks = 0;
    const walk = (pid) => { for (const c of children.get(pid) ?? []) ticks += c.ticks, walk(c.pid); };
    walk(String(process.pid));
    return ticks * 10; // USER_HZ: 100 on Linux
}
const frames = Number(process.argv[process.argv.indexOf('--frames') + 1] || 5);
const gpu = process.argv.includes('--gpu');
const counts = countsText.split(',').map(Number);
const option = (name, fallback) => (process.argv.includes(name) ? process.argv[process.argv.indexOf(name) + 1] : fallback);
const methods = option('--methods', 'palette,vat').split(',');
const before = option('--before', null);
// Where TREE's web/ is: runtimes/ since the move, the tree itself before it.
const beforeRoot = (tree) => fs.existsSync(path.join(tree, 'runtimes', 'web')) ? path.resolve(tree, 'runtimes') : path.resolve(tree);

const page = THREE_PAGE + '<canvas id="c" width="960" height="540"></canvas>';

const result = await withPage({ '/': RUNTIMES, '/bench/': path.resolve(dir), ...(before ? { '/before/': beforeRoot(before) } : {}) }, '/__blank.html', async (p) => {
    await p.setContent(page);
    const r = await p.evaluate(async ({ counts, methods }) => {
        const THREE = await import('three');
        const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
        const { readPal, instanceData, clipInstance } = await import('/web/crowdbake_pal.mjs');
        const { Crowd, loadPaletteGLSL, compileProgram } = await import('/web/crowdbake_crowd.mjs');
        // The floor every method pays (triangle setup, rasterisation, the instance's placement): the
        // mesh at rest, no skinning.
        class RestCrowd extends Crowd {
            makeProgram(glsl, header, fragment) {
                return compileProgram(gl, `#version 300 es
in vec3 a_position; in vec3 a_normal; in vec4 a_place; in vec4 a_fade;
uniform mat4 u_view_projection; out vec3 v_world; out vec3 v_normal;
void main() {
    float c = cos(a_place.w), s = sin(a_place.w);
    mat3 yaw = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
    v_world = a_place.xyz + a_fade.z * (yaw * a_position);
    v_normal = yaw * a_normal;
    gl_Position = u_view_projection * vec4(v_world, 1.0);
}`, fragment);
            }
        }
        const { VatCrowd, readVat } = await import('/web/crowdbake_vat.mjs');
        const { meshFromGLTF } = await import('/web/crowdbake_three.mjs');
        const bytes = async (u) => new Uint8Array(await (await fetch(u)).arrayBuffer());
        const gl = document.getElementById('c').getContext('webgl2', { antialias: false });
        const pal = readPal(await bytes('/bench/model.pal'));
        const localPal = methods.some((m) => m.startsWith('local_')) ? readPal(await bytes('/bench/model-local.pal')) : null;
        const vat = readVat(await bytes('/bench/model.exr'));
        const mesh = meshFromGLTF(await new GLTFLoader().loadAsync('/bench/model.glb'));
        const glsl = await loadPaletteGLSL();
        const max = Math.max(...counts);
        const make = {
            palette: () => new Crowd(gl, { pal, glsl, mesh, capacity: max, bonePass: false }),
            bones: () => new Crowd(gl, { pal, glsl, mesh, capacity: max, bonePass: true, lod: false }),
            lod: () => new Crowd(gl, { pal, glsl, mesh, capacity: max, bonePass: true }),
            auto: () => new Crowd(gl, { pal, glsl, mesh, capacity: max }),
            rest: () => new RestCrowd(gl, { pal, glsl, mesh, capacity: max, bonePass: false }),
            vat: () => new VatCrowd(gl, { pal, vat, glsl, mesh, capacity: max }),
            local_palette: () => new Crowd(gl, { pal: localPal, glsl, mesh, capacity: max, bonePass: false }),
            local_bones: () => new Crowd(gl, { pal: localPal, glsl, mesh, capacity: max, bonePass: true, lod: false }),
            local_lod: () => new Crowd(gl, { pal: localPal, glsl, mesh, capacity: max, bonePass: true }),
            local_auto: () => new Crowd(gl, { pal: localPal, glsl, mesh, capacity: max }),
            before: async () => {
                const old = await import('/before/web/crowdbake_crowd.mjs');
                return new old.Crowd(gl, { pal, glsl: await old.loadPaletteGLSL(), mesh, capacity: max });
            },
        };
        const crowds = {};
        for (const m of methods) crowds[m] = await make[m]();
        // Each crowd plays its own palette's rows (a local bake may choose other rates) of the same clip.
        const name = (pal.clips.find((c) => c.loops) ?? pal.clips[0]).name;
        const stateOf = (p) => {
            const [first_row, frame_count, rate] = clipInstance(p.clips.find((c) => c.name === name)); // timed too
            return { first_row, frame_count, rate, rate_per_speed: 0, phase: 'golden_ratio' };
        };
        const size = Math.max(...[0, 1, 2].map((k) => Math.max(...pal.clips.map((c) => c.bounds_max[k] - c.bounds_min[k]))));
        const pixel = new Uint8Array(4);
        let vp = null;
        window.benchPlace = (n) => {
            const g = Math.ceil(Math.sqrt(n)), side = g * size * 1.5;
            for (const c of Object.values(crowds)) {
                const state = stateOf(c.pal ?? pal);
                c.count = 0;
                for (let i = 0; i < n; ++i)
                    c.setInstance(i, { position: [((i % g) - g / 2) * size * 1.5, 0, (Math.floor(i / g) - g / 2) * size * 1.5],
                                       yaw: i * 2.4, inst: instanceData(state, 0, i) });
            }
            // Looking down at the whole herd: every instance in view, none culled by the camera.
            const camera = new THREE.PerspectiveCamera(50, 960 / 540, side * 0.01, side * 10);
            camera.position.set(0, side * 0.8, side * 0.7);
            camera.lookAt(0, 0, 0);
            camera.updateMatrixWorld();
            vp = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).elements;
        };
        window.benchFrame = (method, f) => { // one frame of one method: ms from its draw to a 1-pixel readPixels
            const t0 = performance.now();
            gl.viewport(0, 0, 960, 540);
            gl.enable(gl.DEPTH_TEST);
            gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
            crowds[method].draw(vp, 0.5 + f / 30);
            gl.readPixels(480, 270, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
            return performance.now() - t0;
        };
        const ext = gl.getExtension('WEBGL_debug_renderer_info');
        const perInstance = Object.fromEntries(Object.entries(crowds).map(([m, c]) => [m, c.bytesPerInstance(m.endsWith('palette') ? 'palette'
            : m === 'vat' || m === 'rest' ? 'vat' : c.choice(max).method)]));
        return { renderer: ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER),
                 vertices: mesh.positions.length / 3, palette_bytes: crowds.palette?.textures.bytes,
                 vat_bytes: crowds.vat?.textures.bytes, bone_pass_bytes: crowds.bones?.bones.bytes,
                 local_palette_bytes: crowds.local_palette?.textures.bytes,
                 bytes_per_instance: perInstance,
                 auto_choice: crowds.auto ? Object.fromEntries(counts.map((n) => [n, crowds.auto.choice(n)])) : undefined,
                 local_auto_choice: crowds.local_auto ? Object.fromEntries(counts.map((n) => [n, crowds.local_auto.choice(n)])) : undefined,
                 lod_choice: crowds.auto?.lodChoice().reason ?? crowds.lod?.lodChoice().reason };
    }, { counts, methods });
    r.times = {};
    r.cpu = {};
    for (const n of counts) {
        await p.evaluate((n) => window.benchPlace(n), n);
        r.times[n] = {};
        r.cpu[n] = {};
        for (const method of methods) r.times[n][method] = [], r.cpu[n][method] = [];
        for (let f = -1; f < frames; ++f) // frame -1 warms up (shader compile, upload)
            for (const method of f % 2 ? methods : [...methods].reverse()) {
                const cpu0 = cpuMs();
                const wall = await p.evaluate(([m, f]) => window.benchFrame(m, f), [method, f]);
                const cpu = cpuMs() - cpu0;
                if (f >= 0) r.times[n][method].push(wall), r.cpu[n][method].push(cpu);
            }
    }
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
}, { gpu });

const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const report = { renderer: result.renderer, vertices: result.vertices, palette_bytes: result.palette_bytes,
                 vat_bytes: result.vat_bytes, bone_pass_bytes: result.bone_pass_bytes, bytes_per_instance: result.bytes_per_instance,
                 local_palette_bytes: result.local_palette_bytes, local_auto_choice: result.local_auto_choice,
                 lod_choice: result.lod_choice,
                 auto_choice: result.auto_choice, frames, methods, counts: {} };
for (const [n, m] of Object.entries(result.times)) {
    const c = report.counts[n] = {};
    for (const method of methods) c[`${method}_ms`] = median(m[method]), c[`${method}_min_ms`] = Math.min(...m[method]);
    // Each frame drew every method back to back (in turns): frame f's VAT time over a method's is a pair
    // that one moment's load hit alike; the ratio reported is the median over the pairs.
    if (m.vat) for (const method of methods.filter((x) => x !== 'vat'))
        c[`vat_over_${method}`] = median(m.vat.map((v, f) => v / m[method][f]));
    const cpu = result.cpu[n];
    for (const method of methods) c[`${method}_cpu_ms`] = median(cpu[method]);
    if (cpu.vat) for (const method of methods.filter((x) => x !== 'vat'))
        c[`cpu_vat_over_${method}`] = median(cpu.vat.map((v, f) => v / Math.max(cpu[method][f], 1)));
}
console.log(JSON.stringify(report));
