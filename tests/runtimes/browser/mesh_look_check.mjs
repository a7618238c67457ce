// mesh_look_check.mjs - does `crowdbake mesh` keep what the model looks like? In headless Chromium,
// three.js's GLTFLoader (the independent reader) loads the source model and the written mesh; for
// each primitive, in order, it compares what three makes of them: the material (type, colour,
// metalness, roughness, alpha mode, sides, vertex colours), its texture (sampler and the decoded
// pixels, hashed) and the UVs. Then both are drawn in their bind pose (their geometry as plain
// meshes, so only the look differs) under the same lights and camera, and the share of covered
// pixels whose colour differs by more than `tolerance` (of 255) is measured; the mesh with three's
// default material on every primitive (what `mesh` wrote before it kept materials) is the negative
// control.
//
//   node tests/runtimes/browser/mesh_look_check.mjs DIR NAME[=SOURCE] ...
//
// DIR holds NAME.glb (the source; or SOURCE, a path under DIR) and NAME.mesh.glb (`crowdbake mesh`
// of it). Prints JSON.
import path from 'node:path';
import { withPage, checkRoutes, THREE_PAGE } from './driver.mjs';

const [dir, ...names] = process.argv.slice(2);
const tolerance = 12;

const result = await withPage(checkRoutes(dir), '/__blank.html', async (p) => {
    await p.setContent(THREE_PAGE);
    const r = await p.evaluate(async ({ names, tolerance }) => {
        const THREE = await import('three');
        const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
        const { offscreen, cameraOn, compareColours } = await import('/tests/page_draw.mjs');
        const { image } = offscreen(320);
        const compare = (a, b) => compareColours(a, b, tolerance);
        const pixelsHash = async (img) => { // the decoded texture, as the page sees it
            const canvas = new OffscreenCanvas(img.width, img.height), g = canvas.getContext('2d');
            g.drawImage(img, 0, 0);
            const data = g.getImageData(0, 0, img.width, img.height).data;
            const digest = new Uint8Array(await crypto.subtle.digest('SHA-256', data));
            return `${img.width}x${img.height} ` + Array.from(digest.slice(0, 8), (b) => b.toString(16).padStart(2, '0')).join('');
        };
        const facts = async (m, geometry) => ({
            type: m.type, name: m.name, color: m.color.toArray().map((v) => +v.toFixed(6)), opacity: m.opacity,
            metalness: +m.metalness.toFixed(6), roughness: +m.roughness.toFixed(6), transparent: m.transparent,
            alphaTest: m.alphaTest, side: m.side, vertexColors: m.vertexColors,
            map: m.map ? { pixels: await pixelsHash(m.map.image), channel: m.map.channel, magFilter: m.map.magFilter,
                minFilter: m.map.minFilter, wrapS: m.map.wrapS, wrapT: m.map.wrapT, flipY: m.map.flipY,
                colorSpace: m.map.colorSpace } : null,
            uv: geometry.attributes.uv ? geometry.attributes.uv.count : 0,
        });
        const primitives = (gltf) => { // each skinned primitive's geometry and material, in file order
            const list = [];
            gltf.scene.traverse((o) => { if (o.isSkinnedMesh) list.push(o); });
            return list;
        };
        const sameArray = (a, b) => { // the values three reads (normalized integers dequantized)
            if (!a || !b) return a === b;
            if (a.count !== b.count || a.itemSize !== b.itemSize) return false;
            for (let i = 0; i < a.count; ++i)
                for (let k = 0; k < a.itemSize; ++k) if (Math.abs(a.getComponent(i, k) - b.getComponent(i, k)) > 8e-6) return false; // u16 texcoords (--quantize) round by half a step
            return true;
        };
        const plain = (list, material) => { // bind pose: the geometry as it is, no skin, no node transform
            const group = new THREE.Group();
            for (const o of list) group.add(new THREE.Mesh(o.geometry, material || o.material));
            return group;
        };
        const out = {};
        for (const entry of names) {
            const [name, sourceFile] = entry.split('=');
            const source = primitives(await new GLTFLoader().loadAsync(`/check/${sourceFile || name + '.glb'}`));
            const mesh = primitives(await new GLTFLoader().loadAsync(`/check/${name}.mesh.glb`));
            const rows = [];
            for (let i = 0; i < Math.max(source.length, mesh.length); ++i) {
                const a = source[i], b = mesh[i];
                const fa = a && await facts(a.material, a.geometry), fb = b && await facts(b.material, b.geometry);
                rows.push({ same: JSON.stringify(fa) === JSON.stringify(fb), same_uv: !!a && !!b &&
                    sameArray(a.geometry.attributes.uv, b.geometry.attributes.uv), source: fa, mesh: fb });
            }
            const reference = plain(source), drawn = plain(mesh), bare = plain(mesh, new THREE.MeshStandardMaterial());
            const box = new THREE.Box3().setFromObject(reference), center = box.getCenter(new THREE.Vector3());
            const extent = box.getSize(new THREE.Vector3()).length();
            const camera = cameraOn(center, extent);
            const ref = image(reference, camera);
            out[name] = {
                primitives: rows.length, materials_same: rows.filter((r) => r.same).length,
                uvs_same: rows.filter((r) => r.same_uv && r.source.uv > 0).length,
                textured: rows.filter((r) => r.mesh && r.mesh.map).length,
                vertex_colours: rows.filter((r) => r.mesh && r.mesh.vertexColors).length,
                texture_pixels: rows.filter((r) => r.mesh && r.mesh.map).map((r) => r.mesh.map.pixels),
                distinct_colours: new Set(rows.map((r) => r.mesh && JSON.stringify(r.mesh.color))).size,
                look: compare(image(drawn, camera), ref), default_material: compare(image(bare, camera), ref),
                differences: rows.filter((r) => !r.same),
            };
        }
        return out;
    }, { names, tolerance });
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    return r;
});
console.log(JSON.stringify(result));
