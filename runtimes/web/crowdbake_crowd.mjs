// crowdbake_crowd.mjs - a WebGL2 crowd runtime for crowdbake palettes: one instanced draw call per
// animal type. An ES module with no dependencies (readPal from crowdbake_pal.mjs gives the palette).
//
//     import { readPal } from './crowdbake_pal.mjs';
//     import { Crowd, loadPaletteGLSL } from './crowdbake_crowd.mjs';
//     const crowd = new Crowd(gl, { pal: readPal(bytes), glsl: await loadPaletteGLSL(), mesh, capacity: 10000 });
//     crowd.setInstance(i, { position: [x, 0, z], yaw, inst: instanceData(state, speed, i) });
//     crowd.draw(viewProjection, seconds);                 // every instance, one drawElementsInstanced
//
// The vertex shader is runtimes/glsl/crowdbake_palette.glsl itself (ES 3.00), prefixed with the
// palette's #defines: there is no second copy of the skinning to drift. `make` writes it beside these
// modules as crowdbake_palette_glsl.mjs (a string), so the modules find it wherever they are served.
// `mesh` holds the skinned mesh in the model's own vertex order, as the palette's bone indices
// expect: positions (3 floats a vertex), normals (3, optional), joints (4 integers), weights (4
// floats), indices (optional).

import { autoBonePassVertices, BonePass, LodTiers, MAIN_BONES, resolveLod, boneShaderSource, lodUniform, sortInfluences,
         sortTrianglesByInfluences } from './crowdbake_bones.mjs';

import { hasLocalRows } from './crowdbake_pal.mjs';
import { PALETTE_GLSL } from './crowdbake_palette_glsl.mjs';

// Where the source tree keeps the GLSL file, relative to this module (the viewer's site has it there).
export const GLSL_URL = new URL('../glsl/crowdbake_palette.glsl', import.meta.url);

// The shipped GLSL: the copy made at build time beside this module, or the text at `url` (another
// version of the library, e.g. a shader being edited).
export async function loadPaletteGLSL(url) {
    if (url === undefined) return PALETTE_GLSL;
    const response = await fetch(url);
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status} (the runtime's vertex shader)`);
    return response.text();
}

// The defines that select the library's layout and precision for a .pal header; CB_LOCAL_ROWS for local rows
// (version 6: each bone blended in its parent's frame, then composed down its chain).
export function paletteDefines(header) {
    const defines = [`CB_LAYOUT_${header.layout_name.toUpperCase()}`, `CB_PRECISION_${header.precision_name.toUpperCase()}`];
    if (header.flags & 4) defines.push('CB_POSITIONS_RELATIVE');
    if (hasLocalRows(header)) defines.push('CB_LOCAL_ROWS');
    return defines;
}

// The per-bone texels of cb_bind_positions (RGBA32F, one texel a bone): row 0 xyz the bind position, row 1 xyz the
// position offset; local rows add row 2 (the parent's index as a float, -1 for a root), row 3 (pos_min, scale_max)
// and row 4 (pos_max, 0), what the shader walks chains and decodes u16 with. Returns { data, rows }.
export function bonePositionTexels(pal) {
    const n = pal.header.bone_count, rows = hasLocalRows(pal.header) ? 5 : 2, data = new Float32Array(n * rows * 4);
    pal.bones.forEach((b, j) => {
        data.set(b.bind_position, j * 4);
        data.set(b.position_offset, (n + j) * 4);
        if (rows < 5) return;
        data[(2 * n + j) * 4] = b.parent;
        data.set([...b.range.pos_min, b.range.scale_max], (3 * n + j) * 4);
        data.set(b.range.pos_max, (4 * n + j) * 4);
    });
    return { data, rows };
}

// The texture format of a palette's payload, taken as is: RGBA32F, RGBA16F, or RGBA16UI
// (read through usampler2D).
export function paletteTextureFormat(gl, header) {
    if (header.precision === 0) return { internalFormat: gl.RGBA32F, format: gl.RGBA, type: gl.FLOAT, name: 'RGBA32F' };
    if (header.precision === 1) return { internalFormat: gl.RGBA16F, format: gl.RGBA, type: gl.HALF_FLOAT, name: 'RGBA16F' };
    return { internalFormat: gl.RGBA16UI, format: gl.RGBA_INTEGER, type: gl.UNSIGNED_SHORT, name: 'RGBA16UI' };
}

function texture(gl, internalFormat, width, height, format, type, data) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texImage2D(gl.TEXTURE_2D, 0, internalFormat, width, height, 0, format, type, data);
    return t;
}

// Uploads the palette (and, for qpos or a half palette, its bind positions and position offsets
// as two RGBA32F rows; five for local rows: bonePositionTexels). Returns the textures and the bytes they take on the GPU.
export function uploadPalette(gl, pal) {
    const h = pal.header, f = paletteTextureFormat(gl, h);
    const max = gl.getParameter(gl.MAX_TEXTURE_SIZE);
    if (h.width > max || h.height > max)
        throw new Error(`palette ${h.width}x${h.height} exceeds this GPU's ${max}-texel limit; bake with --max-texture-size ${max}`);
    const palette = texture(gl, f.internalFormat, h.width, h.height, f.format, f.type, pal.texels);
    let bind = null, bytes = h.width * h.height * h.texel_bytes;
    if (h.layout === 2 || h.flags & 4) {
        const { data, rows } = bonePositionTexels(pal);
        bind = texture(gl, gl.RGBA32F, h.bone_count, rows, gl.RGBA, gl.FLOAT, data);
        bytes += data.byteLength;
    }
    return { palette, bind, bytes, format: f.name };
}

// Per instance, 16 floats: place (x, y, z, yaw), inst (the roster's four numbers), from (the
// previous state's four, for a cross-fade), fade (start time, duration, scale, unused).
export const INSTANCE_FLOATS = 16;

// The runtime's vertex main around a skinning that sets p and n (object space).
const mainSource = (skin) => `
in vec3 a_position; in vec3 a_normal; in ivec4 a_joints; in vec4 a_weights;
in vec4 a_place; in vec4 a_inst; in vec4 a_from; in vec4 a_fade;
uniform float u_time; uniform mat4 u_view_projection;
out vec3 v_world; out vec3 v_normal;
void main() {
    vec3 p, n;
${skin}
    float c = cos(a_place.w), s = sin(a_place.w);
    mat3 yaw = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
    v_world = a_place.xyz + a_fade.z * (yaw * p);
    v_normal = yaw * n;
    gl_Position = u_view_projection * vec4(v_world, 1.0);
}
`;

// One pass over the bones for both the position and the normal (each texel read once).
const MAIN = mainSource(`
    float fade = a_fade.y > 0.0 ? clamp((u_time - a_fade.x) / a_fade.y, 0.0, 1.0) : 1.0;
    if (fade < 1.0) cb_skin_position_normal_crossfade(a_position, a_normal, a_joints, a_weights, a_from, a_inst, fade, u_time, p, n);
    else cb_skin_position_normal(a_position, a_normal, a_joints, a_weights, a_inst, u_time, p, n);`);

const FRAGMENT = `#version 300 es
precision mediump float;
in vec3 v_world; in vec3 v_normal;
uniform vec3 u_color;
out vec4 o_color;
void main() {
    vec3 n = normalize(v_normal);
    float light = 0.35 + 0.65 * max(dot(n, normalize(vec3(0.4, 0.8, 0.3))), 0.0);
    o_color = vec4(u_color * light, 1.0);
}
`;

// The runtime's vertex shader for a palette: the shipped library with its defines, then main.
export function vertexShaderSource(glsl, header) {
    return `#version 300 es\n${paletteDefines(header).map((d) => `#define ${d}\n`).join('')}${glsl}\n${MAIN}`;
}

export function compileProgram(gl, vertexSource, fragmentSource, varyings = null) {
    const shader = (type, source) => {
        const s = gl.createShader(type);
        gl.shaderSource(s, source);
        gl.compileShader(s);
        if (!gl.getShaderParameter(s, gl.COMPILE_STATUS))
            throw new Error(`${type === gl.VERTEX_SHADER ? 'vertex' : 'fragment'} shader does not compile: ${gl.getShaderInfoLog(s)}`);
        return s;
    };
    const program = gl.createProgram();
    gl.attachShader(program, shader(gl.VERTEX_SHADER, vertexSource));
    gl.attachShader(program, shader(gl.FRAGMENT_SHADER, fragmentSource));
    if (varyings) gl.transformFeedbackVaryings(program, varyings, gl.INTERLEAVED_ATTRIBS);
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`does not link: ${gl.getProgramInfoLog(program)}`);
    return program;
}

function buffer(gl, target, data) {
    const b = gl.createBuffer();
    gl.bindBuffer(target, b);
    gl.bufferData(target, data, gl.STATIC_DRAW);
    return b;
}

export class Crowd {
    // options: pal (readPal), glsl (the library's text), mesh, capacity (instances), color,
    // captureWorld (link v_world for transform feedback: tests read skinned positions back),
    // bonePass: 'auto' (the default: the bone pass from bonePassVertices skinned vertices a frame,
    // AUTO_BONE_PASS_VERTICES (local rows: AUTO_BONE_PASS_VERTICES_LOCAL) unless given; per-vertex blending
    // below it or where WebGL2 cannot render to float textures), true (always; or { rows }), false (never); crowdbake_bones.mjs.
    // lod: the bone pass's animation LOD ('auto', the default: fewer influences under the sizes where
    // the model's worst vertex moves at most a pixel: from animationLod, a roster type's animation_lod, when
    // given, else crowdbake_bones.mjs's lodThresholds; or { two, one } pixels tall, or false).
    // crowd.lodChoice() says which thresholds and why.
    // lodTiers: true (the default) draws the LOD's tiers apart - the instances sorted by tier on the CPU each frame,
    // one draw a tier, its program compiled for its influences, the same pixels without a size test and influence loop
    // a vertex; false: one draw, each vertex finding its tier.
    // crowd.choice(n) says which a herd of n gets, and why.
    constructor(gl, options) {
        const { pal, glsl, mesh, capacity = 1024, color = [0.8, 0.7, 0.55], captureWorld = false, bonePass = 'auto' } = options;
        this.gl = gl;
        this.pal = pal;
        this.localRows = hasLocalRows(pal.header); // CB_LOCAL_ROWS: each bone composed down its chain, both paths
        this.color = color;
        this.capacity = capacity;
        this.count = 0;
        this.vertexCount = mesh.positions.length / 3;
        const auto = autoBonePassVertices(pal.header, options.bonePassVertices);
        this.bonePassVertices = bonePass === 'auto' ? auto.vertices : bonePass ? 0 : Infinity;
        this.bonePassWhy = bonePass === 'auto' ? auto.why : ''; // the threshold's reason where it is not the usual one
        this.lodOption = options.lod === undefined ? 'auto' : options.lod;
        this.animationLod = options.animationLod; // lod 'auto': the bake's measure (a roster type's animation_lod)
        this.lodMesh = mesh; // else lod 'auto' measures its error on first use
        this.size = Math.max(1e-6, ...pal.clips.flatMap((c) => [0, 1, 2].map((k) => c.bounds_max[k] - c.bounds_min[k])));
        this.textures = this.upload(options);
        const varyings = captureWorld ? ['v_world'] : null;
        this.program = this.makeProgram(glsl, pal.header, FRAGMENT, varyings);
        this.bones = null;
        this.bonesUnavailable = null;
        if (this.bonePassVertices !== Infinity) {
            const fail = (e) => {
                if (bonePass !== 'auto') throw e;
                this.bonesUnavailable = e.message; // 'auto' draws every herd per vertex, and says why
            };
            try {
                this.bonesProgram = compileProgram(gl, boneShaderSource(glsl, pal.header, MAIN_BONES, ['CB_BONE_TEXTURE']),
                                                   FRAGMENT, varyings);
            } catch (e) { fail(e); }
        }
        gl.bindVertexArray(null); // the buffers below join no other vertex array
        const sorted = sortInfluences(mesh.joints, mesh.weights); // the LOD keeps the first ones
        this.buffers = {
            a_position: [3, buffer(gl, gl.ARRAY_BUFFER, mesh.positions)],
            a_normal: mesh.normals ? [3, buffer(gl, gl.ARRAY_BUFFER, mesh.normals)] : null,
            a_joints: [4, buffer(gl, gl.ARRAY_BUFFER, sorted.joints), true], // ivec4: WebGL wants a signed type
            a_weights: [4, buffer(gl, gl.ARRAY_BUFFER, sorted.weights)],
        };
        this.instances = new Float32Array(capacity * INSTANCE_FLOATS);
        this.instanceBuffer = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, this.instanceBuffer);
        gl.bufferData(gl.ARRAY_BUFFER, this.instances.byteLength, gl.DYNAMIC_DRAW);
        this.indexCount = 0;
        if (mesh.indices) {
            const indices = sortTrianglesByInfluences(mesh.indices instanceof Uint32Array || mesh.indices instanceof Uint16Array
                ? mesh.indices : new Uint32Array(mesh.indices), sorted.weights);
            this.indexBuffer = buffer(gl, gl.ELEMENT_ARRAY_BUFFER, indices);
            this.indexType = indices instanceof Uint16Array ? gl.UNSIGNED_SHORT : gl.UNSIGNED_INT;
            this.indexCount = indices.length;
        }
        this.vao = this.makeVertexArray(this.program);
        if (this.bonesProgram) {
            this.bonesVao = this.makeVertexArray(this.bonesProgram);
            try {
                if (options.lodTiers ?? true)
                    this.tiers = new LodTiers(gl, { glsl, header: pal.header, fragment: FRAGMENT, capacity,
                                                    makeVertexArray: (p) => this.makeVertexArray(p) });
            } catch (e) {
                if (bonePass !== 'auto') throw e; // 'auto' draws the LOD in one draw, as lodTiers: false
            }
            // Forced, the pass is made now for the whole capacity (its errors thrown); 'auto' makes it when
            // a herd first takes it, for that herd (grown by powers of two): memory follows the herd.
            this.makeBonePass = (n) => new BonePass(gl, { glsl, header: pal.header, capacity: n, instanceBuffer: this.instanceBuffer,
                                                          instanceFloats: INSTANCE_FLOATS, ...(typeof bonePass === 'object' ? bonePass : {}) });
            if (bonePass !== 'auto') this.bones = this.makeBonePass(capacity);
            else if (!gl.getExtension('EXT_color_buffer_float'))
                this.bonesUnavailable = 'this WebGL2 cannot render to float textures (no EXT_color_buffer_float)';
        }
        this.meshBytes = mesh.positions.byteLength + (mesh.normals?.byteLength ?? 0) + mesh.joints.length * 4 +
                         mesh.weights.byteLength + (mesh.indices?.byteLength ?? 0);
        this.dirty = true;
    }

    // The vertex array of one of the crowd's programs: the mesh's buffers and the instance rows.
    makeVertexArray(program) {
        const gl = this.gl, vao = gl.createVertexArray();
        gl.bindVertexArray(vao);
        for (const [name, b] of Object.entries(this.buffers)) {
            const loc = gl.getAttribLocation(program, name);
            if (loc < 0) continue;
            if (!b) { gl.vertexAttrib3f(loc, 0, 1, 0); continue; } // no normals: straight up
            const [size, data, integer] = b;
            gl.bindBuffer(gl.ARRAY_BUFFER, data);
            gl.enableVertexAttribArray(loc);
            if (integer) gl.vertexAttribIPointer(loc, size, gl.INT, 0, 0);
            else gl.vertexAttribPointer(loc, size, gl.FLOAT, false, 0, 0);
        }
        gl.bindBuffer(gl.ARRAY_BUFFER, this.instanceBuffer);
        ['a_place', 'a_inst', 'a_from', 'a_fade'].forEach((name, k) => {
            const loc = gl.getAttribLocation(program, name);
            if (loc < 0) return;
            gl.enableVertexAttribArray(loc);
            gl.vertexAttribPointer(loc, 4, gl.FLOAT, false, INSTANCE_FLOATS * 4, k * 16);
            gl.vertexAttribDivisor(loc, 1);
        });
        if (this.indexBuffer) gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indexBuffer);
        gl.bindVertexArray(null);
        return vao;
    }

    // How a herd of n instances is drawn, and why: { method: 'bones' | 'palette', reason }.
    choice(n = this.count) {
        const vertices = n * this.vertexCount;
        if (this.bonesProgram && !this.bonesUnavailable && vertices >= this.bonePassVertices)
            return { method: 'bones', reason: this.bonePassVertices ? `${vertices} skinned vertices a frame >= ${this.bonePassVertices}: ` +
                `each bone blended once per instance (bonePass: false draws per vertex)${this.bonePassWhy}` : 'bonePass: true' };
        if (this.bonesUnavailable) return { method: 'palette', reason: `no bone pass here: ${this.bonesUnavailable}` };
        if (this.bonePassVertices === Infinity) return { method: 'palette', reason: 'bonePass: false' };
        return { method: 'palette', reason: `${vertices} skinned vertices a frame < ${this.bonePassVertices}: the bone pass ` +
            `would not pay for its extra pass (bonePass: true forces it)${this.bonePassWhy}` };
    }

    // The bone pass, large enough for n instances (made or grown here under bonePass: 'auto').
    bonePassFor(n) {
        if (!this.bones || this.bones.capacity < n) {
            this.bones?.dispose();
            this.bones = this.makeBonePass(Math.min(this.capacity, 2 ** Math.ceil(Math.log2(Math.max(n, 64)))));
        }
        return this.bones;
    }

    // Bytes per instance on the GPU: its row of the instance buffer, and the bone pass's three texels
    // a bone when that pass is used (a VAT's instance costs its row alone; its texture is shared).
    // (and with the LOD's tiers drawn apart, the instance's place in the frame's order, 4 bytes).
    bytesPerInstance(method = this.choice().method) {
        return INSTANCE_FLOATS * 4 + (method === 'bones' ? 48 * this.pal.header.bone_count + (this.tiers ? 4 : 0) : 0);
    }

    // Instance i: position [x, y, z], yaw (radians), scale, inst (the four numbers of
    // instanceData), and for a cross-fade from (the previous four), fadeStart and fadeDuration (s).
    // A scaled instance moving at a world speed v plays instanceData(state, v / scale, i): its
    // feet stay planted (rate = speed / (scale x speed reference)). The previous frame's position
    // for motion vectors is the same skinning at time - dt (runtimes/glsl/README.md).
    setInstance(i, { position = [0, 0, 0], yaw = 0, scale = 1, inst, from = inst, fadeStart = 0, fadeDuration = 0 }) {
        if (i >= this.capacity) throw new Error(`instance ${i} is beyond the crowd's capacity of ${this.capacity}`);
        this.instances.set([...position, yaw, ...inst, ...from, fadeStart, fadeDuration, scale, 0], i * INSTANCE_FLOATS);
        this.count = Math.max(this.count, i + 1);
        this.dirty = true;
    }

    setCount(n) {
        this.count = Math.min(n, this.capacity);
    }

    makeProgram(glsl, header, fragment, varyings) {
        return compileProgram(this.gl, vertexShaderSource(glsl, header), fragment, varyings);
    }

    upload(options) {
        return uploadPalette(this.gl, options.pal);
    }

    bindTextures(u) {
        const gl = this.gl, h = this.pal.header;
        gl.activeTexture(gl.TEXTURE0);
        gl.bindTexture(gl.TEXTURE_2D, this.textures.palette);
        gl.uniform1i(u('cb_palette'), 0);
        if (this.textures.bind) {
            gl.activeTexture(gl.TEXTURE1);
            gl.bindTexture(gl.TEXTURE_2D, this.textures.bind);
            gl.uniform1i(u('cb_bind_positions'), 1);
        }
        gl.uniform1i(u('cb_row_texels'), h.row_texels);
        gl.uniform1i(u('cb_rows_per_block'), h.height);
        gl.uniform3fv(u('cb_bounds_min'), h.bounds_min);
        gl.uniform3fv(u('cb_bounds_max'), h.bounds_max);
        gl.uniform1f(u('cb_linear_range'), h.linear_range);
    }

    // The animation LOD's thresholds ({ two, one } pixels tall, or false), measured on first use under 'auto'.
    get lod() {
        return this.lodChoice().lod;
    }

    // { lod, reason }: the LOD the bone pass's draw uses and why (the thresholds, the error they keep within,
    // the option that overrides them).
    lodChoice() {
        this.lodResolved ??= resolveLod(this.lodOption, this.pal, this.lodMesh, this.size, this.animationLod);
        return this.lodResolved;
    }

    // Binds the program, textures and uniforms for a draw at `time` seconds (lod: false draws every
    // instance with all its influences, as capture does).
    bind(viewProjection, time, lod) {
        const gl = this.gl, bones = this.choice().method === 'bones', p = bones ? this.bonesProgram : this.program;
        this.prepare(bones, time);
        gl.useProgram(p);
        gl.bindVertexArray(bones ? this.bonesVao : this.vao);
        const u = (name) => gl.getUniformLocation(p, name);
        this.bindTextures(u);
        if (bones) {
            this.bones.bindTargets(u);
            gl.uniform3fv(u('u_lod'), lodUniform(lod ?? this.lod, this.size, viewProjection, gl.getParameter(gl.VIEWPORT)[3]));
        }
        gl.uniform1f(u('u_time'), time);
        gl.uniformMatrix4fv(u('u_view_projection'), false, viewProjection);
        gl.uniform3fv(u('u_color'), this.color);
    }

    // The instance rows uploaded when changed, and with the bone pass, the pass run at `time`.
    prepare(bones, time) {
        const gl = this.gl;
        if (this.dirty) {
            gl.bindBuffer(gl.ARRAY_BUFFER, this.instanceBuffer);
            gl.bufferSubData(gl.ARRAY_BUFFER, 0, this.instances, 0, this.count * INSTANCE_FLOATS);
            this.dirty = false;
        }
        if (bones) this.bonePassFor(this.count).run(this.count, time, (u) => this.bindTextures(u));
    }

    // The LOD's tiers drawn apart (lodTiers): the bone pass, the instances sorted by tier, one draw a tier.
    drawTiers(viewProjection, time) {
        const gl = this.gl, u = lodUniform(this.lod, this.size, viewProjection, gl.getParameter(gl.VIEWPORT)[3]);
        this.prepare(true, time);
        this.tiers.sort(this.instances, INSTANCE_FLOATS, 14, this.count, viewProjection, u); // a_fade.z: the scale
        return this.tiers.draw(this.count, (p) => {
            const at = (name) => gl.getUniformLocation(p, name);
            this.bindTextures(at);
            this.bones.bindTargets(at);
            gl.uniformMatrix4fv(at('u_view_projection'), false, viewProjection);
            gl.uniform3fv(at('u_color'), this.color);
        }, (count) => {
            if (this.indexCount) gl.drawElementsInstanced(gl.TRIANGLES, this.indexCount, this.indexType, 0, count);
            else gl.drawArraysInstanced(gl.TRIANGLES, 0, this.vertexCount, count);
        });
    }

    // Every instance with one instanced draw call (the LOD's tiers drawn apart: one a tier it has); the draws made.
    draw(viewProjection, time) {
        const gl = this.gl;
        if (!this.count) return 0;
        if (this.tiers && this.lod && this.choice().method === 'bones') return this.drawTiers(viewProjection, time);
        this.bind(viewProjection, time);
        if (this.indexCount) gl.drawElementsInstanced(gl.TRIANGLES, this.indexCount, this.indexType, 0, this.count);
        else gl.drawArraysInstanced(gl.TRIANGLES, 0, this.vertexCount, this.count);
        gl.bindVertexArray(null);
        return 1;
    }

    // With captureWorld: every instance's skinned vertices (v_world, 3 floats, instance by
    // instance in the mesh's vertex order) at `time`, read back with transform feedback from one
    // instanced draw of points (transform feedback takes no indexed draws).
    capture(time) {
        const gl = this.gl, n = this.count * this.vertexCount * 3;
        const out = gl.createBuffer();
        gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, out);
        gl.bufferData(gl.TRANSFORM_FEEDBACK_BUFFER, n * 4, gl.STATIC_READ);
        this.bind(new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]), time, false);
        gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, out);
        gl.enable(gl.RASTERIZER_DISCARD);
        gl.beginTransformFeedback(gl.POINTS);
        gl.drawArraysInstanced(gl.POINTS, 0, this.vertexCount, this.count);
        gl.endTransformFeedback();
        gl.disable(gl.RASTERIZER_DISCARD);
        gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
        gl.bindVertexArray(null);
        const values = new Float32Array(n);
        gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, out);
        gl.getBufferSubData(gl.TRANSFORM_FEEDBACK_BUFFER, 0, values);
        gl.deleteBuffer(out);
        const error = gl.getError();
        if (error !== gl.NO_ERROR) throw new Error(`WebGL error 0x${error.toString(16)} while capturing the skinned vertices`);
        return values;
    }

    get vramBytes() {
        return this.textures.bytes + this.meshBytes + this.instances.byteLength + (this.bones?.bytes ?? 0) +
               (this.tiers?.order.byteLength ?? 0);
    }
}
