// local_check.mjs - local rows (.pal version 6) drawn by the web runtimes in headless Chromium (SwiftShader), against
// the global bake of the same model and against the reader's own composition on the CPU.
//
//   node tests/runtimes/browser/local_check.mjs DIR NAME:CLIP:FROM_CLIP ...
//
// DIR holds NAME.glb, NAME.pal (global rows) and NAME-local.pal (local rows; each is drawn with its own rows). Per model, ten instances of
// CLIP (golden-ratio phases, two cross-fading from FROM_CLIP) at two times:
// - capture: the WebGL2 Crowd's skinned vertices (transform feedback) of the local palette, per vertex ('direct') and
//   through the bone pass ('bones'), against the CPU skinning with the reader's composed bone matrices
//   (instanceBoneMatrix / instanceBoneMatrixCrossfade: the same local palette) and against the global palette drawn the
//   same way; two broken runtimes the same way: the local rows drawn as global ('no_local': CB_LOCAL_ROWS and the
//   bind texture's rows 2..4 left out) and the shader's compose step skipped ('no_compose');
// - image: the eight steady ones drawn lit (Crowd: direct, bone pass, the LOD's tiers drawn apart; CrowdbakeHerd: per vertex and bone
//   pass, the LOD's tiers drawn apart) against the global palette's image: the share of covered pixels that differ;
// - sockets: CrowdbakeHerd.boneMatrixAt of every bone (cross-fades included) against the global palette's.
// Errors are in model heights (the palette header's model_height). Prints JSON; tests/runtimes/test_web_local.c judges.
import { withPage, checkRoutes, THREE_PAGE } from './driver.mjs';

const [dir, ...specs] = process.argv.slice(2);
const models = specs.map((s) => { const [name, clip, from] = s.split(':'); return { name, clip, from }; });

const result = await withPage(checkRoutes(dir), '/__blank.html', async (p) => {
    await p.setContent(THREE_PAGE);
    const out = {};
    for (const model of models) {
        out[model.name] = await p.evaluate(async ({ name, clip, from }) => {
            const THREE = await import('three');
            const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
            const { readPal, clipInstance, instanceBoneMatrix, instanceBoneMatrixCrossfade } = await import('/web/crowdbake_pal.mjs');
            const { Crowd, loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
            const { CrowdbakeHerd, meshFromGLTF } = await import('/web/crowdbake_three.mjs');
            const { offscreen, clipBox, cameraOn, compareColours } = await import('/tests/page_draw.mjs');
            const read = async (file) => readPal(new Uint8Array(await (await fetch(`/check/${file}`)).arrayBuffer()), { name: file, verifyChecksum: true });
            const global = await read(`${name}.pal`), local = await read(`${name}-local.pal`);
            const glsl = await loadPaletteGLSL(), gltf = await new GLTFLoader().loadAsync(`/check/${name}.glb`);
            const mesh = meshFromGLTF(gltf), height = local.header.model_height;
            // Each palette's own rows for the clips (the two bakes may choose different rates).
            const clipOf = (pal, n) => pal.clips.find((k) => k.name === n);
            const instOf = (k, phase) => clipInstance(k, 1, phase); // a timed clip's too (.pal version 7)
            const { center, extent } = clipBox(clipOf(global, clip));
            const place = (i) => [center.x + ((i % 5) - 2) * extent * 0.45, 0, (Math.floor(i / 5) - 0.5) * extent * 0.6];
            // Eight steady instances, then (fading) two cross-fading from FROM_CLIP: a local cross-fade blends each bone's
            // local poses before composing, a global one mixes matrices, so those two differ by design.
            const instances = (t, pal, fading = true) => Array.from({ length: fading ? 10 : 8 }, (_, i) => ({
                position: place(i), yaw: i * 0.6, inst: instOf(clipOf(pal, clip), (i * 0.618034) % 1),
                ...(i >= 8 ? { from: instOf(clipOf(pal, from), 0.3 * i % 1), fadeStart: t - 0.1 * (i - 7), fadeDuration: 0.4 } : {}) }));
            const canvas = document.createElement('canvas');
            canvas.width = canvas.height = 320;
            const gl = canvas.getContext('webgl2', { antialias: false });
            const crowdOf = (pal, options, t, shader = glsl, fading = true) => {
                const crowd = new Crowd(gl, { pal, glsl: shader, mesh, capacity: 10, ...options });
                instances(t, pal, fading).forEach((o, i) => crowd.setInstance(i, o));
                return crowd;
            };
            // The CPU's skinning of the same instances with the reader's composed bones.
            const cpuSkin = (pal, t) => {
                const n = mesh.positions.length / 3, got = new Float32Array(10 * n * 3);
                instances(t, pal).forEach((o, i) => {
                    const fade = o.from ? Math.min(Math.max((t - o.fadeStart) / o.fadeDuration, 0), 1) : 1;
                    const bones = Array.from({ length: pal.header.bone_count }, (_, j) => (fade < 1
                        ? instanceBoneMatrixCrossfade(pal, o.from, o.inst, fade, t, j) : instanceBoneMatrix(pal, o.inst, t, j)));
                    const c = Math.cos(o.yaw), s = Math.sin(o.yaw);
                    for (let v = 0; v < n; ++v) {
                        const x = mesh.positions.subarray(3 * v, 3 * v + 3), p = [0, 0, 0];
                        for (let k = 0; k < 4; ++k) {
                            const w = mesh.weights[4 * v + k], m = bones[mesh.joints[4 * v + k]];
                            if (w) for (let r = 0; r < 3; ++r) p[r] += w * (m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r]);
                        }
                        got.set([o.position[0] + c * p[0] + s * p[2], o.position[1] + p[1], o.position[2] - s * p[0] + c * p[2]], (i * n + v) * 3);
                    }
                });
                return got;
            };
            // The largest difference in model heights: of the eight steady instances, and of the two cross-fading ones.
            const n3 = mesh.positions.length;
            const worstOf = (a, b, lo, hi) => { let m = 0; for (let i = lo * n3; i < hi * n3; ++i) m = Math.max(m, Math.abs(a[i] - b[i])); return m / height; };
            const worst = (a, b) => ({ steady: worstOf(a, b, 0, 8), fading: worstOf(a, b, 8, 10) });
            const capture = (pal, options, t, shader) => crowdOf(pal, { ...options, captureWorld: true }, t, shader).capture(t);
            const noLocal = { ...local, header: { ...local.header, flags: local.header.flags & ~32 },
                              bones: local.bones.map((b) => ({ ...b, range: undefined })) };
            const lines = glsl.split('\n'), at = lines.findIndex((l) => l.includes('cb:local-compose'));
            if (at < 0) throw new Error('cb:local-compose is not in the shader');
            const noCompose = [...lines.slice(0, at), '        // compose skipped (a broken runtime)', ...lines.slice(at + 1)].join('\n');
            const camera = cameraOn(new THREE.Vector3(center.x, center.y, 0), extent * 2.6, { fov: 35, offset: [0.2, 0.5, 1.2] });
            camera.updateMatrixWorld();
            const vp = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).elements;
            const crowdImage = (crowd, t) => {
                gl.viewport(0, 0, 320, 320);
                gl.enable(gl.DEPTH_TEST);
                gl.clearColor(0, 0, 0, 0);
                gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
                crowd.draw(vp, t);
                const px = new Uint8Array(320 * 320 * 4);
                gl.readPixels(0, 0, 320, 320, gl.RGBA, gl.UNSIGNED_BYTE, px);
                return px;
            };
            const view = offscreen(320);
            const herdOf = (pal, options) => {
                const herd = new CrowdbakeHerd(gltf, pal, null, { count: 8, glsl, lodTiers: false, ...options });
                instances(0, pal, false).forEach((o, i) => herd.place(i, o.position, { yaw: o.yaw }));
                return herd;
            };
            const herds = { global: herdOf(global, { bonePass: false }), direct: herdOf(local, { bonePass: false }),
                            bones: herdOf(local, { bonePass: true }), global_bones: herdOf(global, { bonePass: true }),
                            tiers: herdOf(local, { bonePass: true, lodTiers: true }), global_tiers: herdOf(global, { bonePass: true, lodTiers: true }) };
            const rows = [];
            for (const t of [0.4, 1.3]) {
                const row = { time: t, capture: {}, image: {}, herd: {} };
                const cpu = cpuSkin(local, t), reference = capture(global, { bonePass: false }, t);
                for (const [what, pal, options, shader] of [['direct', local, { bonePass: false }], ['bones', local, { bonePass: true, lod: false }],
                                                            ['no_local', noLocal, { bonePass: false }], ['no_compose', local, { bonePass: false }, noCompose]]) {
                    const got = capture(pal, options, t, shader);
                    row.capture[what] = { vs_cpu: worst(got, cpu), vs_global: worst(got, reference) };
                }
                row.capture.cpu_vs_global = worst(cpu, reference);
                row.capture.global_vs_its_cpu = worst(reference, cpuSkin(global, t)); // the harness's own floor
                const want = crowdImage(crowdOf(global, { bonePass: false }, t, glsl, false), t);
                for (const [what, pal, options] of [['direct', local, { bonePass: false }], ['bones', local, { bonePass: true, lod: false }],
                                                    ['tiers', local, { bonePass: true }], ['no_local', noLocal, { bonePass: false }]])
                    row.image[what] = compareColours(want, crowdImage(crowdOf(pal, options, t, glsl, false), t), 24);
                // The herd: the instances' states set as the Crowd's (cross-fades from FROM_CLIP at the same moments).
                const images = {};
                for (const [what, herd] of Object.entries(herds)) {
                    instances(t, herd.pal, false).forEach((o, i) => {
                        const a = herd.geometry.attributes;
                        a.cb_inst.array.set(o.inst, i * 4), a.cb_from.array.set(o.inst, i * 4);
                        a.cb_inst.needsUpdate = a.cb_from.needsUpdate = true;
                    });
                    herd.update(t, view.renderer, what.endsWith('tiers') ? camera : undefined); // the camera: tiers drawn apart
                    images[what] = view.image(herd, camera);
                }
                row.herd.direct = compareColours(images.global, images.direct, 24);
                row.herd.bones = compareColours(images.global_bones, images.bones, 24);
                row.herd.tiers = compareColours(images.global_tiers, images.tiers, 24);
                // Each joint where boneMatrixAt puts it (the bone's matrix at its bind position), local against global.
                let socket = 0;
                for (let i = 0; i < 8; ++i)
                    for (let j = 0; j < local.header.bone_count; ++j) {
                        const b = new THREE.Vector3(...local.bones[j].bind_position);
                        const at = (herd) => b.clone().applyMatrix4(herd.boneMatrixAt(i, j));
                        socket = Math.max(socket, at(herds.direct).distanceTo(at(herds.global)) / height);
                    }
                row.herd.joints_vs_global = socket;
                rows.push(row);
            }
            return { vertices: mesh.positions.length / 3, bones: local.header.bone_count, precision: local.header.precision_name,
                     local_rows: [new Crowd(gl, { pal: local, glsl, mesh, capacity: 1 }).localRows, herds.direct.localRows],
                     rows: local.header.rows, global_rows: global.header.rows, results: rows };
        }, model);
    }
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return out;
});
console.log(JSON.stringify(result));
