// herd_check.mjs - what a game needs from CrowdbakeHerd (runtimes/web/crowdbake_three.mjs), checked in
// headless Chromium against three.js itself and the WebGL2 runtime:
//   shadows  - the herd's shadow on a ground plane (directional, spot and point lights) against the
//              shadow of three's own SkinnedMesh + AnimationMixer at the same clip time; the same
//              herd with an unskinned depth material as the negative control;
//   culling  - draw calls (renderer.info) with the herd in view, behind the camera, moved back in;
//   bounds   - every vertex of every baked row and mid-row (the runtime's transform feedback,
//              crowdbake_crowd.mjs) inside the herd's box and sphere at three placements; the bind
//              pose's box as the negative control;
//   variety  - setColorAt tints, a scaled instance's size in pixels and its clip rate;
//   motion   - motionVectorMaterial's velocity image against the finite difference of three's
//              CPU skinning (SkinnedMesh.getVertexPosition) at t - dt and t, rasterized by three.
//
//   node tests/runtimes/browser/herd_check.mjs DIR
//
// DIR holds fox.glb + fox.pal (root motion kept, as three plays it), cow.glb + cow.pal and
// fish.glb + fish.pal. Prints JSON.
import path from 'node:path';
import { withPage, RUNTIMES, THREE_PAGE } from './driver.mjs';

const [dir] = process.argv.slice(2);

const result = await withPage({ '/': RUNTIMES, '/check/': path.resolve(dir) }, '/__blank.html', async (p) => {
    await p.setContent(THREE_PAGE);
    const r = await p.evaluate(async () => {
        const THREE = await import('three');
        const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
        const { readPal } = await import('/web/crowdbake_pal.mjs');
        const { Crowd, loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
        const { CrowdbakeHerd, meshFromGLTF } = await import('/web/crowdbake_three.mjs');
        const glsl = await loadPaletteGLSL();
        const load = async (name) => ({
            pal: readPal(new Uint8Array(await (await fetch(`/check/${name}.pal`)).arrayBuffer()), { verifyChecksum: true }),
            gltf: await new GLTFLoader().loadAsync(`/check/${name}.glb`),
        });
        const size = 256;
        const renderer = new THREE.WebGLRenderer({ antialias: false });
        renderer.setSize(size, size);
        const read = (target, Type = Uint8Array) => {
            const px = new Type(size * size * 4);
            renderer.readRenderTargetPixels(target, 0, 0, size, size, px);
            return px;
        };
        const share = (a, b) => { // the share of the pixels set in either mask where they differ
            let covered = 0, differ = 0;
            for (let i = 0; i < a.length; ++i) covered += a[i] || b[i], differ += a[i] !== b[i];
            return differ / Math.max(covered, 1);
        };
        const fox = await load('fox');
        const walk = fox.pal.clips.find((c) => c.name === 'Walk');
        const lo = new THREE.Vector3(...walk.bounds_min), hi = new THREE.Vector3(...walk.bounds_max);
        const center = lo.clone().add(hi).multiplyScalar(0.5), extent = hi.clone().sub(lo).length();
        const mixer = new THREE.AnimationMixer(fox.gltf.scene);
        mixer.clipAction(fox.gltf.animations.find((a) => a.name === 'Walk')).play();
        const ortho = (half) => new THREE.OrthographicCamera(-half, half, half, -half, 0.01 * extent, 20 * extent);
        const herdOf = (asset, options = {}) => {
            const herd = new CrowdbakeHerd(asset.gltf, asset.pal, null, { count: 1, glsl, ...options });
            herd.setState(0, 'Walk', { phase: 0, fade: 0 });
            return herd;
        };

        // Shadows: the casters write no colour and no depth in the view, only in the light's shadow
        // map; the view camera looks straight down at the lit ground, so the image is the shadow alone.
        const shadows = () => {
            renderer.shadowMap.enabled = true;
            renderer.shadowMap.type = THREE.BasicShadowMap;
            const target = new THREE.WebGLRenderTarget(size, size);
            const ground = new THREE.Mesh(new THREE.PlaneGeometry(extent * 8, extent * 8).rotateX(-Math.PI / 2),
                                          new THREE.MeshLambertMaterial({ color: 0xffffff }));
            ground.position.set(center.x, lo.y - extent * 0.01, center.z);
            ground.receiveShadow = true;
            const view = ortho(extent);
            view.position.set(center.x, lo.y + extent * 4, center.z);
            view.up.set(0, 0, -1);
            view.lookAt(center.x, lo.y, center.z);
            const lights = {
                directional: () => {
                    const l = new THREE.DirectionalLight(0xffffff, 3);
                    l.position.copy(center).add(new THREE.Vector3(extent * 0.6, extent * 2, extent * 0.3));
                    l.target.position.copy(center);
                    Object.assign(l.shadow.camera, { left: -extent, right: extent, top: extent, bottom: -extent,
                                                     near: 0.01 * extent, far: 6 * extent });
                    return l;
                },
                spot: () => {
                    const l = new THREE.SpotLight(0xffffff, 3, 0, Math.PI / 4, 0, 0);
                    l.position.copy(center).add(new THREE.Vector3(-extent * 0.4, extent * 1.5, extent * 0.3));
                    l.target.position.copy(center);
                    Object.assign(l.shadow.camera, { near: 0.01 * extent, far: 6 * extent });
                    return l;
                },
                point: () => {
                    const l = new THREE.PointLight(0xffffff, 3, 0, 0);
                    l.position.copy(center).add(new THREE.Vector3(extent * 0.3, extent * 1.2, extent * 0.2));
                    Object.assign(l.shadow.camera, { near: 0.01 * extent, far: 6 * extent });
                    return l;
                },
            };
            const casters = {
                reference: fox.gltf.scene,
                herd: herdOf(fox),
                unskinned: Object.assign(herdOf(fox), { // three's own depth materials: no skinning
                    customDepthMaterial: new THREE.MeshDepthMaterial({ depthPacking: THREE.RGBADepthPacking }),
                    customDistanceMaterial: new THREE.MeshDistanceMaterial() }),
            };
            const unseen = new THREE.MeshBasicMaterial({ colorWrite: false, depthWrite: false });
            fox.gltf.scene.traverse((o) => { if (o.isMesh) Object.assign(o, { material: unseen, frustumCulled: false }); });
            for (const c of Object.values(casters)) {
                c.traverse((o) => { o.castShadow = true; });
                if (c.isInstancedMesh) [c.material].flat().forEach((m) => Object.assign(m, { colorWrite: false, depthWrite: false }));
            }
            const out = {};
            for (const [name, make] of Object.entries(lights)) {
                const light = make();
                light.castShadow = true;
                light.shadow.mapSize.set(1024, 1024);
                light.shadow.camera.updateProjectionMatrix();
                const mask = (caster, t) => {
                    const scene = new THREE.Scene();
                    scene.add(ground, light, caster);
                    if (light.target) scene.add(light.target);
                    mixer.setTime(t);
                    if (caster.update) caster.update(t);
                    renderer.setRenderTarget(target);
                    renderer.setClearColor(0x000000, 1);
                    renderer.render(scene, view);
                    const px = read(target);
                    scene.remove(ground, light, caster);
                    return Array.from({ length: size * size }, (_, i) => px[i * 4] < 40 && px[i * 4 + 3] > 0);
                };
                const rows = [];
                for (const t of [0.1, 0.37]) {
                    const m = Object.fromEntries(Object.entries(casters).map(([k, c]) => [k, mask(c, t)]));
                    rows.push({ time: t, shadow_pixels: m.herd.filter(Boolean).length, herd: share(m.herd, m.reference),
                                unskinned: share(m.unskinned, m.reference), masks: m });
                }
                out[name] = { rows: rows.map(({ masks, ...r }) => r),
                              between_times: share(rows[0].masks.herd, rows[1].masks.herd),
                              reference_between_times: share(rows[0].masks.reference, rows[1].masks.reference) };
            }
            renderer.shadowMap.enabled = false;
            return out;
        };

        // Culling: draw calls of one frame with the herd in view, behind, and an instance moved back.
        const culling = () => {
            const herd = new CrowdbakeHerd(fox.gltf, fox.pal, null, { count: 3, glsl });
            const scene = new THREE.Scene();
            scene.add(herd);
            [0, 1, 2].forEach((i) => herd.place(i, [center.x + (i - 1) * extent, 0, center.z]));
            const camera = new THREE.PerspectiveCamera(50, 1, extent * 0.05, extent * 50);
            camera.position.copy(center).add(new THREE.Vector3(0, extent * 0.5, extent * 4));
            camera.lookAt(center);
            const calls = () => {
                herd.update(0.3);
                renderer.setRenderTarget(null);
                renderer.render(scene, camera);
                return renderer.info.render.calls;
            };
            const inView = calls();
            camera.lookAt(center.clone().add(new THREE.Vector3(0, 0, extent * 8))); // the herd behind the camera
            const behind = calls();
            herd.place(1, [center.x, 0, center.z + extent * 12]); // one walks round into view
            const movedIntoView = calls();
            return { in_view: inView, behind, moved_into_view: movedIntoView, frustum_culled: herd.frustumCulled };
        };

        // Bounds: every vertex of every row and mid-row, skinned by the WebGL2 runtime's transform
        // feedback, placed three ways, against the herd's box and sphere at each placement.
        const bounds = async (name) => {
            const asset = await load(name);
            const mesh = meshFromGLTF(asset.gltf);
            const gl = document.createElement('canvas').getContext('webgl2');
            const placements = [{ position: [0, 0, 0], yaw: 0, scale: 1 }, { position: [3, -1, 5], yaw: 2.1, scale: 0.5 },
                                { position: [-7, 2, 1], yaw: -0.7, scale: 2.5 }];
            const instances = [];
            for (const c of asset.pal.clips)
                for (let r = 0; r < c.frames; ++r)
                    for (const at of [r, r + 0.5]) // rate 0, the phase on the row or half-way to the next
                        instances.push({ inst: [c.first_row, c.loops ? c.frames : -c.frames, 0, at / c.frames] });
            const crowd = new Crowd(gl, { pal: asset.pal, glsl, mesh, capacity: instances.length, captureWorld: true });
            instances.forEach((inst, i) => crowd.setInstance(i, inst));
            const world = crowd.capture(0);
            const herd = new CrowdbakeHerd(mesh, asset.pal, null, { count: 1, glsl });
            const bind = new THREE.BufferGeometry().setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
            bind.computeBoundingBox();
            const height = asset.pal.header.model_height || 1;
            let worstBox = -Infinity, worstSphere = -Infinity, outsideBind = 0;
            const v = new THREE.Vector3(), n = crowd.vertexCount;
            placements.forEach((pl) => {
                herd.place(0, pl.position, pl);
                herd.computeBoundingBox();
                herd.computeBoundingSphere();
                const box = herd.boundingBox, sphere = herd.boundingSphere;
                const turn = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 1, 0), pl.yaw);
                const m = new THREE.Matrix4().compose(new THREE.Vector3(...pl.position), turn, new THREE.Vector3().setScalar(pl.scale));
                const bindBox = bind.boundingBox.clone().applyMatrix4(m); // the negative control
                for (let i = 0; i < instances.length; ++i)
                    for (let j = 0; j < n; ++j) {
                        v.fromArray(world, (i * n + j) * 3).applyMatrix4(m);
                        const out = Math.max(box.min.x - v.x, v.x - box.max.x, box.min.y - v.y, v.y - box.max.y,
                                             box.min.z - v.z, v.z - box.max.z); // > 0: outside
                        worstBox = Math.max(worstBox, out / (height * pl.scale));
                        worstSphere = Math.max(worstSphere, (v.distanceTo(sphere.center) - sphere.radius) / (height * pl.scale));
                        outsideBind += !bindBox.containsPoint(v);
                    }
            });
            return { vertices: n, instances: instances.length, worst_outside_box: worstBox, worst_outside_sphere: worstSphere,
                     outside_bind_pose_box: outsideBind };
        };

        // Per-instance variety: tints, a scaled instance, and its clip rate at a world speed.
        const variety = () => {
            const white = new THREE.MeshBasicMaterial({ color: 0xffffff });
            const herd = new CrowdbakeHerd(fox.gltf, fox.pal, null, { count: 2, glsl, material: white });
            herd.place(0, [center.x - extent * 0.6, 0, center.z]);
            herd.place(1, [center.x + extent * 0.9, 0, center.z], { scale: 2 });
            herd.setColorAt(0, new THREE.Color(1, 0, 0));
            herd.setColorAt(1, new THREE.Color(0, 0, 1));
            herd.instanceColor.needsUpdate = true;
            for (const i of [0, 1]) herd.setState(i, 'Survey', { phase: 0, fade: 0 });
            herd.update(0);
            const camera = ortho(extent * 1.5);
            camera.position.set(center.x, center.y, center.z + extent * 5);
            camera.lookAt(center.x, center.y, center.z - extent);
            const scene = new THREE.Scene();
            scene.add(herd);
            const target = new THREE.WebGLRenderTarget(size, size);
            renderer.setRenderTarget(target);
            renderer.setClearColor(0x000000, 1);
            renderer.render(scene, camera);
            const px = read(target);
            const colour = { red: { rows: new Set(), pixels: 0, left: 0 }, blue: { rows: new Set(), pixels: 0, left: 0 } };
            for (let y = 0; y < size; ++y)
                for (let x = 0; x < size; ++x) {
                    const [r, , b] = px.subarray((y * size + x) * 4);
                    const c = r > 128 && b < 40 ? colour.red : b > 128 && r < 40 ? colour.blue : null;
                    if (c) c.rows.add(y), c.pixels++, c.left += x < size / 2;
                }
            // Rates: a locomotion state made from the Walk clip with a speed reference of 50 units/s.
            const speedReference = 50;
            herd.states.stride = { clip: 'Walk', first_row: walk.first_row, frame_count: walk.frames, rate: walk.fps,
                                   rate_per_speed: walk.fps / speedReference, phase: 'zero' };
            const rateOf = (i) => herd.geometry.attributes.cb_inst.array[i * 4 + 2];
            const frameOf = (i) => {
                const [, frames, rate, phase] = herd.geometry.attributes.cb_inst.array.subarray(i * 4, i * 4 + 4);
                return herd.time * rate + phase * frames;
            };
            herd.update(1.3);
            for (const i of [0, 1]) herd.setState(i, 'stride', { speed: 80, fade: 0 });
            const rateScale2 = rateOf(1), before = frameOf(1);
            herd.place(1, [center.x + extent * 0.9, 0, center.z], { scale: 4 }); // grows while walking
            return {
                red: { pixels: colour.red.pixels, left: colour.red.left, height: colour.red.rows.size },
                blue: { pixels: colour.blue.pixels, left: colour.blue.left, height: colour.blue.rows.size },
                rate_scale_1: rateOf(0), expected_rate_scale_1: walk.fps * 80 / speedReference,
                rate_scale_2: rateScale2, expected_rate_scale_2: walk.fps * 80 / (2 * speedReference),
                rate_scale_4: rateOf(1), expected_rate_scale_4: walk.fps * 80 / (4 * speedReference),
                frame_before_rescale: before, frame_after_rescale: frameOf(1),
            };
        };

        // Motion vectors: the herd's velocity image against three's CPU skinning at t - dt and t,
        // projected and written per vertex, rasterized by three's own skinned mesh at t.
        const motion = () => {
            const t = 0.37, dt = 1 / 30;
            const camera = ortho(extent * 0.6);
            camera.position.copy(center).add(new THREE.Vector3(extent * 3, extent * 0.5, extent * 1));
            camera.lookAt(center);
            camera.updateMatrixWorld();
            const target = new THREE.WebGLRenderTarget(size, size, { type: THREE.FloatType });
            const image = (scene) => {
                renderer.setRenderTarget(target);
                renderer.setClearColor(0x000000, 0);
                renderer.render(scene, camera);
                return read(target, Float32Array);
            };
            let skinned = null;
            fox.gltf.scene.traverse((o) => { if (o.isSkinnedMesh && !skinned) skinned = o; });
            const projected = (time) => {
                mixer.setTime(time);
                fox.gltf.scene.updateMatrixWorld(true);
                const n = skinned.geometry.attributes.position.count, out = new Float32Array(n * 2), v = new THREE.Vector3();
                for (let i = 0; i < n; ++i) {
                    skinned.getVertexPosition(i, v).applyMatrix4(skinned.matrixWorld).project(camera);
                    out[i * 2] = v.x, out[i * 2 + 1] = v.y;
                }
                return out;
            };
            const before = projected(t - dt), now = projected(t);
            const velocity = now.map((x, i) => 0.5 * (x - before[i]));
            skinned.geometry.setAttribute('ref_velocity', new THREE.BufferAttribute(velocity, 2));
            const show = new THREE.MeshBasicMaterial();
            show.onBeforeCompile = (s) => {
                s.vertexShader = s.vertexShader.replace('#include <common>', '#include <common>\nin vec2 ref_velocity; out vec2 v_ref;')
                    .replace('#include <begin_vertex>', '#include <begin_vertex>\nv_ref = ref_velocity;');
                s.fragmentShader = s.fragmentShader.replace('#include <common>', '#include <common>\nin vec2 v_ref;')
                    .replace('#include <dithering_fragment>', 'gl_FragColor = vec4(v_ref, 0.0, 1.0);');
            };
            show.customProgramCacheKey = () => 'ref-velocity';
            skinned.material = show;
            const reference = new THREE.Scene();
            reference.add(fox.gltf.scene); // mixer at t
            const want = image(reference);
            const herd = herdOf(fox);
            herd.setState(0, 'Walk', { phase: 0, fade: 0 });
            herd.material = herd.motionVectorMaterial();
            const scene = new THREE.Scene();
            scene.add(herd);
            const compare = (previous) => {
                herd.update(previous);
                herd.update(t);
                const got = image(scene);
                let error = 0, magnitude = 0, common = 0;
                for (let i = 0; i < size * size; ++i) {
                    if (got[i * 4 + 3] !== 1 || want[i * 4 + 3] !== 1) continue;
                    common++;
                    error += Math.hypot(got[i * 4] - want[i * 4], got[i * 4 + 1] - want[i * 4 + 1]);
                    magnitude += Math.hypot(want[i * 4], want[i * 4 + 1]);
                }
                return { pixels: common, mean_velocity_px: (magnitude / Math.max(common, 1)) * size, error: error / magnitude };
            };
            return { dt, herd: compare(t - dt), no_previous_frame: compare(t), wrong_direction: compare(t + dt) };
        };

        return { three: THREE.REVISION, shadows: shadows(), culling: culling(), variety: variety(), motion: motion(),
                 bounds: { cow: await bounds('cow'), fish: await bounds('fish') } };
    });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
