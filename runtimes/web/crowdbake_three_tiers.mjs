// crowdbake_three_tiers.mjs - the animation LOD's tiers drawn apart for CrowdbakeHerd (crowdbake_three.mjs), as
// crowdbake_bones.mjs's LodTiers does for the WebGL2 Crowd. Given the camera (herd.update(time, renderer, camera)),
// each frame every instance's tier is found once on the CPU, by the rule the bone pass's draw applies per vertex
// (cb_herd_influences: its size on screen from modelMatrix x instanceMatrix), and the instances are copied, bucketed
// by tier (stable, into arrays made once), into three child InstancedMeshes that share the herd's vertex buffers. Each
// child's materials (colour, shadow depth and distance) are the herd's compiled with CB_INFLUENCES 1, 2 or 4 and skin
// from the bone pass's row cb_bone_instance: no size test or influence loop a vertex on the far tiers, the same pixels.
// The herd itself is then left out of the render lists (its layers emptied; three still draws its children, and the
// first tier's raycast answers for the herd's instances).
import * as THREE from 'three';
import { TIER_INFLUENCES } from './crowdbake_bones.mjs';

// The herd's skinning for a tier's materials (CB_HERD_TIER): the same two functions as BONE_VERTEX_PARS, the tier
// compiled in (CB_INFLUENCES) and the instance's row in the bone pass an attribute.
export const TIER_VERTEX_PARS = `
in float cb_bone_instance;
vec3 cb_skinned_position; bool cb_skinned = false;
vec3 cb_herd_normal(vec3 p, vec3 n) {
    vec3 skinned_n;
    cb_skin_bone_pass(p, n, ivec4(cb_joints), cb_weights, int(cb_bone_instance), cb_skinned_position, skinned_n);
    cb_skinned = true;
    return skinned_n;
}
vec3 cb_herd_position(vec3 p) {
    vec3 n;
    if (!cb_skinned) cb_skin_bone_pass(p, vec3(0.0, 1.0, 0.0), ivec4(cb_joints), cb_weights, int(cb_bone_instance),
                                       cb_skinned_position, n);
    return cb_skinned_position;
}
`;

const SHARED = ['position', 'normal', 'cb_joints', 'cb_weights', 'uv', 'color']; // the herd's per-vertex attributes

export class HerdTiers {
    // herd: the CrowdbakeHerd; tierLike(material, influences): a material skinned as a tier's.
    constructor(herd, tierLike) {
        const capacity = herd.instanceMatrix.count, source = herd.geometry;
        this.herd = herd;
        this.count = [0, 0, 0];
        this.next = [0, 0, 0];
        this.tier = new Uint8Array(capacity);
        this.clip = new THREE.Matrix4();
        this.mask = herd.layers.mask; // the herd's own layers, which its tiers take while they draw
        this.meshes = TIER_INFLUENCES.map((k) => {
            const geometry = new THREE.BufferGeometry();
            for (const name of SHARED) if (source.attributes[name]) geometry.setAttribute(name, source.attributes[name]);
            geometry.setIndex(source.index);
            for (const g of source.groups) geometry.addGroup(g.start, g.count, g.materialIndex);
            geometry.setAttribute('cb_bone_instance',
                new THREE.InstancedBufferAttribute(new Float32Array(capacity), 1).setUsage(THREE.DynamicDrawUsage));
            geometry.boundingBox = source.boundingBox;
            geometry.boundingSphere = source.boundingSphere;
            const material = Array.isArray(herd.material) ? herd.material.map((m) => tierLike(m, k)) : tierLike(herd.material, k);
            const mesh = new THREE.InstancedMesh(geometry, material, capacity);
            mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
            mesh.customDepthMaterial = tierLike(herd.customDepthMaterial, k);
            mesh.customDistanceMaterial = tierLike(herd.customDistanceMaterial, k);
            mesh.frustumCulled = false; // the herd's bounds hold every instance; each tier draws what it has
            mesh.raycast = k === 1 // the herd answers for its instances, through one tier while it is out of the layers
                ? (raycaster, intersects) => { if (herd.layers.mask === 0) herd.raycast(raycaster, intersects); } : () => {};
            mesh.count = 0;
            mesh.layers.mask = 0;
            mesh.name = `crowdbake LOD tier: ${k} influence${k > 1 ? 's' : ''}`;
            herd.add(mesh);
            return mesh;
        });
    }

    // Sorts the herd's count instances into the tiers for `camera` (lod: { two, one } pixels tall; pixelsAtW1: the
    // herd's size on screen at w = 1 and scale 1, as cb_lod.x), and takes the herd's place in the render lists.
    sort(camera, lod, pixelsAtW1) {
        camera.updateMatrixWorld(); // where render() will put them
        this.herd.updateWorldMatrix(true, false);
        const herd = this.herd, n = herd.count, m = herd.instanceMatrix.array, w = herd.matrixWorld.elements;
        const c = this.clip.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).multiply(herd.matrixWorld).elements;
        const { count, next, tier } = this, one = lod.one ?? 0, two = lod.two ?? 0;
        count.fill(0);
        for (let i = 0, o = 0; i < n; ++i, o += 16) { // cb_herd_influences on the CPU: place = modelMatrix x instanceMatrix
            const depth = c[3] * m[o + 12] + c[7] * m[o + 13] + c[11] * m[o + 14] + c[15];
            const x = w[0] * m[o] + w[4] * m[o + 1] + w[8] * m[o + 2], y = w[1] * m[o] + w[5] * m[o + 1] + w[9] * m[o + 2];
            const z = w[2] * m[o] + w[6] * m[o + 1] + w[10] * m[o + 2], pixels = (pixelsAtW1 * Math.hypot(x, y, z)) / depth;
            tier[i] = pixels < one ? 0 : pixels < two ? 1 : 2;
            ++count[tier[i]];
        }
        next.fill(0);
        for (let i = 0; i < n; ++i) { // stable: each tier keeps the herd's order
            const mesh = this.meshes[tier[i]], slot = next[tier[i]]++, to = mesh.instanceMatrix.array;
            for (let e = 0; e < 16; ++e) to[slot * 16 + e] = m[i * 16 + e];
            mesh.geometry.attributes.cb_bone_instance.array[slot] = i;
        }
        const mask = herd.layers.mask || this.mask;
        this.mask = mask;
        for (let k = 0; k < 3; ++k) {
            const mesh = this.meshes[k];
            mesh.count = count[k];
            mesh.instanceMatrix.needsUpdate = mesh.geometry.attributes.cb_bone_instance.needsUpdate = true;
            mesh.layers.mask = mask;
            mesh.castShadow = herd.castShadow, mesh.receiveShadow = herd.receiveShadow;
        }
        herd.layers.mask = 0;
    }

    // The herd draws itself again (one draw, each vertex finding its tier, or no bone pass).
    off() {
        if (this.herd.layers.mask === 0) this.herd.layers.mask = this.mask;
        for (const mesh of this.meshes) mesh.count = 0, mesh.layers.mask = 0;
    }
}
