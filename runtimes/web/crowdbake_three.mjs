// crowdbake_three.mjs - a three.js drop-in for crowdbake palettes: CrowdbakeHerd, an
// InstancedMesh whose materials skin every instance from the palette (the shipped
// runtimes/glsl/crowdbake_palette.glsl, patched into three's own materials with onBeforeCompile): the model's own
// glTF materials (textures, vertex colours, alpha modes), one draw call per material for the whole herd.
//
//     const herd = new CrowdbakeHerd(gltf, readPal(palBytes), readRoster(json).types.cow, { count: 1000, glsl });
//     scene.add(herd); herd.setState(7, 'flee', { speed: 9.9 });
//     renderer.setAnimationLoop((ms) => { herd.update(ms / 1000, renderer); renderer.render(scene, camera); });
//
// Given the renderer, update() runs the bone pass (crowdbake_three_bones.mjs) when the herd is large
// enough for it to pay (bonePass: 'auto', the default; herd.choice() says which and why).
//
// Place instances with place(i, position, { yaw, scale }) or InstancedMesh's setMatrixAt; tint them
// with setColorAt. A placed instance moving at a locomotion state's speed is drawn at its place plus
// the palette's per-row travel offset (.pal version 5: travelOffsetAt), so a gallop's planted feet
// stay still; instances set with setMatrixAt add travelOffsetAt themselves. The herd casts animated shadows (customDepthMaterial, customDistanceMaterial),
// is frustum-culled against bounds that hold every baked pose, and motionVectorMaterial() draws
// its screen-space velocity for TAA or motion blur. `three` is an import-map name (pages) or the
// npm package (runtimes/web/package.json pins it).
import * as THREE from 'three';
import { clipInstance, hasLocalRows, instanceData, instanceBoneMatrix, instanceBoneMatrixCrossfade, instanceFirstRow } from './crowdbake_pal.mjs';
import { FootstepClock } from './crowdbake_contacts.mjs';
import { bonePositionTexels, paletteDefines } from './crowdbake_crowd.mjs';
import { autoBonePassVertices, resolveLod, sortInfluences } from './crowdbake_bones.mjs';
import { BONE_VERTEX_PARS, HerdBonePass } from './crowdbake_three_bones.mjs';
import { HerdTiers, TIER_VERTEX_PARS } from './crowdbake_three_tiers.mjs';
import { instanceTravelOffset } from './crowdbake_travel.mjs';

// The skinned meshes of a GLTFLoader result that use its first skin, merged in glTF order:
// positions, normals, joints, weights and indices as the palette's bone indices expect
// (crowdbake bakes the same vertices in the same order), and what draws them as the model looks:
// texture coordinates (uvs, TEXCOORD_0) and vertex colours (colors, RGBA) where any primitive has
// them, and one group per primitive ({ start, count, materialIndex } into materials, the glTF's own
// materials: base colour, textures, alpha mode, vertex colours).
export function meshFromGLTF(gltf) {
    const parts = [];
    let skeleton = null;
    gltf.scene.updateMatrixWorld(true);
    gltf.scene.traverse((o) => {
        if (!o.isSkinnedMesh) return;
        skeleton ??= o.skeleton;
        if (o.skeleton.bones.every((b, i) => b === skeleton.bones[i])) parts.push(o);
    });
    if (!parts.length) throw new Error('the model has no skinned mesh');
    const geometries = parts.map((o) => o.geometry);
    const vertices = geometries.reduce((n, g) => n + g.attributes.position.count, 0);
    const indices = geometries.reduce((n, g) => n + (g.index ? g.index.count : g.attributes.position.count), 0);
    const any = (name) => geometries.some((g) => g.attributes[name]);
    const out = { positions: new Float32Array(vertices * 3), normals: new Float32Array(vertices * 3),
                  joints: new Uint16Array(vertices * 4), weights: new Float32Array(vertices * 4),
                  indices: new Uint32Array(indices), uvs: any('uv') ? new Float32Array(vertices * 2) : null,
                  colors: any('color') ? new Float32Array(vertices * 4).fill(1) : null, groups: [], materials: [] };
    let v0 = 0, i0 = 0;
    parts.forEach((o, p) => {
        const g = o.geometry, a = g.attributes, n = a.position.count;
        const copy = (attr, dst, size) => { // getComponent: normalized integers (quantized UVs, colours) as floats
            if (!attr || !dst) return;
            for (let v = 0; v < n; ++v)
                for (let k = 0; k < Math.min(size, attr.itemSize); ++k) dst[(v0 + v) * size + k] = attr.getComponent(v, k);
        };
        copy(a.position, out.positions, 3);
        copy(a.normal, out.normals, 3);
        copy(a.skinIndex, out.joints, 4);
        copy(a.skinWeight, out.weights, 4);
        copy(a.uv, out.uvs, 2);
        copy(a.color, out.colors, 4);
        const count = g.index ? g.index.count : n;
        if (g.index) for (let i = 0; i < count; ++i) out.indices[i0 + i] = v0 + g.index.getX(i);
        else for (let i = 0; i < n; ++i) out.indices[i0 + i] = v0 + i;
        out.groups.push({ start: i0, count, materialIndex: p });
        out.materials.push(Array.isArray(o.material) ? o.material[0] : o.material);
        v0 += n, i0 += count;
    });
    return out;
}

// The palette as three.js textures: RGBA32F, RGBA16F or RGBA16UI (usampler2D), and the bind
// positions (row 0) and position offsets (row 1, half palettes) the shader reads (local rows: rows 2..4 too,
// bonePositionTexels).
export function paletteTextures(pal) {
    const h = pal.header;
    const types = [[THREE.RGBAFormat, THREE.FloatType, 'RGBA32F'], [THREE.RGBAFormat, THREE.HalfFloatType, 'RGBA16F'],
                   [THREE.RGBAIntegerFormat, THREE.UnsignedShortType, 'RGBA16UI']];
    const [format, type, internal] = types[h.precision];
    const palette = new THREE.DataTexture(pal.texels, h.width, h.height, format, type);
    palette.internalFormat = internal;
    const { data, rows } = bonePositionTexels(pal);
    const bind = new THREE.DataTexture(data, h.bone_count, rows, THREE.RGBAFormat, THREE.FloatType);
    for (const t of [palette, bind]) {
        t.minFilter = t.magFilter = THREE.NearestFilter;
        t.generateMipmaps = false;
        t.flipY = false;
        t.needsUpdate = true;
    }
    return { palette, bind };
}

// States of a roster type (readRoster(...).types.NAME), or made from the palette's clips (no type, or one
// without states).
function statesOf(pal, type) {
    if (type && Object.keys(type.states).length) return type.states; // a type without states plays its clips
    const states = Object.create(null); // clip names are data: '__proto__' is a clip like any other
    for (const c of pal.clips) { // a timed clip's: its cells and a negative rate (clipInstance)
        const [first_row, frame_count, rate] = clipInstance(c);
        states[c.name] = { clip: c.name, first_row, frame_count, rate, rate_per_speed: 0, phase: c.loops ? 'golden_ratio' : 'zero' };
    }
    return states;
}

// The position and the normal are skinned together where three's shader asks for the normal
// (beginnormal_vertex, before begin_vertex), each bone's texels read once; a shader without
// normals (a depth material) skins the position alone in begin_vertex.
const VERTEX_INPUTS = `
in vec4 cb_joints; in vec4 cb_weights; in vec4 cb_inst; in vec4 cb_from; in vec2 cb_fade;
uniform float cb_time;
`;
const VERTEX_PARS = `
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

// The box that holds every clip's animated bounds (the .pal clip table: the skinned mesh over each
// baked row), in the model's space, and the sphere around it: an instance's bounds in any pose.
export function animatedBounds(pal) {
    const box = new THREE.Box3();
    for (const c of pal.clips)
        box.union(new THREE.Box3(new THREE.Vector3(...c.bounds_min), new THREE.Vector3(...c.bounds_max)));
    return { box, sphere: box.getBoundingSphere(new THREE.Sphere()) };
}

// The motion-vector pass's additions to a patched material: the position at cb_previous_time
// (the same skinning, one call at the previous frame's time) projected by the previous frame's
// view-projection; the fragment writes 0.5 x (NDC now - NDC before), the velocity in units of
// the screen's width and height, as RG.
const MOTION_VERTEX_PARS = `
uniform float cb_previous_time; uniform mat4 cb_previous_view_projection;
out vec4 cb_clip_now; out vec4 cb_clip_before;
vec3 cb_herd_previous_position(vec3 p) {
    float f = cb_fade.y > 0.0 ? clamp((cb_previous_time - cb_fade.x) / cb_fade.y, 0.0, 1.0) : 1.0;
    return f < 1.0 ? cb_skin_position_crossfade(p, ivec4(cb_joints), cb_weights, cb_from, cb_inst, f, cb_previous_time)
                   : cb_skin_position(p, ivec4(cb_joints), cb_weights, cb_inst, cb_previous_time);
}
`;
const MOTION_VERTEX = `
cb_clip_now = gl_Position;
vec4 cb_before = vec4(cb_herd_previous_position(position), 1.0);
#ifdef USE_INSTANCING
cb_before = instanceMatrix * cb_before;
#endif
cb_clip_before = cb_previous_view_projection * modelMatrix * cb_before;
`;
const MOTION_FRAGMENT = `
gl_FragColor = vec4(0.5 * (cb_clip_now.xy / cb_clip_now.w - cb_clip_before.xy / cb_clip_before.w), 0.0, 1.0);
`;

export class CrowdbakeHerd extends THREE.InstancedMesh {
    // gltf: GLTFLoader's result (or meshFromGLTF's arrays); pal: readPal's; type: a roster type
    // (readRoster(...).types.NAME) or null to make a state of each clip. options: count, glsl
    // (the library's text: loadPaletteGLSL()), material (one three.js material, or an array with one
    // per primitive, to patch; default: a clone of each primitive's own glTF material, so the herd
    // looks like the model), fade (cross-fade seconds, 0.25), bonePass ('auto': the bone pass from
    // bonePassVertices skinned vertices a frame, AUTO_BONE_PASS_VERTICES (local rows: _LOCAL) unless given, when update()
    // is given the renderer; true: always then; false: never).
    // lod: with the bone pass, the animation LOD of crowdbake_bones.mjs ('auto': from the model's own error, the
    // roster type's animation_lod or else lodThresholds; { two, one } or false); herd.lodChoice() says which and why.
    // lodTiers (true): given the camera (update(time, renderer, camera)), the LOD's tiers drawn apart
    // (crowdbake_three_tiers.mjs), the same pixels without a size test and influence loop a vertex; false, or no
    // camera: one draw, each vertex finding its tier.
    constructor(gltf, pal, type, { count = 1000, glsl, material, fade = 0.25, bonePass = 'auto', bonePassVertices,
                                   lod = 'auto', lodTiers = true } = {}) {
        if (!glsl) throw new Error('CrowdbakeHerd: options.glsl is the shipped library (await loadPaletteGLSL())');
        const mesh = gltf.positions ? gltf : meshFromGLTF(gltf);
        const geometry = new THREE.BufferGeometry();
        geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
        geometry.setAttribute('normal', new THREE.BufferAttribute(mesh.normals, 3));
        const sorted = sortInfluences(mesh.joints, mesh.weights); // largest first: the LOD keeps the first ones
        geometry.setAttribute('cb_joints', new THREE.BufferAttribute(Float32Array.from(sorted.joints), 4));
        geometry.setAttribute('cb_weights', new THREE.BufferAttribute(sorted.weights, 4));
        if (mesh.uvs) geometry.setAttribute('uv', new THREE.BufferAttribute(mesh.uvs, 2));
        if (mesh.colors) geometry.setAttribute('color', new THREE.BufferAttribute(mesh.colors, 4));
        geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
        const per = (n) => new THREE.InstancedBufferAttribute(new Float32Array(count * n), n).setUsage(THREE.DynamicDrawUsage);
        geometry.setAttribute('cb_inst', per(4));
        geometry.setAttribute('cb_from', per(4));
        geometry.setAttribute('cb_fade', per(2));
        material ??= mesh.materials?.length ? mesh.materials.map((m) => m.clone()) // the herd's own: patched below
                                            : new THREE.MeshStandardMaterial({ color: 0xd8c8a8 });
        if (Array.isArray(material)) // one group per primitive: one draw each, every instance in it
            (mesh.groups ?? [{ start: 0, count: mesh.indices.length, materialIndex: 0 }])
                .forEach((g) => geometry.addGroup(g.start, g.count, Math.min(g.materialIndex, material.length - 1)));
        super(geometry, material, count);
        const bounds = animatedBounds(pal);
        geometry.boundingBox = bounds.box; // InstancedMesh places these at each instance: the herd's bounds
        geometry.boundingSphere = bounds.sphere;
        this.frustumCulled = true;
        this.boundsVersion = this.instanceMatrix.version;
        this.instanceScale = new Float32Array(count).fill(1);
        this.pal = pal;
        this.localRows = hasLocalRows(pal.header); // CB_LOCAL_ROWS: each bone composed down its chain
        this.states = statesOf(pal, type);
        this.fade = fade;
        this.time = 0;
        this.instanceState = new Array(count).fill(null);
        this.speed = new Float32Array(count);
        this.phase = new Float32Array(count).fill(NaN); // NaN: the state's own phase rule
        this.footsteps = new FootstepClock(type?.clips, count); // the roster's contacts (onContact)
        this.placed = new Array(count).fill(null); // place()'s position, yaw and scale: travel offsets go on top
        this.clipAtRow = new Map(pal.clips.map((c) => [instanceFirstRow(c), c]));
        const textures = paletteTextures(pal);
        const uniforms = {
            cb_palette: { value: textures.palette }, cb_bind_positions: { value: textures.bind },
            cb_row_texels: { value: pal.header.row_texels }, cb_rows_per_block: { value: pal.header.height },
            cb_bounds_min: { value: new THREE.Vector3(...pal.header.bounds_min) },
            cb_bounds_max: { value: new THREE.Vector3(...pal.header.bounds_max) },
            cb_linear_range: { value: pal.header.linear_range }, cb_time: { value: 0 },
        };
        this.uniforms = uniforms;
        const defines = Object.fromEntries(paletteDefines(pal.header).map((d) => [d, '']));
        const auto = autoBonePassVertices(pal.header, bonePassVertices); // local rows: a lower threshold, and why
        this.bonePassVertices = bonePass === 'auto' ? auto.vertices : bonePass ? 0 : Infinity;
        this.bonePassWhy = bonePass === 'auto' ? auto.why : '';
        this.lodOption = lod;
        this.lodTiers = lodTiers;
        this.tiers = null;
        this.animationLod = type?.animation_lod; // lod 'auto': the bake's measure, when the roster has it
        this.lodMesh = mesh; // else lod 'auto' measures its error on first use
        this.lodSize = Math.max(...[0, 1, 2].map((k) => bounds.box.max.getComponent(k) - bounds.box.min.getComponent(k)));
        this.bones = null;
        this.bonesOn = false;
        this.patched = [];
        this.vertexCount = mesh.positions.length / 3;
        this.makeBonePass = () => new HerdBonePass({ glsl, header: pal.header, capacity: count, geometry, uniforms });
        const onBeforeCompile = (shader) => {
            Object.assign(shader.uniforms, uniforms);
            const pars = 'CB_HERD_TIER' in shader.defines ? TIER_VERTEX_PARS : 'CB_BONE_TEXTURE' in shader.defines ? BONE_VERTEX_PARS
                                                                                                      : VERTEX_PARS;
            shader.vertexShader = shader.vertexShader
                .replace('#include <common>', `#include <common>\n${glsl}\n${VERTEX_INPUTS}${pars}`)
                .replace('#include <beginnormal_vertex>', 'vec3 objectNormal = cb_herd_normal(position, normal);')
                .replace('#include <begin_vertex>', 'vec3 transformed = cb_herd_position(position);');
        };
        const customProgramCacheKey = () => `crowdbake-${paletteDefines(pal.header).join('-')}${this.bonesOn ? '-bones' : ''}`;
        const skinnedLike = (m) => {
            this.patched.push(m);
            return Object.assign(m, { defines: { ...m.defines, ...defines }, onBeforeCompile, customProgramCacheKey });
        };
        this.skinnedLike = skinnedLike; // one skinning patch for every primitive's colour, shadow depth and motion vectors
        this.tierLike = (m, k) => Object.assign(m.clone(), { // a LOD tier's copy of a patched material (HerdTiers)
            defines: { ...m.defines, CB_BONE_TEXTURE: '', CB_HERD_TIER: '', CB_INFLUENCES: k }, onBeforeCompile,
            customProgramCacheKey: () => `crowdbake-${paletteDefines(pal.header).join('-')}-tier${k}` });
        (Array.isArray(material) ? material : [material]).forEach(skinnedLike);
        this.customDepthMaterial = skinnedLike(new THREE.MeshDepthMaterial({ depthPacking: THREE.RGBADepthPacking }));
        this.customDistanceMaterial = skinnedLike(new THREE.MeshDistanceMaterial());
        uniforms.cb_previous_time = { value: 0 };
        uniforms.cb_previous_view_projection = { value: new THREE.Matrix4() };
        this.previousViewProjection = null; // null: the camera's current one (the velocity of the animation alone)
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
        const inst = instanceData(s, speed / this.instanceScale[i], i, this.time); // world speed / scale: the model's own speed
        if (!Number.isNaN(phase)) inst[3] = phase;
        this.instanceState[i] = state;
        this.speed[i] = speed;
        this.phase[i] = phase;
        attrs.cb_inst.array.set(inst, i * 4);
        attrs.cb_from.array.set(fade > 0 && current[1] !== 0 ? current : inst, i * 4);
        attrs.cb_fade.array.set([this.time, fade], i * 2);
        attrs.cb_inst.needsUpdate = attrs.cb_from.needsUpdate = attrs.cb_fade.needsUpdate = true;
        this.footsteps.restart(i, inst, this.time);
    }

    // A new speed, keeping the frame it is on (no pop): the phase absorbs the change of rate.
    setSpeed(i, speed) {
        const [, count, rate, phase] = this.geometry.attributes.cb_inst.array.subarray(i * 4, i * 4 + 4);
        const frames = Math.abs(count), fpos = this.time * Math.abs(rate) + phase * frames; // a timed clip's rate < 0
        const next = Math.abs(instanceData(this.states[this.instanceState[i]], speed / this.instanceScale[i], i, this.time)[2]);
        const p = (fpos - this.time * next) / frames;
        this.setState(i, this.instanceState[i], { speed, phase: p - Math.floor(p), fade: 0 });
    }

    // Places instance i at `position` ([x, y, z]), turned `yaw` radians about +y and scaled by
    // `scale`: a locomotion state then plays at speed / (scale x speed reference), feet planted.
    place(i, position, { yaw = 0, scale = 1 } = {}) {
        this.placed[i] = { position: new THREE.Vector3(...position), yaw, scale };
        this.drawPlaced(i);
        const was = this.instanceScale[i];
        this.instanceScale[i] = scale;
        if (was !== scale && this.states[this.instanceState[i]].rate_per_speed !== 0) this.setSpeed(i, this.speed[i]); // same frame
    }

    // Instance i's matrix from its place and, moving at a locomotion state's speed, its travel offset.
    drawPlaced(i) {
        const { position, yaw, scale } = this.placed[i];
        const turn = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 1, 0), yaw);
        const at = this.travelOffsetAt(i).multiplyScalar(scale).applyQuaternion(turn).add(position);
        super.setMatrixAt(i, new THREE.Matrix4().compose(at, turn, new THREE.Vector3().setScalar(scale)));
        this.boundingBox = this.boundingSphere = null;
        this.instanceMatrix.needsUpdate = true;
    }

    // Instance i's per-row travel offset at the herd's time, in the model's frame (model units): where
    // the body of a clip with offsets (.pal version 5) is drawn, relative to a point moving at the
    // state's speed, so its planted feet stay still; cross-fades mix the two clips' offsets as the
    // shader mixes their poses. Zero for an instance at standstill or in a state that does not follow
    // the speed, and for palettes without offsets.
    travelOffsetAt(i, out = new THREE.Vector3()) {
        const s = this.states[this.instanceState[i]];
        out.set(0, 0, 0);
        if (!this.pal.rowTravel || !s?.rate_per_speed || !(this.speed[i] > 0)) return out;
        const a = this.geometry.attributes, at = (attr, n) => attr.array.subarray(i * n, i * n + n);
        const offset = (inst) => {
            const clip = this.clipAtRow.get(inst[0]);
            return clip ? instanceTravelOffset(this.pal, clip, inst, this.time) : [0, 0, 0];
        };
        const [start, length] = at(a.cb_fade, 2), to = offset(at(a.cb_inst, 4));
        const fade = length > 0 ? Math.min(Math.max((this.time - start) / length, 0), 1) : 1;
        const from = fade < 1 ? offset(at(a.cb_from, 4)) : to;
        return out.set(...from.map((v, k) => v + (to[k] - v) * fade));
    }

    // The herd's bounds follow its instances: computed again (lazily, by three's culling) after
    // setMatrixAt or a write to instanceMatrix flagged needsUpdate (an O(count) pass, once a frame
    // at most).
    setMatrixAt(i, matrix) {
        if (this.placed) this.placed[i] = null; // the caller's matrix: it adds travelOffsetAt itself
        super.setMatrixAt(i, matrix);
        this.boundingBox = this.boundingSphere = null;
    }

    // A material that draws the herd's screen-space velocity (RG: 0.5 x NDC now - NDC at the
    // previous update's time, through previousViewProjection) for a TAA or motion-blur pass,
    // e.g. as scene.overrideMaterial into a HalfFloat render target. Instances are taken where
    // they are now: moving ones add their own displacement.
    motionVectorMaterial() {
        const m = this.skinnedLike(new THREE.MeshBasicMaterial());
        const patch = m.onBeforeCompile, key = m.customProgramCacheKey; // with or without the bone pass
        m.onBeforeCompile = (shader, renderer) => {
            patch(shader, renderer);
            shader.vertexShader = shader.vertexShader
                .replace('void main() {', `${MOTION_VERTEX_PARS}\nvoid main() {`) // after the herd's own functions
                .replace('#include <project_vertex>', `#include <project_vertex>\n${MOTION_VERTEX}`);
            shader.fragmentShader = shader.fragmentShader
                .replace('#include <common>', '#include <common>\nin vec4 cb_clip_now; in vec4 cb_clip_before;')
                .replace('#include <dithering_fragment>', MOTION_FRAGMENT);
        };
        m.customProgramCacheKey = () => `${key()}-motion`;
        return m;
    }

    // { lod, reason }: the bone pass's animation LOD and why (measured on first use under 'auto').
    lodChoice() {
        this.lodResolved ??= resolveLod(this.lodOption, this.pal, this.lodMesh, this.lodSize, this.animationLod);
        return this.lodResolved;
    }

    onBeforeRender(renderer, scene, camera) {
        if (this.bonesOn) { // the LOD's scale: pixels tall at w = 1 (size x half the viewport's height x P[1][1])
            const viewport = renderer.getCurrentViewport(new THREE.Vector4()), lod = this.lodChoice().lod;
            this.uniforms.cb_lod.value.set(this.lodSize * 0.5 * viewport.w * camera.projectionMatrix.elements[5],
                                           lod ? lod.two ?? 0 : 0, lod ? lod.one ?? 0 : 0);
        }
        const before = this.uniforms.cb_previous_view_projection.value;
        if (this.previousViewProjection) before.copy(this.previousViewProjection);
        else before.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
    }

    setPhase(i, phase) {
        this.setState(i, this.instanceState[i], { phase, fade: 0 });
    }

    // How the herd is skinned with `renderer` (the one update() was given): { method: 'bones' |
    // 'palette', reason }.
    choice(renderer) {
        const vertices = this.count * this.vertexCount;
        if (this.bonePassVertices === Infinity) return { method: 'palette', reason: 'bonePass: false' };
        if (!renderer) return { method: 'palette', reason: 'update(time) was not given the renderer the bone pass draws with' };
        if (!renderer.extensions.has('EXT_color_buffer_float'))
            return { method: 'palette', reason: 'this WebGL2 cannot render to float textures (no EXT_color_buffer_float)' };
        if (vertices < this.bonePassVertices)
            return { method: 'palette', reason: `${vertices} skinned vertices a frame < ${this.bonePassVertices}: the bone pass ` +
                     `would not pay for its extra pass (bonePass: true forces it)${this.bonePassWhy}` };
        return { method: 'bones', reason: this.bonePassVertices ? `${vertices} skinned vertices a frame >= ${this.bonePassVertices}` +
                 `: each bone blended once per instance (bonePass: false draws per vertex)${this.bonePassWhy}` : 'bonePass: true' };
    }

    // Switches every patched material (colour, shadow depth, motion vectors) to the bone pass or back:
    // a define, so three compiles each variant once and keeps both.
    useBonePass(on) {
        if (on === this.bonesOn) return;
        this.bonesOn = on;
        this.bones ??= on ? this.makeBonePass() : null;
        for (const m of this.patched) {
            if (on) m.defines.CB_BONE_TEXTURE = '';
            else delete m.defines.CB_BONE_TEXTURE;
            m.needsUpdate = true;
        }
    }

    // GPU bytes per instance: its matrix, colour slot and four crowdbake rows (14 + 16 + 4 floats
    // with a colour), the bone pass's 48 bytes a bone when it runs, and with the LOD's tiers drawn apart, the tier's
    // copy of its matrix and its row in the pass (17 floats).
    bytesPerInstance() {
        return (16 + 4 + 4 + 2 + (this.instanceColor ? 3 : 0)) * 4 + (this.bonesOn ? 48 * this.pal.header.bone_count : 0) +
               (this.tiers?.meshes[0].layers.mask ? 17 * 4 : 0);
    }

    // The clock the shader plays every instance at, in seconds; the time it replaces is the
    // motion vectors' previous frame. With the renderer, the bone pass runs here when chosen; with the camera too,
    // the LOD's tiers are sorted here for it (lodTiers), at the renderer's current viewport.
    update(time, renderer = null, camera = null) {
        this.uniforms.cb_previous_time.value = this.time;
        const inst = this.geometry.attributes.cb_inst.array;
        this.footsteps.advance(this.count, time, (i) => [this.states[this.instanceState[i]].clip, inst.subarray(i * 4, i * 4 + 4)]);
        this.time = time;
        this.uniforms.cb_time.value = time;
        // Placed instances first: the bone pass reads their matrices.
        if (this.pal.rowTravel) for (let i = 0; i < this.count; ++i) if (this.placed[i]) this.drawPlaced(i);
        this.useBonePass(this.choice(renderer).method === 'bones');
        if (this.bonesOn) this.bones.run(renderer, this.count);
        const lod = this.bonesOn && this.lodTiers && camera ? this.lodChoice().lod : false;
        if (lod) { // the LOD's scale, as onBeforeRender sets cb_lod.x
            const viewport = renderer.getCurrentViewport(new THREE.Vector4());
            this.tiers ??= new HerdTiers(this, this.tierLike);
            this.tiers.sort(camera, lod, this.lodSize * 0.5 * viewport.w * camera.projectionMatrix.elements[5]);
        } else this.tiers?.off();
        if (this.instanceMatrix.version !== this.boundsVersion) {
            this.boundsVersion = this.instanceMatrix.version;
            this.boundingBox = this.boundingSphere = null;
        }
    }

    // Calls listener({ instance, foot, bone, kind: 'land' | 'lift', time }) from update() whenever an
    // instance's clip time crosses one of its clip's footstep contacts (the roster type's clips'
    // contacts): every crossing since the last update, in order, across loop ends and rate changes.
    onContact(listener) {
        this.footsteps.listeners.push(listener);
        return this;
    }

    // The skinning matrix (bind space to the instance's posed model, before its instance matrix) of
    // `bone` for instance i at the herd's time: its clip, time and cross-fade, as the shader blends.
    boneMatrixAt(i, bone, out = new THREE.Matrix4()) {
        const a = this.geometry.attributes, at = (attr, n) => attr.array.subarray(i * n, i * n + n);
        const [start, length] = at(a.cb_fade, 2);
        const fade = length > 0 ? Math.min(Math.max((this.time - start) / length, 0), 1) : 1;
        // A cross-fade as the shader blends it (global rows: the two matrices mixed; local rows: each bone's two
        // local poses blended, then composed).
        return out.fromArray(fade < 1 ? instanceBoneMatrixCrossfade(this.pal, at(a.cb_from, 4), at(a.cb_inst, 4), fade, this.time, bone)
            : instanceBoneMatrix(this.pal, at(a.cb_inst, 4), this.time, bone));
    }

    // Where a prop attached to a socket (a roster socket: { bone, bind_transform }) of instance i is
    // in the world: the herd's world matrix x the instance's matrix x the bone's x the socket's.
    socketMatrixAt(i, socket, out = new THREE.Matrix4()) {
        const instance = new THREE.Matrix4();
        this.getMatrixAt(i, instance);
        this.boneMatrixAt(i, socket.bone, out).multiply(new THREE.Matrix4().fromArray(socket.bind_transform));
        return out.premultiply(instance).premultiply(this.matrixWorld);
    }
}

