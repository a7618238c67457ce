// three_check.mjs - the three.js drop-in (runtimes/web/crowdbake_three.mjs, CrowdbakeHerd) against three.js
// itself: the same model skinned by three's own SkinnedMesh + AnimationMixer from the glTF (an
// independent implementation) and by a CrowdbakeHerd instance from the palette, at the same clip
// times, rendered as white silhouettes from the same camera; prints, per time, the share of the
// covered pixels where the two silhouettes disagree. A deliberately broken herd (its skinning patch
// left out: the mesh stays in its bind pose) is measured the same way.
//
//   node tests/runtimes/browser/three_check.mjs DIR CLIP T1,T2,...
//
// DIR holds model.glb and model.pal (baked with root motion kept, as three plays it). Prints JSON.
import path from 'node:path';
import { withPage, RUNTIMES, THREE_PAGE } from './driver.mjs';

const [dir, clip, timesText] = process.argv.slice(2);
const times = timesText.split(',').map(Number);

const result = await withPage({ '/': RUNTIMES, '/check/': path.resolve(dir) }, '/__blank.html', async (p) => {
    await p.setContent(THREE_PAGE);
    const r = await p.evaluate(async ({ clip, times }) => {
        const THREE = await import('three');
        const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
        const { readPal } = await import('/web/crowdbake_pal.mjs');
        const { loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
        const { CrowdbakeHerd } = await import('/web/crowdbake_three.mjs');
        const pal = readPal(new Uint8Array(await (await fetch('/check/model.pal')).arrayBuffer()), { verifyChecksum: true });
        const glsl = await loadPaletteGLSL();
        const gltf = await new GLTFLoader().loadAsync('/check/model.glb');
        const size = 256;
        const renderer = new THREE.WebGLRenderer({ antialias: false });
        renderer.setSize(size, size);
        const target = new THREE.WebGLRenderTarget(size, size);
        const white = new THREE.MeshBasicMaterial({ color: 0xffffff });
        // The reference: three's own skinning of the glTF.
        const reference = new THREE.Scene();
        reference.add(gltf.scene);
        gltf.scene.traverse((o) => { if (o.isMesh) { o.material = white; o.frustumCulled = false; } });
        const mixer = new THREE.AnimationMixer(gltf.scene);
        const animation = gltf.animations.find((a) => a.name === clip);
        mixer.clipAction(animation).play();
        const herds = {};
        for (const broken of [false, true]) {
            const scene = new THREE.Scene();
            const herd = new CrowdbakeHerd(gltf, pal, null, { count: 1, glsl, material: new THREE.MeshBasicMaterial({ color: 0xffffff }) });
            if (broken) herd.material.onBeforeCompile = () => {}, herd.material.customProgramCacheKey = () => 'unpatched';
            herd.setState(0, clip, { phase: 0, fade: 0 });
            scene.add(herd);
            herds[broken ? 'broken' : 'herd'] = { scene, herd };
        }
        const c = pal.clips.find((k) => k.name === clip);
        const lo = new THREE.Vector3(...c.bounds_min), hi = new THREE.Vector3(...c.bounds_max);
        const center = lo.clone().add(hi).multiplyScalar(0.5), extent = hi.clone().sub(lo).length();
        const camera = new THREE.PerspectiveCamera(35, 1, extent * 0.05, extent * 20);
        camera.position.copy(center).add(new THREE.Vector3(extent * 1.2, extent * 0.5, extent * 1.4));
        camera.lookAt(center);
        const mask = (scene) => {
            renderer.setRenderTarget(target);
            renderer.setClearColor(0x000000, 1);
            renderer.render(scene, camera);
            const px = new Uint8Array(size * size * 4);
            renderer.readRenderTargetPixels(target, 0, 0, size, size, px);
            return Array.from({ length: size * size }, (_, i) => px[i * 4] > 127);
        };
        const compare = (a, b) => {
            let covered = 0, differ = 0;
            for (let i = 0; i < a.length; ++i) covered += a[i] || b[i], differ += a[i] !== b[i];
            return { covered, differ, share: differ / Math.max(covered, 1) };
        };
        const out = [];
        for (const t of times) {
            mixer.setTime(t);
            const want = mask(reference);
            const row = { time: t };
            for (const [name, h] of Object.entries(herds)) {
                h.herd.update(t);
                row[name] = compare(want, mask(h.scene));
            }
            out.push(row);
        }
        return { clip, frames: c.frames, fps: c.fps, three: THREE.REVISION, results: out };
    }, { clip, times });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
