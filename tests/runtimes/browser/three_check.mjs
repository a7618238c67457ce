// three_check.mjs - the three.js drop-in (runtimes/web/crowdbake_three.mjs, CrowdbakeHerd) against three.js
// itself: the same model skinned by three's own SkinnedMesh + AnimationMixer from the glTF (an
// independent implementation) and by a CrowdbakeHerd instance from the palette, at the same clip
// times, rendered as white silhouettes from the same camera; prints, per time, the share of the
// covered pixels where the two silhouettes disagree. A deliberately broken herd (its skinning patch
// left out: the mesh stays in its bind pose) is measured the same way. So is the WebGL2 Crowd
// (runtimes/web/crowdbake_crowd.mjs), its own canvas, the same camera: per-vertex blending, the bone
// pass, the herd-size choice (bonePass: 'auto' below and above its threshold: which it picked, and its
// pixels) and the animation LOD (forced on at this size: the 2 largest weights, the largest alone; and at its default,
// where an instance this large on screen keeps every influence). And the LOD's tiers drawn apart (Crowd's lodTiers, the
// default) against one draw finding each vertex's tier, on the same decision (9 Foxes, a third on each tier): the bytes
// of the two images that differ (0: the same image), and, to show the check can fail, those that differ from every
// instance on every influence and from every instance on the far tier; the same for CrowdbakeHerd's tiers drawn apart
// (update(time, renderer, camera)) against its one draw (update(time, renderer)).
//
//   node tests/runtimes/browser/three_check.mjs DIR CLIP T1,T2,...
//
// DIR holds model.glb and model.pal (baked with root motion kept, as three plays it). Prints JSON.
import path from 'node:path';
import { withPage, checkRoutes, THREE_PAGE } from './driver.mjs';

const [dir, clip, timesText] = process.argv.slice(2);
const times = timesText.split(',').map(Number);

const result = await withPage(checkRoutes(dir), '/__blank.html', async (p) => {
    await p.setContent(THREE_PAGE);
    const r = await p.evaluate(async ({ clip, times }) => {
        const THREE = await import('three');
        const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
        const { readPal, clipInstance } = await import('/web/crowdbake_pal.mjs');
        const { Crowd, loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
        const { CrowdbakeHerd, meshFromGLTF } = await import('/web/crowdbake_three.mjs');
        const pal = readPal(new Uint8Array(await (await fetch('/check/model.pal')).arrayBuffer()), { verifyChecksum: true });
        const glsl = await loadPaletteGLSL();
        const gltf = await new GLTFLoader().loadAsync('/check/model.glb');
        const { offscreen, clipBox, cameraOn, compareMasks } = await import('/tests/page_draw.mjs');
        const size = 256, view = offscreen(size), renderer = view.renderer;
        const white = new THREE.MeshBasicMaterial({ color: 0xffffff });
        // The reference: three's own skinning of the glTF.
        const reference = new THREE.Scene();
        reference.add(gltf.scene);
        gltf.scene.traverse((o) => { if (o.isMesh) { o.material = white; o.frustumCulled = false; } });
        const mixer = new THREE.AnimationMixer(gltf.scene);
        const animation = gltf.animations.find((a) => a.name === clip);
        mixer.clipAction(animation).play();
        // herd: bonePass 'auto', one Fox (under the threshold: per vertex); herd_bones: the bone pass;
        // herd_auto_big: 'auto' with a threshold of one vertex (the bone pass); herd_lod_one: the bone pass's LOD forced to
        // one influence; broken: unpatched.
        const herds = {};
        for (const [name, options] of [['herd', {}], ['herd_bones', { bonePass: true }], ['herd_auto_big', { bonePassVertices: 1 }],
                                       ['herd_lod_one', { bonePass: true, lod: { one: 1e6 } }], ['broken', {}]]) {
            const scene = new THREE.Scene();
            const herd = new CrowdbakeHerd(gltf, pal, null, { count: 1, glsl, material: new THREE.MeshBasicMaterial({ color: 0xffffff }),
                                                              ...options });
            if (name === 'broken') herd.material.onBeforeCompile = () => {}, herd.material.customProgramCacheKey = () => 'unpatched';
            herd.setState(0, clip, { phase: 0, fade: 0 });
            scene.add(herd);
            herds[name] = { scene, herd };
        }
        const c = pal.clips.find((k) => k.name === clip);
        const { center, extent } = clipBox(c);
        const camera = cameraOn(center, extent, { fov: 35, offset: [1.2, 0.5, 1.4] });
        const mask = (scene) => view.mask(scene, camera);
        const compare = compareMasks;
        // The WebGL2 Crowd: one instance at the origin, the clip from its start, drawn lit on black.
        const canvas = document.createElement('canvas');
        canvas.width = canvas.height = size;
        const gl = canvas.getContext('webgl2', { antialias: false });
        const mesh = meshFromGLTF(gltf);
        const crowdOf = (options) => {
            const crowd = new Crowd(gl, { pal, glsl, mesh, capacity: 1, ...options });
            crowd.setInstance(0, { inst: clipInstance(c) }); // a timed clip's numbers too (.pal version 7)
            return crowd;
        };
        const crowds = {
            palette: crowdOf({ bonePass: false }), bones: crowdOf({ bonePass: true, lod: false }),
            auto_small: crowdOf({}), auto_big: crowdOf({ bonePassVertices: 1 }),
            lod_forced: crowdOf({ bonePass: true, lod: { two: 1e6 } }), lod_one_forced: crowdOf({ bonePass: true, lod: { one: 1e6 } }),
            lod_default: crowdOf({ bonePass: true }),
        };
        const choices = Object.fromEntries(Object.entries(crowds).map(([k, v]) => [k, v.choice()]));
        for (const [k, h] of Object.entries(herds)) choices[k] = h.herd.choice(renderer);
        camera.updateMatrixWorld();
        const vp = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).elements;
        const crowdPixels = (crowd, t) => {
            gl.viewport(0, 0, size, size);
            gl.enable(gl.DEPTH_TEST);
            gl.clearColor(0, 0, 0, 1);
            gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
            crowd.draw(vp, t);
            const px = new Uint8Array(size * size * 4);
            gl.readPixels(0, 0, size, size, gl.RGBA, gl.UNSIGNED_BYTE, px);
            return px;
        };
        const crowdMask = (crowd, t) => {
            const px = crowdPixels(crowd, t);
            return Array.from({ length: size * size }, (_, i) => px[i * 4] + px[i * 4 + 1] + px[i * 4 + 2] > 0);
        };
        // The LOD's tiers drawn apart (lodTiers, the default) against one draw finding each vertex's tier, on the same
        // decision: 9 small Foxes of 9 sizes in a grid, the thresholds half way between sizes so that 3 take each tier.
        const { lodTier, lodUniform } = await import('/web/crowdbake_bones.mjs');
        const nine = Array.from({ length: 9 }, (_, i) => ({
            position: [center.x + ((i % 3) - 1) * extent * 0.3, center.y - extent * 0.3, center.z + (Math.floor(i / 3) - 1) * extent * 0.3],
            yaw: i * 0.7, scale: 0.3 + 0.02 * ((i * 4) % 9), inst: clipInstance(c, 1, i / 9) }));
        const herdOf = (options) => {
            const crowd = new Crowd(gl, { pal, glsl, mesh, capacity: 9, bonePass: true, ...options });
            nine.forEach((o, i) => crowd.setInstance(i, o));
            return crowd;
        };
        const every = herdOf({ lod: false }), u0 = lodUniform({}, every.size, vp, size)[0]; // pixels tall at w = 1, scale 1
        const sizes = nine.map((o) => (u0 * o.scale) / (vp[3] * o.position[0] + vp[7] * o.position[1] + vp[11] * o.position[2] + vp[15]));
        const sorted = [...sizes].sort((a, b) => a - b), split = { one: (sorted[2] + sorted[3]) / 2, two: (sorted[5] + sorted[6]) / 2 };
        const tierCrowds = { apart: herdOf({ lod: split }), one_draw: herdOf({ lod: split, lodTiers: false }), every,
                             far: herdOf({ lod: { one: 1e6 } }) };
        const tierCounts = [0, 0, 0];
        for (const o of nine) ++tierCounts[lodTier(vp, [u0, split.two, split.one], ...o.position, o.scale)];
        const out = [];
        for (const t of times) {
            mixer.setTime(t);
            const want = mask(reference);
            const row = { time: t };
            for (const [name, h] of Object.entries(herds)) {
                h.herd.update(t, renderer);
                row[name] = compare(want, mask(h.scene));
            }
            const bones = crowdMask(crowds.bones, t);
            for (const [name, crowd] of Object.entries(crowds)) {
                const got = name === 'bones' ? bones : crowdMask(crowd, t);
                row[`crowd_${name}`] = { ...compare(want, got), vs_bones: compare(bones, got).differ };
            }
            const apart = crowdPixels(tierCrowds.apart, t), oneDraw = crowdPixels(tierCrowds.one_draw, t);
            const every = crowdPixels(tierCrowds.every, t), far = crowdPixels(tierCrowds.far, t);
            row.tiers = { counts: tierCounts, draws: tierCrowds.apart.draw(vp, t), bytes_differ: apart.reduce((n, v, i) => n + (v !== oneDraw[i]), 0),
                          vs_every_influence: apart.reduce((n, v, i) => n + (v !== every[i]), 0),
                          vs_all_far: apart.reduce((n, v, i) => n + (v !== far[i]), 0),
                          covered: apart.reduce((n, v, i) => n + (i % 4 === 0 && v + apart[i + 1] + apart[i + 2] > 0), 0) };
            out.push(row);
        }
        // The herd's LOD tiers drawn apart (update given the camera) against its one draw (update without it): the same
        // 9 Foxes lit, the same image's bytes; to show the check can fail, those that differ from every Fox on every
        // influence and from every Fox on the far tier.
        const herdTiers = (tiersOn, lod) => {
            const scene = new THREE.Scene(), sun = new THREE.DirectionalLight(0xffffff, 2.5);
            sun.position.set(center.x + extent, center.y + extent * 2, center.z + extent * 0.5);
            const herd = new CrowdbakeHerd(gltf, pal, null, { count: 9, glsl, bonePass: true, lod });
            nine.forEach((o, i) => {
                herd.setState(i, clip, { phase: o.inst[3], fade: 0 });
                herd.place(i, o.position, { yaw: o.yaw, scale: o.scale });
            });
            scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 1.5), sun, herd);
            return { scene, herd, tiersOn };
        };
        const herdCases = { apart: herdTiers(true, split), one_draw: herdTiers(false, split), every: herdTiers(true, false),
                            far: herdTiers(true, { one: 1e6 }) };
        const draw = (h, t) => {
            h.herd.update(t, renderer, h.tiersOn ? camera : null);
            return view.pixels(h.scene, camera);
        };
        for (const [k, t] of times.entries()) {
            const differ = (a, b) => { const x = draw(herdCases[a], t), y = draw(herdCases[b], t); return x.reduce((n, v, i) => n + (v !== y[i]), 0); };
            const same = differ('apart', 'one_draw');
            const hits = (h) => { // a ray from the camera to the middle Fox's body: the instances it meets, tiers or not
                const body = new THREE.Vector3(...nine[4].position).add(new THREE.Vector3(0, c.bounds_max[1] * nine[4].scale * 0.4, 0));
                const ray = new THREE.Raycaster(camera.position, body.sub(camera.position).normalize());
                return ray.intersectObject(h.scene, true).map((x) => `${x.object === h.herd}:${x.instanceId}`).join(' ');
            };
            out[k].herd_tiers = { counts: [...herdCases.apart.herd.tiers.count], bytes_differ: same,
                                  raycast: [hits(herdCases.apart), hits(herdCases.one_draw)],
                                  vs_every_influence: differ('apart', 'every'), vs_all_far: differ('apart', 'far'),
                                  bytes_per_instance: [herdCases.apart.herd.bytesPerInstance(), herdCases.one_draw.herd.bytesPerInstance()] };
        }
        return { clip, frames: c.frames, fps: c.fps, three: THREE.REVISION, choices, results: out };
    }, { clip, times });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
