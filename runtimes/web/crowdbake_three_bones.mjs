// crowdbake_three_bones.mjs - the bone pass of CrowdbakeHerd (crowdbake_three.mjs), as crowdbake_bones.mjs
// is the WebGL2 Crowd's: before the herd draws, one fragment per (instance, bone) blends the bone's
// transform at the herd's time (cross-fade included) into a three.js render target of three RGBA32F
// textures (cb_bone_pass of the shipped GLSL); the herd's materials, compiled with CB_BONE_TEXTURE,
// then skin from it (cb_skin_bone_pass_influences): three texel fetches an influence, no decoding.
// The instance matrix stays three's (its culling, shadows and setMatrixAt work as before), so the
// bones are not placed in the world here. It renders with the renderer given to herd.update(time,
// renderer); three.js renders to float targets where WebGL2 has EXT_color_buffer_float.
import * as THREE from 'three';
import { paletteDefines } from './crowdbake_crowd.mjs';

const PASS_VERTEX = `
in vec4 cb_inst; in vec4 cb_from; in vec2 cb_fade;
uniform float cb_time; uniform int cb_pass_rows; uniform vec2 cb_pass_size;
flat out vec4 v_inst; flat out vec4 v_from; flat out float v_fade; flat out int v_x0;
void main() {  // instance i: a quad over its row of bones in its column block
    int block = gl_InstanceID / cb_pass_rows, row = gl_InstanceID - block * cb_pass_rows, bones = cb_row_texels / CB_TEXELS_PER_BONE;
    v_x0 = block * bones;
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    vec2 px = vec2(float(v_x0) + corner.x * float(bones), float(row) + corner.y);
    gl_Position = vec4(px / cb_pass_size * 2.0 - 1.0, 0.0, 1.0);
    v_inst = cb_inst, v_from = cb_from;
    v_fade = cb_fade.y > 0.0 ? clamp((cb_time - cb_fade.x) / cb_fade.y, 0.0, 1.0) : 1.0;
}
`;

const PASS_FRAGMENT = `
flat in vec4 v_inst; flat in vec4 v_from; flat in float v_fade; flat in int v_x0;
uniform float cb_time;
layout(location = 0) out vec4 o_c0; layout(location = 1) out vec4 o_c1; layout(location = 2) out vec4 o_c2;
void main() { cb_bone_pass(int(gl_FragCoord.x) - v_x0, v_from, v_inst, v_fade, cb_time, o_c0, o_c1, o_c2); }
`;

// The herd's skinning with the bone pass (CB_BONE_TEXTURE): the same two functions as the
// per-vertex VERTEX_PARS of crowdbake_three.mjs, read from the pass's textures.
export const BONE_VERTEX_PARS = `
uniform vec3 cb_lod; // the animation LOD: pixels tall at w = 1 and scale 1, the 2- and 1-influence thresholds
vec3 cb_skinned_position; bool cb_skinned = false;
int cb_herd_influences() { // the instance's size on screen: its origin's depth and its scale
#ifdef USE_INSTANCING
    mat4 place = modelMatrix * instanceMatrix;
#else
    mat4 place = modelMatrix;
#endif
    float w = (projectionMatrix * viewMatrix * place[3]).w;
    return cb_lod_influences(cb_lod.x * length(place[0].xyz) / w, cb_lod.y, cb_lod.z);
}
vec3 cb_herd_normal(vec3 p, vec3 n) {
    vec3 skinned_n;
    cb_skin_bone_pass_influences(p, n, ivec4(cb_joints), cb_weights, gl_InstanceID, cb_herd_influences(), cb_skinned_position,
                                 skinned_n);
    cb_skinned = true;
    return skinned_n;
}
vec3 cb_herd_position(vec3 p) {
    vec3 n;
    if (!cb_skinned) cb_skin_bone_pass_influences(p, vec3(0.0, 1.0, 0.0), ivec4(cb_joints), cb_weights, gl_InstanceID,
                                                  cb_herd_influences(), cb_skinned_position, n);
    return cb_skinned_position;
}
`;

export class HerdBonePass {
    // geometry: the herd's (its cb_inst, cb_from and cb_fade rows are the pass's instances); uniforms:
    // the herd's palette uniforms, which gain cb_bones0..2 and cb_bone_rows.
    constructor({ glsl, header, capacity, geometry, uniforms }) {
        const max = 8192; // SwiftShader's and most GPUs' texture size, at least WebGL2's 2048 guaranteed is too few rows
        this.rows = Math.min(capacity, max);
        this.width = Math.ceil(capacity / this.rows) * header.bone_count;
        this.target = new THREE.WebGLRenderTarget(this.width, this.rows, {
            count: 3, type: THREE.FloatType, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter,
            magFilter: THREE.NearestFilter, depthBuffer: false, generateMipmaps: false,
        });
        const quad = new THREE.InstancedBufferGeometry();
        quad.setAttribute('position', new THREE.BufferAttribute(new Float32Array(12), 3)); // corners: gl_VertexID
        quad.setIndex([0, 1, 2, 2, 1, 3]);
        for (const name of ['cb_inst', 'cb_from', 'cb_fade']) quad.setAttribute(name, geometry.attributes[name]);
        const defines = paletteDefines(header).map((d) => `#define ${d}\n`).join('');
        Object.assign(uniforms, {
            cb_bones0: { value: this.target.textures[0] }, cb_bones1: { value: this.target.textures[1] },
            cb_bones2: { value: this.target.textures[2] }, cb_bone_rows: { value: this.rows },
            cb_pass_rows: { value: this.rows }, cb_pass_size: { value: new THREE.Vector2(this.width, this.rows) },
            cb_lod: { value: new THREE.Vector3() },
        });
        const material = new THREE.RawShaderMaterial({
            glslVersion: THREE.GLSL3, uniforms, depthTest: false, depthWrite: false,
            vertexShader: `${defines}${glsl}\n${PASS_VERTEX}`, fragmentShader: `${defines}${glsl}\n${PASS_FRAGMENT}`,
        });
        this.quad = quad;
        this.mesh = new THREE.Mesh(quad, material);
        this.mesh.frustumCulled = false;
        this.scene = new THREE.Scene();
        this.scene.add(this.mesh);
        this.camera = new THREE.OrthographicCamera(); // unused: the pass's vertex shader places its quads itself
        this.bytes = this.width * this.rows * 16 * 3;
    }

    // Blends the bones of instances 0..count-1 (at the uniforms' cb_time) into the target.
    run(renderer, count) {
        this.quad.instanceCount = count;
        const previous = renderer.getRenderTarget(), autoClear = renderer.autoClear;
        renderer.autoClear = false; // every texel of instances 0..count-1 is written
        renderer.setRenderTarget(this.target);
        renderer.render(this.scene, this.camera);
        renderer.setRenderTarget(previous);
        renderer.autoClear = autoClear;
    }
}
