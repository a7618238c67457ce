// crowdbake_bones.mjs - the bone pass of crowdbake_crowd.mjs (new Crowd(gl, { ..., bonePass: 'auto' | true })).
// Per-vertex skinning decodes and blends every influence's bone from the palette's two rows at
// every vertex. The bone pass does that once per instance and bone: before the draw, one fragment
// per (instance, bone) writes the bone's blended transform (cross-fade included) to three RGBA32F
// render targets (cb_bone_pass_placed of the shipped GLSL: the instance's yaw, scale and position applied
// too), and the draw's vertex shader reads it back with three plain texel fetches an influence, blends
// the influences' transforms and applies the sum once (cb_skin_bone_pass_influences, #define
// CB_BONE_TEXTURE), straight to world space. It needs
// EXT_color_buffer_float (render to float textures), which WebGL2 on desktop GPUs and SwiftShader have.
import { compileProgram, paletteDefines } from './crowdbake_crowd.mjs';
import { rowBoneMatrix, hasLocalRows } from './crowdbake_pal.mjs';

const PASS_VERTEX = `
in vec4 a_place; in vec4 a_inst; in vec4 a_from; in vec4 a_fade;
uniform float u_time; uniform int u_rows; uniform vec2 u_size;
flat out vec4 v_place; flat out vec4 v_inst; flat out vec4 v_from; flat out vec2 v_fade; flat out int v_x0;
void main() {  // instance i: a quad over its row of bones in its column block
    int block = gl_InstanceID / u_rows, row = gl_InstanceID - block * u_rows, bones = cb_row_texels / CB_TEXELS_PER_BONE;
    v_x0 = block * bones;
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    vec2 px = vec2(float(v_x0) + corner.x * float(bones), float(row) + corner.y);
    gl_Position = vec4(px / u_size * 2.0 - 1.0, 0.0, 1.0);
    v_place = a_place, v_inst = a_inst, v_from = a_from;
    v_fade = vec2(a_fade.y > 0.0 ? clamp((u_time - a_fade.x) / a_fade.y, 0.0, 1.0) : 1.0, a_fade.z); // weight, scale
}
`;

const PASS_FRAGMENT = `
flat in vec4 v_place; flat in vec4 v_inst; flat in vec4 v_from; flat in vec2 v_fade; flat in int v_x0;
uniform float u_time;
layout(location = 0) out vec4 o_c0; layout(location = 1) out vec4 o_c1; layout(location = 2) out vec4 o_c2;
void main() {
    cb_bone_pass_placed(int(gl_FragCoord.x) - v_x0, v_from, v_inst, v_fade.x, u_time, v_place, v_fade.y, o_c0, o_c1, o_c2);
}
`;

// When a Crowd with bonePass: 'auto' (the default) takes the bone pass: from this many skinned
// vertices a frame (instances x mesh vertices). Below it the pass's fixed cost (a render target
// switch and a second program) is not paid back; above it, per-vertex blending decodes and blends
// every influence's bone at every vertex, the bone pass once per instance and bone (bench/run.py's
// crowd benchmark measures both: the bone pass is ahead from 100 Cows, 500 k vertices).
export const AUTO_BONE_PASS_VERTICES = 50000;
// The same for local rows (.pal version 6): their per-vertex path walks each influence's chain to the root (Cow: up to
// 11 bones, each decoded and blended), so the bone pass pays back far sooner. Measured (web43, bench_crowd.mjs,
// SwiftShader, local palettes, medians of interleaved frames): 1 fish (336 vertices) per vertex 4.1 ms, bone pass
// 8.9; 3 fish (1,008) 5.0 and 5.1; 10 fish (3,360) 7.8 and 5.6; 1 Cow (4,970) 40.4 and 9.5; 2 Cows 34.3 and 11.3.
export const AUTO_BONE_PASS_VERTICES_LOCAL = 3000;

// The bonePass: 'auto' threshold for a palette: { vertices, why } (a given bonePassVertices wins).
export function autoBonePassVertices(header, given) {
    if (given !== undefined) return { vertices: given, why: '' };
    if (!hasLocalRows(header)) return { vertices: AUTO_BONE_PASS_VERTICES, why: '' };
    return { vertices: AUTO_BONE_PASS_VERTICES_LOCAL, why: ` (local rows: the per-vertex path walks each influence's chain, ` +
        `so 'auto' takes the pass from ${AUTO_BONE_PASS_VERTICES_LOCAL}, not ${AUTO_BONE_PASS_VERTICES})` };
}

// Animation LOD, on by default: an instance whose animated bounds span fewer than `two` pixels on
// screen is skinned with its 2 largest bone weights, fewer than `one` pixels with its largest alone
// (the kept weights scaled to sum to 1), the rule crowdbake mesh --max-influences 2|1 applies to a far
// LOD mesh. lod: 'auto' (the default: lodThresholds, from the model's own error), false, or { two, one }
// (0: never). DEFAULT_LOD: fixed thresholds, what 'auto' was before it and the Godot herd's default (at 24
// pixels a pixel is 4% of the animal): pass it as lod to draw as a Godot herd does.
export const DEFAULT_LOD = { two: 24, one: 12 };
export const LOD_PIXEL_ERROR = 1; // 'auto': the most a vertex may move, in pixels, for the LOD's fewer influences
export const LOD_POSES = 64;      // 'auto': poses measured, spread evenly over every clip's rows

// The animation LOD's thresholds for a model (lod: 'auto'): the sizes on screen (pixels, as lodUniform
// measures them: `size` tall) under which skinning with the 2 largest weights, or the largest alone,
// moves no vertex more than `pixelError` pixels from its full skin - the worst vertex over `poses` poses
// spread over every clip's rows. A vertex's error scales with the instance's size on screen, so a
// tier whose worst vertex is off by a fraction f of `size` is within `pixelError` below pixelError / f
// pixels. mesh: positions, joints, weights (as Crowd takes them). Returns { two, one, worst: { two, one },
// poses } (worst: fractions of `size`; a tier that moves nothing gets 1e6 pixels).
export function lodThresholds(pal, mesh, size, { pixelError = LOD_PIXEL_ERROR, poses = LOD_POSES } = {}) {
    const bones = pal.header.bone_count, verts = mesh.positions.length / 3, m = new Float64Array(bones * 16), b = new Array(16);
    const rows = pal.clips.reduce((n, c) => n + c.frames, 0), worst = [0, 0], p = new Float64Array(12);
    const { joints, weights } = sortInfluences(mesh.joints, mesh.weights);
    const x = mesh.positions;
    for (let k = 0; k < poses; ++k) {
        let row = Math.floor((k + 0.5) * rows / poses), clip = 0; // the k-th of `poses` rows spread over every clip
        while (row >= pal.clips[clip].frames) row -= pal.clips[clip++].frames;
        const at = pal.clips[clip].first_row + row; // the row itself: a timed clip's rows lie at no fixed rate
        for (let j = 0; j < bones; ++j) m.set(rowBoneMatrix(pal, at, j, b), j * 16);
        for (let v = 0; v < verts; ++v) {
            const px = x[v * 3], py = x[v * 3 + 1], pz = x[v * 3 + 2];
            let n = 0; // p: each influence's skinned point, 3 numbers each
            for (; n < 4 && weights[v * 4 + n]; ++n) {
                const o = joints[v * 4 + n] * 16;
                for (let r = 0; r < 3; ++r) p[n * 3 + r] = m[o + r] * px + m[o + 4 + r] * py + m[o + 8 + r] * pz + m[o + 12 + r];
            }
            if (!n) continue; // no weight: nothing skins it
            const w0 = weights[v * 4], w1 = n > 1 ? weights[v * 4 + 1] : 0, kept2 = w0 + w1;
            let d1 = 0, d2 = 0;
            for (let r = 0; r < 3; ++r) {
                let full = 0;
                for (let i = 0; i < n; ++i) full += weights[v * 4 + i] * p[i * 3 + r];
                const one = p[r] - full, two = (w0 * p[r] + w1 * p[3 + r]) / kept2 - full;
                d1 += one * one, d2 += two * two;
            }
            worst[0] = Math.max(worst[0], Math.sqrt(d1) / size), worst[1] = Math.max(worst[1], Math.sqrt(d2) / size);
        }
    }
    const pixels = (f) => (f > pixelError / 1e6 ? pixelError / f : 1e6);
    const one = pixels(worst[0]);
    return { two: Math.max(pixels(worst[1]), one), one, worst: { two: worst[1], one: worst[0] }, poses, pixelError };
}

// The thresholds of lod 'auto' from what the bake measured: a roster type's animation_lod (each tier's worst vertex
// error in model units over every frame of its clips at 30 fps, docs/roster.md), for an animal `size` units tall
// on screen: under pixelError x size / error pixels no vertex moves more than pixelError pixels. The shape
// lodThresholds returns (poses: the frames the bake measured); null without a usable measure.
export function lodThresholdsMeasured(measured, size, { pixelError = LOD_PIXEL_ERROR } = {}) {
    const one = measured?.one_influence_error, two = measured?.two_influences_error;
    if (!(one >= 0 && two >= 0 && size > 0)) return null;
    const pixels = (e) => (e > 0 ? pixelError * size / e : 1e6), worst = { two: two / size, one: one / size };
    return { two: Math.max(pixels(two), pixels(one)), one: pixels(one), worst, poses: measured.frames ?? 0, pixelError };
}

// The LOD to draw with and why: lod as given ('auto': the roster type's animation_lod when given, `measured`, else
// lodThresholds measured here), as { lod, reason }.
export function resolveLod(lod, pal, mesh, size, measured) {
    if (lod === false) return { lod: false, reason: 'lod: false: every influence at every size' };
    if (lod !== 'auto') return { lod, reason: `lod: { two: ${lod.two ?? 0}, one: ${lod.one ?? 0} } as given` };
    const fromRoster = lodThresholdsMeasured(measured, size), t = fromRoster ?? lodThresholds(pal, mesh, size);
    const where = fromRoster ? `the roster's animation_lod, ${t.poses} frames` : `${t.poses} poses measured here`;
    return { lod: { two: t.two, one: t.one }, thresholds: t,
             reason: `lod 'auto': 2 influences under ${t.two.toFixed(1)} pixels tall, 1 under ${t.one.toFixed(1)}: there the ` +
                     `worst vertex (${where}) moves at most ${t.pixelError} pixel (${(t.worst.two * 100).toFixed(2)}% ` +
                     `and ${(t.worst.one * 100).toFixed(2)}% of the animal's size); lod: { two, one } or false overrides` };
}

// The vertex main that skins from the bone pass straight to world space (the pass placed each bone).
export const MAIN_BONES = `
in vec3 a_position; in vec3 a_normal; in ivec4 a_joints; in vec4 a_weights;
in vec4 a_place; in vec4 a_fade;
uniform mat4 u_view_projection; uniform vec3 u_lod; // pixels tall at w = 1 and scale 1, the two thresholds
out vec3 v_world; out vec3 v_normal;
void main() {
    float pixels = u_lod.x * a_fade.z / (u_view_projection * vec4(a_place.xyz, 1.0)).w; // the instance's size on screen
    cb_skin_bone_pass_influences(a_position, a_normal, a_joints, a_weights, gl_InstanceID, cb_lod_influences(pixels, u_lod.y, u_lod.z),
                                 v_world, v_normal);
    gl_Position = u_view_projection * vec4(v_world, 1.0);
}
`;

// The LOD's tiers drawn apart (Crowd's lodTiers, the default): each frame every instance's tier is found once on the
// CPU (lodTier, the rule MAIN_BONES applies per vertex), the instances are bucketed by tier, and each tier draws with
// a program compiled for its influences (CB_INFLUENCES 1, 2, 4: no influence count, loop or size test a vertex on the
// far tiers). a_bone_instance: the instance's row in the bone pass (the tier's order, pointed at its first).
export const TIER_INFLUENCES = [1, 2, 4];
export const MAIN_BONE_TIER = `
in vec3 a_position; in vec3 a_normal; in ivec4 a_joints; in vec4 a_weights; in int a_bone_instance;
uniform mat4 u_view_projection;
out vec3 v_world; out vec3 v_normal;
void main() {
    cb_skin_bone_pass(a_position, a_normal, a_joints, a_weights, a_bone_instance, v_world, v_normal);
    gl_Position = u_view_projection * vec4(v_world, 1.0);
}
`;

// The tier (0: 1 influence, 1: 2, 2: every one) of an instance at place (x, y, z) and scale, for u (lodUniform's):
// MAIN_BONES's cb_lod_influences on the same size on screen (in double precision: an instance within a rounding
// of a threshold may take the other side of it).
export function lodTier(viewProjection, u, x, y, z, scale) {
    const m = viewProjection, pixels = (u[0] * scale) / (m[3] * x + m[7] * y + m[11] * z + m[15]);
    return pixels < u[2] ? 0 : pixels < u[1] ? 1 : 2;
}

export class LodTiers {
    // fragment: the draw's fragment shader; makeVertexArray(program): the crowd's mesh and instance attributes.
    constructor(gl, { glsl, header, fragment, capacity, makeVertexArray }) {
        this.gl = gl;
        this.programs = TIER_INFLUENCES.map((k) => compileProgram(gl, boneShaderSource(glsl, header, MAIN_BONE_TIER,
            ['CB_BONE_TEXTURE', `CB_INFLUENCES ${k}`]), fragment));
        this.order = new Int32Array(capacity); // the instances by tier, the frame's
        this.first = [0, 0, 0];
        this.count = [0, 0, 0];
        this.next = [0, 0, 0];
        this.buffer = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
        gl.bufferData(gl.ARRAY_BUFFER, this.order.byteLength, gl.DYNAMIC_DRAW);
        this.arrays = this.programs.map((p) => {
            const vao = makeVertexArray(p), loc = gl.getAttribLocation(p, 'a_bone_instance');
            gl.bindVertexArray(vao);
            gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
            gl.enableVertexAttribArray(loc);
            gl.vertexAttribIPointer(loc, 1, gl.INT, 4, 0);
            gl.vertexAttribDivisor(loc, 1);
            gl.bindVertexArray(null);
            return { vao, loc };
        });
    }

    // Buckets instances 0..n-1 by tier, stable (instances: `stride` floats a row, place x, y, z first, the scale at
    // `scaleAt`), into this.order: tier k is order[first[k] .. first[k] + count[k]). No allocation.
    sort(instances, stride, scaleAt, n, viewProjection, u) {
        const { order, first, count, next } = this, tier = (i) => lodTier(viewProjection, u, instances[i * stride],
            instances[i * stride + 1], instances[i * stride + 2], instances[i * stride + scaleAt]);
        count.fill(0);
        for (let i = 0; i < n; ++i) ++count[tier(i)];
        first[0] = next[0] = 0, first[1] = next[1] = count[0], first[2] = next[2] = count[0] + count[1];
        for (let i = 0; i < n; ++i) order[next[tier(i)]++] = i; // the tier again, not stored: nothing to allocate
    }

    // One draw a nonempty tier of the sorted n: bind(program) sets its textures and uniforms, draw(count) draws.
    draw(n, bind, draw) {
        const gl = this.gl;
        gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
        gl.bufferSubData(gl.ARRAY_BUFFER, 0, this.order, 0, n);
        let draws = 0;
        for (let k = 0; k < 3; ++k) {
            if (!this.count[k]) continue;
            gl.useProgram(this.programs[k]);
            gl.bindVertexArray(this.arrays[k].vao);
            bind(this.programs[k]);
            gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
            gl.vertexAttribIPointer(this.arrays[k].loc, 1, gl.INT, 4, this.first[k] * 4);
            draw(this.count[k]);
            ++draws;
        }
        gl.bindVertexArray(null);
        return draws;
    }

    dispose() {
        const gl = this.gl;
        this.programs.forEach((p) => gl.deleteProgram(p));
        this.arrays.forEach((a) => gl.deleteVertexArray(a.vao));
        gl.deleteBuffer(this.buffer);
    }
}

// u_lod for a draw: the instance's size on screen is size x scale x (viewport height / 2) x P[1][1] / w,
// and P[1][1] is the length of the view-projection's second row (the view's rotation keeps lengths).
export function lodUniform(lod, size, viewProjection, viewportHeight) {
    if (!lod) return [0, 0, 0];
    const p11 = Math.hypot(viewProjection[1], viewProjection[5], viewProjection[9]);
    return [size * 0.5 * viewportHeight * p11, lod.two ?? 0, lod.one ?? 0];
}

// The mesh's triangles ordered by how many influences their vertices read (stable within each count):
// a CPU rasteriser shades neighbouring vertices of the index list together and runs the influence loop
// as long as the longest of them, so grouping alike vertices shortens the loops. The same triangles.
export function sortTrianglesByInfluences(indices, weights) {
    const count = (v) => (weights[v * 4 + 3] ? 4 : weights[v * 4 + 2] ? 3 : weights[v * 4 + 1] ? 2 : 1);
    const triangles = indices.length / 3, keys = new Uint8Array(triangles), order = new Uint32Array(triangles);
    for (let t = 0; t < triangles; ++t)
        keys[t] = Math.max(count(indices[t * 3]), count(indices[t * 3 + 1]), count(indices[t * 3 + 2])), order[t] = t;
    order.sort((a, b) => keys[a] - keys[b] || a - b);
    const out = new indices.constructor(indices.length);
    order.forEach((t, k) => out.set(indices.subarray(t * 3, t * 3 + 3), k * 3));
    return out;
}

// Each vertex's influences largest weight first (the order LOD keeps), in place of mesh.joints/weights.
export function sortInfluences(joints, weights) {
    const j = Int32Array.from(joints), w = Float32Array.from(weights);
    for (let v = 0; v < w.length; v += 4) {
        const order = [0, 1, 2, 3].sort((a, b) => weights[v + b] - weights[v + a]);
        order.forEach((k, i) => { j[v + i] = joints[v + k]; w[v + i] = weights[v + k]; });
    }
    return { joints: j, weights: w };
}

// The shipped library with the palette's defines (and `extra`), then a main.
export function boneShaderSource(glsl, header, main, extra = []) {
    const defines = [...paletteDefines(header), ...extra].map((d) => `#define ${d}\n`).join('');
    return `#version 300 es\n${defines}${glsl}\n${main}`;
}

export class BonePass {
    // It reads a_inst, a_from and a_fade from the crowd's instanceBuffer (instanceFloats a row);
    // rows: instances per column block of the bone textures (the GPU's texture size, or fewer).
    constructor(gl, { glsl, header, capacity, instanceBuffer, instanceFloats, rows = Infinity }) {
        if (!gl.getExtension('EXT_color_buffer_float'))
            throw new Error('bonePass: this WebGL2 cannot render to float textures (no EXT_color_buffer_float); draw without it');
        const max = gl.getParameter(gl.MAX_TEXTURE_SIZE), bones = header.bone_count;
        this.gl = gl;
        this.header = header;
        this.capacity = capacity;
        this.rows = Math.min(capacity, max, rows);
        this.width = Math.ceil(capacity / this.rows) * bones;
        if (this.width > max) throw new Error(`bonePass: ${capacity} instances of ${bones} bones exceed this GPU's ${max}-texel textures`);
        this.program = compileProgram(gl, boneShaderSource(glsl, header, PASS_VERTEX), boneShaderSource(glsl, header, PASS_FRAGMENT));
        this.targets = [0, 1, 2].map(() => {
            const t = gl.createTexture();
            gl.bindTexture(gl.TEXTURE_2D, t);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
            gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, this.width, this.rows);
            return t;
        });
        this.framebuffer = gl.createFramebuffer();
        gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, this.framebuffer);
        this.targets.forEach((t, k) => gl.framebufferTexture2D(gl.DRAW_FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + k, gl.TEXTURE_2D, t, 0));
        gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1, gl.COLOR_ATTACHMENT2]);
        const status = gl.checkFramebufferStatus(gl.DRAW_FRAMEBUFFER);
        gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, null);
        if (status !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`bonePass: the bone textures are not renderable (0x${status.toString(16)})`);
        this.vao = gl.createVertexArray();
        gl.bindVertexArray(this.vao);
        gl.bindBuffer(gl.ARRAY_BUFFER, instanceBuffer);
        [['a_place', 0], ['a_inst', 1], ['a_from', 2], ['a_fade', 3]].forEach(([name, k]) => {
            const loc = gl.getAttribLocation(this.program, name);
            if (loc < 0) return;
            gl.enableVertexAttribArray(loc);
            gl.vertexAttribPointer(loc, 4, gl.FLOAT, false, instanceFloats * 4, k * 16);
            gl.vertexAttribDivisor(loc, 1);
        });
        gl.bindVertexArray(null);
        this.bytes = this.width * this.rows * 16 * 3;
    }

    // Blends the bones of instances 0..count-1 at `time`; bindPalette(u) binds the palette's textures.
    run(count, time, bindPalette) {
        const gl = this.gl, p = this.program;
        const framebuffer = gl.getParameter(gl.DRAW_FRAMEBUFFER_BINDING), viewport = gl.getParameter(gl.VIEWPORT);
        const blend = gl.isEnabled(gl.BLEND), depth = gl.isEnabled(gl.DEPTH_TEST), scissor = gl.isEnabled(gl.SCISSOR_TEST);
        gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, this.framebuffer);
        gl.viewport(0, 0, this.width, this.rows);
        gl.disable(gl.BLEND);
        gl.disable(gl.DEPTH_TEST);
        gl.disable(gl.SCISSOR_TEST); // a page drawing into part of its canvas must not clip the bone textures
        gl.useProgram(p);
        gl.bindVertexArray(this.vao);
        const u = (name) => gl.getUniformLocation(p, name);
        bindPalette(u);
        gl.uniform1f(u('u_time'), time);
        gl.uniform1i(u('u_rows'), this.rows);
        gl.uniform2f(u('u_size'), this.width, this.rows);
        gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 4, count);
        gl.bindVertexArray(null);
        gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, framebuffer);
        gl.viewport(...viewport);
        if (blend) gl.enable(gl.BLEND);
        if (depth) gl.enable(gl.DEPTH_TEST);
        if (scissor) gl.enable(gl.SCISSOR_TEST);
    }

    // Frees its textures, framebuffer, program and vertex array (a larger pass replaces it).
    dispose() {
        const gl = this.gl;
        this.targets.forEach((t) => gl.deleteTexture(t));
        gl.deleteFramebuffer(this.framebuffer);
        gl.deleteProgram(this.program);
        gl.deleteVertexArray(this.vao);
    }

    // Binds the bone textures to units 2-4 of the draw's program.
    bindTargets(u) {
        const gl = this.gl;
        this.targets.forEach((t, k) => {
            gl.activeTexture(gl.TEXTURE2 + k);
            gl.bindTexture(gl.TEXTURE_2D, t);
            gl.uniform1i(u(`cb_bones${k}`), 2 + k);
        });
        gl.uniform1i(u('cb_bone_rows'), this.rows);
    }
}
