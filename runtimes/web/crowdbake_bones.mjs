// crowdbake_bones.mjs - the bone pass of crowdbake_crowd.mjs (new Crowd(gl, { ..., bonePass: true })).
// Per-vertex skinning decodes and blends every influence's bone from the palette's two rows at
// every vertex. The bone pass does that once per instance and bone: before the draw, one fragment
// per (instance, bone) writes the bone's blended transform (cross-fade included) to three RGBA32F
// render targets (cb_bone_pass of the shipped GLSL), and the draw's vertex shader reads it back with
// three plain texel fetches an influence (cb_skin_bone_pass, #define CB_BONE_TEXTURE). It needs
// EXT_color_buffer_float (render to float textures), which WebGL2 on desktop GPUs and SwiftShader have.
import { compileProgram, paletteDefines } from './crowdbake_crowd.mjs';

const PASS_VERTEX = `
in vec4 a_inst; in vec4 a_from; in vec4 a_fade;
uniform float u_time; uniform int u_rows; uniform vec2 u_size;
flat out vec4 v_inst; flat out vec4 v_from; flat out float v_fade; flat out int v_x0;
void main() {  // instance i: a quad over its row of bones in its column block
    int block = gl_InstanceID / u_rows, row = gl_InstanceID - block * u_rows, bones = cb_row_texels / CB_TEXELS_PER_BONE;
    v_x0 = block * bones;
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
    vec2 px = vec2(float(v_x0) + corner.x * float(bones), float(row) + corner.y);
    gl_Position = vec4(px / u_size * 2.0 - 1.0, 0.0, 1.0);
    v_inst = a_inst, v_from = a_from;
    v_fade = a_fade.y > 0.0 ? clamp((u_time - a_fade.x) / a_fade.y, 0.0, 1.0) : 1.0;
}
`;

const PASS_FRAGMENT = `
flat in vec4 v_inst; flat in vec4 v_from; flat in float v_fade; flat in int v_x0;
uniform float u_time;
layout(location = 0) out vec4 o_c0; layout(location = 1) out vec4 o_c1; layout(location = 2) out vec4 o_c2;
void main() { cb_bone_pass(int(gl_FragCoord.x) - v_x0, v_from, v_inst, v_fade, u_time, o_c0, o_c1, o_c2); }
`;

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
        [['a_inst', 1], ['a_from', 2], ['a_fade', 3]].forEach(([name, k]) => {
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
        const blend = gl.isEnabled(gl.BLEND), depth = gl.isEnabled(gl.DEPTH_TEST);
        gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, this.framebuffer);
        gl.viewport(0, 0, this.width, this.rows);
        gl.disable(gl.BLEND);
        gl.disable(gl.DEPTH_TEST);
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
