// crowdbake_three.mjs - a three.js drop-in for crowdbake palettes: CrowdbakeHerd, an
// InstancedMesh whose material skins every instance from the palette (the shipped
// samples/shaders/crowdbake_palette.glsl, patched into three's own material with onBeforeCompile),
// one draw call for the whole herd.
//
//     const herd = new CrowdbakeHerd(gltf, readPal(palBytes), readRoster(json).types.cow, { count: 1000, glsl });
//     scene.add(herd); herd.setState(7, 'flee', { speed: 9.9 });
//     renderer.setAnimationLoop((ms) => { herd.update(ms / 1000); renderer.render(scene, camera); });
//
// Place instances with InstancedMesh's setMatrixAt. `three` is an import-map name (pages) or the
// npm package (web/package.json pins it).
import * as THREE from 'three';
import { instanceData } from './crowdbake_pal.mjs';
import { paletteDefines } from './crowdbake_crowd.mjs';

// The skinned meshes of a GLTFLoader result that use its first skin, merged in glTF order:
// positions, normals, joints, weights and indices as the palette's bone indices expect
// (crowdbake bakes the same vertices in the same order).
export function meshFromGLTF(gltf) {
    const parts = [];
    let skeleton = null;
    gltf.scene.updateMatrixWorld(true);
    gltf.scene.traverse((o) => {
        if (!o.isSkinnedMesh) return;
        skeleton ??= o.skeleton;
        if (o.skeleton.bones.every((b, i) => b === skeleton.bones[i])) parts.push(o.geometry);
    });
    if (!parts.length) throw new Error('the model has no skinned mesh');
    const vertices = parts.reduce((n, g) => n + g.attributes.position.count, 0);
    const indices = parts.reduce((n, g) => n + (g.index ? g.index.count : g.attributes.position.count), 0);
    const out = { positions: new Float32Array(vertices * 3), normals: new Float32Array(vertices * 3),
                  joints: new Uint16Array(vertices * 4), weights: new Float32Array(vertices * 4),
                  indices: new Uint32Array(indices) };
    let v0 = 0, i0 = 0;
    for (const g of parts) {
        const a = g.attributes, n = a.position.count;
        const copy = (attr, dst, size) => {
            if (!attr) return;
            for (let v = 0; v < n; ++v) for (let k = 0; k < size; ++k) dst[(v0 + v) * size + k] = attr.getComponent(v, k);
        };
        copy(a.position, out.positions, 3);
        copy(a.normal, out.normals, 3);
        copy(a.skinIndex, out.joints, 4);
        copy(a.skinWeight, out.weights, 4);
        if (g.index) for (let i = 0; i < g.index.count; ++i) out.indices[i0 + i] = v0 + g.index.getX(i);
        else for (let i = 0; i < n; ++i) out.indices[i0 + i] = v0 + i;
        v0 += n, i0 += g.index ? g.index.count : n;
    }
    return out;
}

// The palette as three.js textures: RGBA32F, RGBA16F or RGBA16UI (usampler2D), and the bind
// positions (row 0) and position offsets (row 1, half palettes) the shader reads.
export function paletteTextures(pal) {
    const h = pal.header;
    const types = [[THREE.RGBAFormat, THREE.FloatType, 'RGBA32F'], [THREE.RGBAFormat, THREE.HalfFloatType, 'RGBA16F'],
                   [THREE.RGBAIntegerFormat, THREE.UnsignedShortType, 'RGBA16UI']];
    const [format, type, internal] = types[h.precision];
    const palette = new THREE.DataTexture(pal.texels, h.width, h.height, format, type);
    palette.internalFormat = internal;
    const bindData = new Float32Array(h.bone_count * 8); // row 0: bind positions; row 1: position offsets
    pal.bones.forEach((b, j) => {
        bindData.set(b.bind_position, j * 4);
        bindData.set(b.position_offset, (h.bone_count + j) * 4);
    });
    const bind = new THREE.DataTexture(bindData, h.bone_count, 2, THREE.RGBAFormat, THREE.FloatType);
    for (const t of [palette, bind]) {
        t.minFilter = t.magFilter = THREE.NearestFilter;
        t.generateMipmaps = false;
        t.flipY = false;
        t.needsUpdate = true;
    }
    return { palette, bind };
}

// States of a roster type (readRoster(...).types.NAME), or made from the palette's clips.
function statesOf(pal, type) {
    if (type) return type.states;
    const states = Object.create(null); // clip names are data: '__proto__' is a clip like any other
    for (const c of pal.clips)
        states[c.name] = { clip: c.name, first_row: c.first_row, frame_count: c.loops ? c.frames : -c.frames, rate: c.fps,
                           rate_per_speed: 0, phase: c.loops ? 'golden_ratio' : 'zero' };
    return states;
}

// The position and the normal are skinned together where three's shader asks for the normal
// (beginnormal_vertex, before begin_vertex), each bone's texels read once; a shader without
// normals (a depth material) skins the position alone in begin_vertex.
const VERTEX_PARS = `
in vec4 cb_joints; in vec4 cb_weights; in vec4 cb_inst; in vec4 cb_from; in vec2 cb_fade;
uniform float cb_time;
vec3 cb_skinned_position; bool cb_skinned = false;
float cb_fade_weight() { return cb_fade.y > 0.0 ? clamp((cb_time - cb_fade.x) / cb_fade.y, 0.0, 1.0) : 1.0; }
vec3 cb_herd_normal(vec3 p, vec3 n) {
    vec3 skinned_n;
    cb_skin_position_normal_crossfade(p, n, ivec4(cb_joints), cb_weights, cb_from, cb_inst, cb_fade_weight(), cb_time,
                                      cb_skinned_position, skinned_n);
    cb_skinned = true;
    return skinned_n;
}
vec3 cb_herd_position(vec3 p) {
    return cb_skinned ? cb_skinned_position
                      : cb_skin_position_crossfade(p, ivec4(cb_joints), cb_weights, cb_from, cb_inst, cb_fade_weight(), cb_time);
}
`;

export class CrowdbakeHerd extends THREE.InstancedMesh {
    // gltf: GLTFLoader's result (or meshFromGLTF's arrays); pal: readPal's; type: a roster type
    // (readRoster(...).types.NAME) or null to make a state of each clip. options: count, glsl
    // (the library's text: loadPaletteGLSL()), material (a three.js material to patch; default
    // MeshLambertMaterial), fade (cross-fade seconds, 0.25).
    constructor(gltf, pal, type, { count = 1000, glsl, material, fade = 0.25 } = {}) {
        if (!glsl) throw new Error('CrowdbakeHerd: options.glsl is the shipped library (await loadPaletteGLSL())');
        const mesh = gltf.positions ? gltf : meshFromGLTF(gltf);
        const geometry = new THREE.BufferGeometry();
        geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
        geometry.setAttribute('normal', new THREE.BufferAttribute(mesh.normals, 3));
        geometry.setAttribute('cb_joints', new THREE.BufferAttribute(Float32Array.from(mesh.joints), 4));
        geometry.setAttribute('cb_weights', new THREE.BufferAttribute(mesh.weights, 4));
        geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
        const per = (n) => new THREE.InstancedBufferAttribute(new Float32Array(count * n), n).setUsage(THREE.DynamicDrawUsage);
        geometry.setAttribute('cb_inst', per(4));
        geometry.setAttribute('cb_from', per(4));
        geometry.setAttribute('cb_fade', per(2));
        material ??= new THREE.MeshLambertMaterial({ color: 0xd8c8a8 });
        super(geometry, material, count);
        this.frustumCulled = false; // instances move in the shader
        this.pal = pal;
        this.states = statesOf(pal, type);
        this.fade = fade;
        this.time = 0;
        this.instanceState = new Array(count).fill(null);
        this.speed = new Float32Array(count);
        this.phase = new Float32Array(count).fill(NaN); // NaN: the state's own phase rule
        const textures = paletteTextures(pal);
        const uniforms = {
            cb_palette: { value: textures.palette }, cb_bind_positions: { value: textures.bind },
            cb_row_texels: { value: pal.header.row_texels }, cb_rows_per_block: { value: pal.header.height },
            cb_bounds_min: { value: new THREE.Vector3(...pal.header.bounds_min) },
            cb_bounds_max: { value: new THREE.Vector3(...pal.header.bounds_max) },
            cb_linear_range: { value: pal.header.linear_range }, cb_time: { value: 0 },
        };
        this.uniforms = uniforms;
        material.defines = { ...material.defines, ...Object.fromEntries(paletteDefines(pal.header).map((d) => [d, ''])) };
        material.onBeforeCompile = (shader) => {
            Object.assign(shader.uniforms, uniforms);
            shader.vertexShader = shader.vertexShader
                .replace('#include <common>', `#include <common>\n${glsl}\n${VERTEX_PARS}`)
                .replace('#include <beginnormal_vertex>', 'vec3 objectNormal = cb_herd_normal(position, normal);')
                .replace('#include <begin_vertex>', 'vec3 transformed = cb_herd_position(position);');
        };
        material.customProgramCacheKey = () => `crowdbake-${paletteDefines(pal.header).join('-')}`;
        const identity = new THREE.Matrix4();
        const def = type?.default_state ?? Object.keys(this.states)[0];
        for (let i = 0; i < count; ++i) {
            this.setMatrixAt(i, identity);
            this.setState(i, def, { fade: 0 });
        }
    }

    // Puts instance i in `state` (a roster state or clip name), cross-fading from what it played;
    // speed (model units/s) drives locomotion states' playback so feet stay planted; phase 0..1
    // overrides the golden-ratio spread.
    setState(i, state, { speed = this.speed[i], phase = this.phase[i], fade = this.fade } = {}) {
        // Own properties only: 'constructor' or '__proto__' is a name, never the object's prototype.
        const s = Object.hasOwn(this.states, state) ? this.states[state] : undefined;
        if (!s) throw new Error(`CrowdbakeHerd: no state '${state}' (have ${Object.keys(this.states).join(', ')})`);
        const attrs = this.geometry.attributes;
        const current = [0, 1, 2, 3].map((k) => attrs.cb_inst.array[i * 4 + k]);
        const inst = instanceData(s, speed, i, this.time);
        if (!Number.isNaN(phase)) inst[3] = phase;
        this.instanceState[i] = state;
        this.speed[i] = speed;
        this.phase[i] = phase;
        attrs.cb_inst.array.set(inst, i * 4);
        attrs.cb_from.array.set(fade > 0 && current[1] !== 0 ? current : inst, i * 4);
        attrs.cb_fade.array.set([this.time, fade], i * 2);
        attrs.cb_inst.needsUpdate = attrs.cb_from.needsUpdate = attrs.cb_fade.needsUpdate = true;
    }

    // A new speed, keeping the frame it is on (no pop): the phase absorbs the change of rate.
    setSpeed(i, speed) {
        const [, count, rate, phase] = this.geometry.attributes.cb_inst.array.subarray(i * 4, i * 4 + 4);
        const frames = Math.abs(count), fpos = this.time * rate + phase * frames;
        const next = instanceData(this.states[this.instanceState[i]], speed, i, this.time)[2];
        const p = (fpos - this.time * next) / frames;
        this.setState(i, this.instanceState[i], { speed, phase: p - Math.floor(p), fade: 0 });
    }

    setPhase(i, phase) {
        this.setState(i, this.instanceState[i], { phase, fade: 0 });
    }

    // The clock the shader plays every instance at, in seconds.
    update(time) {
        this.time = time;
        this.uniforms.cb_time.value = time;
    }
}
