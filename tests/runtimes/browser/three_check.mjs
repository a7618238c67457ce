// three_check.mjs - the three.js drop-in (runtimes/web/crowdbake_three.mjs, CrowdbakeHerd) against three.js
// itself: the same model skinned by three's own SkinnedMesh + AnimationMixer from the glTF (an
// independent implementation) and by a CrowdbakeHerd instance from the palette, at the same clip
// times, rendered as white silhouettes from the same camera; prints, per time, the share of the
// covered pixels where the two silhouettes disagree. A deliberately broken herd (its skinning patch
// left out: the mesh stays in its bind pose) is measured the same way. So is the WebGL2 Crowd
// (runtimes/web/crowdbake_crowd.mjs), its own canvas, the same camera: per-vertex blending, the bone
// pass, the herd-size choice (bonePass: 'auto' below and above its threshold: which it picked, and its
// pixels) and the animation LOD (forced on at this size: the 2 largest weights, the largest alone; and at its default,
// where an instance this large on screen keeps every influence).
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
        const { readPal } = await import('/web/crowdbake_pal.mjs');
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
            crowd.setInstance(0, { inst: [c.first_row, c.loops ? c.frames : -c.frames, c.fps, 0] });
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
        const crowdMask = (crowd, t) => {
            gl.viewport(0, 0, size, size);
            gl.enable(gl.DEPTH_TEST);
            gl.clearColor(0, 0, 0, 1);
            gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
            crowd.draw(vp, t);
            const px = new Uint8Array(size * size * 4);
            gl.readPixels(0, 0, size, size, gl.RGBA, gl.UNSIGNED_BYTE, px);
            return Array.from({ length: size * size }, (_, i) => px[i * 4] + px[i * 4 + 1] + px[i * 4 + 2] > 0);
        };
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
            out.push(row);
        }
        return { clip, frames: c.frames, fps: c.fps, three: THREE.REVISION, choices, results: out };
    }, { clip, times });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
