// look_check.mjs - does a CrowdbakeHerd look like the model? In headless Chromium, each model is
// drawn twice under the same lights and camera: by three.js's own SkinnedMesh + AnimationMixer of
// the glTF (the independent reference, with the glTF's materials) and by a one-instance
// CrowdbakeHerd of the same clip at the same time (its default materials: the glTF's own, patched).
// The share of the covered pixels whose colour differs by more than `tolerance` (of 255, any
// channel) is the measure; the old look (one beige MeshLambertMaterial for every primitive) is the
// negative control. Also: the herd's draw calls, and its materials (count, textured, vertex colours).
//
//   node tests/runtimes/browser/look_check.mjs DIR NAME:CLIP:TIME ...
//
// DIR holds NAME.glb and NAME.pal (root motion kept, as three plays it). TIME is moved to the nearest
// baked row, so that what differs is the look and not the blend of two rows. Prints JSON.
import path from 'node:path';
import { withPage, checkRoutes, THREE_PAGE } from './driver.mjs';

const [dir, ...cases] = process.argv.slice(2);
const tolerance = 12;

const result = await withPage(checkRoutes(dir), '/__blank.html', async (p) => {
    await p.setContent(THREE_PAGE);
    const r = await p.evaluate(async ({ cases, tolerance }) => {
        const THREE = await import('three');
        const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
        const { readPal } = await import('/web/crowdbake_pal.mjs');
        const { loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
        const { CrowdbakeHerd } = await import('/web/crowdbake_three.mjs');
        const glsl = await loadPaletteGLSL();
        const { offscreen, clipBox, cameraOn, compareColours } = await import('/tests/page_draw.mjs');
        const { renderer, image } = offscreen(320);
        const compare = (a, b) => compareColours(a, b, tolerance);
        const distinct = (px) => { // colours seen (quantized to 4 bits a channel): a one-colour herd has few
            const seen = new Set();
            for (let i = 0; i < px.length; i += 4) if (px[i + 3]) seen.add((px[i] >> 4) << 8 | (px[i + 1] >> 4) << 4 | px[i + 2] >> 4);
            return seen.size;
        };
        const out = {};
        for (const text of cases) {
            const [name, clip, time] = text.split(':');
            const pal = readPal(new Uint8Array(await (await fetch(`/check/${name}.pal`)).arrayBuffer()));
            const c = pal.clips.find((k) => k.name === clip);
            const t = Math.round(Number(time) * c.fps) / c.fps; // on a baked row: the look, not the rows' blend
            const gltf = await new GLTFLoader().loadAsync(`/check/${name}.glb`);
            const mixer = new THREE.AnimationMixer(gltf.scene);
            mixer.clipAction(gltf.animations.find((a) => a.name === clip)).play();
            gltf.scene.traverse((o) => { if (o.isMesh) o.frustumCulled = false; });
            const herdOf = (material) => {
                const herd = new CrowdbakeHerd(gltf, pal, null, { count: 1, glsl, material });
                herd.setState(0, clip, { phase: 0, fade: 0 });
                herd.update(t);
                herd.frustumCulled = false;
                return herd;
            };
            const herd = herdOf(undefined);
            const beige = herdOf(new THREE.MeshLambertMaterial({ color: 0xd8c8a8 })); // the old look
            const { center, extent } = clipBox(c);
            const camera = cameraOn(center, extent);
            mixer.setTime(t);
            gltf.scene.updateMatrixWorld(true);
            const reference = image(gltf.scene, camera), drawn = image(herd, camera);
            renderer.info.reset();
            renderer.info.autoReset = false;
            image(herd, camera);
            const calls = renderer.info.render.calls;
            renderer.info.autoReset = true;
            const materials = [herd.material].flat();
            out[name] = {
                clip, time: t, herd: compare(drawn, reference), beige: compare(image(beige, camera), reference),
                colours_reference: distinct(reference), colours_herd: distinct(drawn), draw_calls: calls,
                materials: materials.length, textured: materials.filter((m) => m.map).length,
                vertex_colours: materials.filter((m) => m.vertexColors).length,
            };
        }
        return out;
    }, { cases, tolerance });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
