// socket_check.mjs - sockets in the browser: a CrowdbakeHerd instance plays a clip while three.js's
// own SkinnedMesh + AnimationMixer play the glTF (the independent reference). At each time, per
// socket of `crowdbake info --json`, the prop's matrix herd.socketMatrixAt gives against the
// matrixWorld three.js computes for that node in its own hierarchy; and, in pixels, the triangles
// that Head_end's bone alone moves, skinned on the GPU by the herd's shader against the same
// triangles placed on the CPU by boneMatrixAt (and by boneMatrixAt at a wrong time, which must
// disagree): the share of covered pixels where the two silhouettes differ. Each socket's axes are
// also measured: a prop hung by the documented formula keeps its own scale where they are unit long,
// whatever scale three.js's node carries from its ancestors (node_scale).
//
//   node tests/runtimes/browser/socket_check.mjs DIR CLIP T1,T2,...
//
// DIR holds model.glb, model.pal (root motion kept, as three plays it) and info.json. Prints JSON.
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
        const { loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
        const { CrowdbakeHerd, meshFromGLTF } = await import('/web/crowdbake_three.mjs');
        const pal = readPal(new Uint8Array(await (await fetch('/check/model.pal')).arrayBuffer()));
        const sockets = (await (await fetch('/check/info.json')).json()).sockets;
        const gltf = await new GLTFLoader().loadAsync('/check/model.glb');
        const { offscreen, clipBox, cameraOn, compareMasks } = await import('/tests/page_draw.mjs');
        const view = offscreen(512);
        const mixer = new THREE.AnimationMixer(gltf.scene);
        mixer.clipAction(gltf.animations.find((a) => a.name === clip)).play();
        const full = meshFromGLTF(gltf);
        // The triangles the head's bone alone moves (every vertex's whole weight on it).
        const bone = sockets.find((k) => k.name === 'Head_end').bone;
        const only = (v) => [0, 1, 2, 3].some((k) => full.joints[v * 4 + k] === bone && full.weights[v * 4 + k] > 0.999);
        const kept = [];
        for (let i = 0; i < full.indices.length; i += 3)
            if ([0, 1, 2].every((k) => only(full.indices[i + k]))) kept.push(full.indices[i], full.indices[i + 1], full.indices[i + 2]);
        const mesh = { ...full, indices: new Uint32Array(kept) };
        const white = () => new THREE.MeshBasicMaterial({ color: 0xffffff, side: THREE.DoubleSide });
        const gpu = new THREE.Scene(), cpu = new THREE.Scene();
        const herd = new CrowdbakeHerd(mesh, pal, null, { count: 1, glsl: await loadPaletteGLSL(), material: white() });
        herd.setState(0, clip, { phase: 0, fade: 0 });
        gpu.add(herd);
        const placed = new THREE.BufferGeometry();
        placed.setAttribute('position', new THREE.BufferAttribute(new Float32Array(full.positions.length), 3));
        placed.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
        const cpuMesh = new THREE.Mesh(placed, white());
        cpuMesh.frustumCulled = false;
        cpu.add(cpuMesh);
        const place = (m) => { // every vertex by the bone's matrix: the kept ones are all it moves
            const a = placed.attributes.position, v = new THREE.Vector3();
            for (let i = 0; i < a.count; ++i) a.setXYZ(i, ...v.fromArray(full.positions, i * 3).applyMatrix4(m).toArray());
            a.needsUpdate = true;
        };
        const c = pal.clips.find((k) => k.name === clip);
        const { center, extent } = clipBox(c);
        const camera = cameraOn(center, extent, { fov: 35, offset: [1.2, 0.5, 1.4] });
        const mask = (scene) => view.mask(scene, camera);
        const differ = (a, b) => compareMasks(a, b).share;
        const out = [];
        for (const t of times) {
            mixer.setTime(t);
            gltf.scene.updateMatrixWorld(true);
            herd.update(t);
            const row = { time: t, sockets: [] };
            for (const s of sockets) {
                const node = gltf.scene.getObjectByName(s.name.replace(/[.]/g, '')) ?? gltf.scene.getObjectByName(s.name);
                const ours = herd.socketMatrixAt(0, s).elements, three = node.matrixWorld.elements;
                const at = (m) => new THREE.Vector3(m[12], m[13], m[14]);
                const axis = (m, k) => new THREE.Vector3(m[4 * k], m[4 * k + 1], m[4 * k + 2]).normalize();
                const length = (m, k) => new THREE.Vector3(m[4 * k], m[4 * k + 1], m[4 * k + 2]).length();
                row.sockets.push({ name: s.name, position: at(ours).distanceTo(at(three)),
                                   axes: Math.max(...[0, 1, 2].map((k) => axis(ours, k).distanceTo(axis(three, k)))),
                                   // a prop's own scale is kept where the socket's axes are unit long
                                   scale: Math.max(...[0, 1, 2].map((k) => Math.abs(length(ours, k) - 1))),
                                   node_scale: length(three, 0) });
            }
            const drawn = mask(gpu);
            place(herd.boneMatrixAt(0, bone));
            row.differ = differ(drawn, mask(cpu));
            herd.time = t + 1; // a wrong time for boneMatrixAt only: the drawn herd stays at t
            place(herd.boneMatrixAt(0, bone));
            row.differ_wrong_time = differ(drawn, mask(cpu));
            row.covered = drawn.filter(Boolean).length;
            out.push(row);
        }
        return { clip, triangles: mesh.indices.length / 3, height: pal.header.model_height, results: out };
    }, { clip, times });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
