// crowdbake_vat.mjs - the vertex-animation-texture peer of crowdbake_crowd.mjs, to compare both
// methods side by side: reads the VAT that `crowdbake vat MODEL -o OUT.exr --exr-compression none`
// writes and draws a herd from it with the same per-instance data and one instanced draw call.
// The frame choice (wrap, clamp, blend) is the palette library's own cb_frame: a VAT frame is
// a palette row.
import { Crowd, compileProgram } from './crowdbake_crowd.mjs';
import { instanceFirstRow } from './crowdbake_pose.mjs';

const HALF = 1, FLOAT = 2;

// The uncompressed scanline EXR that `crowdbake vat` writes (layers normal.* and position.*,
// half floats). Returns { width, height, frames, vertices, frameWidth, rowsPerFrame, blocks,
// positions, normals } with positions and normals as RGBA half-float Uint16Arrays.
export function readVat(data, name = 'vat.exr') {
    const bytes = data instanceof Uint8Array ? data : new Uint8Array(data);
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const fail = (m) => { throw new Error(`${name}: ${m}`); };
    if (bytes.length < 8 || view.getUint32(0, true) !== 20000630) fail('not an OpenEXR file');
    if (view.getUint32(4, true) & 0x1a00) fail('tiled, deep or multi-part EXR; re-bake with crowdbake vat');
    let at = 8;
    const cstring = () => {
        const end = bytes.indexOf(0, at);
        if (end < 0) fail(`truncated header at byte ${at}`);
        const s = new TextDecoder().decode(bytes.subarray(at, end));
        at = end + 1;
        return s;
    };
    const attrs = {};
    for (;;) {
        const attr = cstring();
        if (!attr) break;
        const type = cstring();
        if (at + 4 > bytes.length) fail(`truncated header at byte ${at}`);
        const size = view.getInt32(at, true);
        at += 4;
        if (size < 0 || at + size > bytes.length) fail(`attribute ${attr} (byte ${at}) runs past the file`);
        const v = new DataView(bytes.buffer, bytes.byteOffset + at, size);
        if (type === 'int') attrs[attr] = v.getInt32(0, true);
        else if (type === 'compression') attrs[attr] = v.getUint8(0);
        else if (type === 'box2i') attrs[attr] = [0, 4, 8, 12].map((o) => v.getInt32(o, true));
        else if (type === 'chlist') {
            const list = [];
            let o = 0;
            while (o < size && bytes[at + o] !== 0) {
                const end = bytes.indexOf(0, at + o);
                list.push({ name: new TextDecoder().decode(bytes.subarray(at + o, end)), type: v.getInt32(end + 1 - at, true) });
                o = end + 1 - at + 16;
            }
            attrs[attr] = list;
        }
        at += size;
    }
    if (attrs.compression !== 0) fail('compressed EXR; bake the VAT with --exr-compression none for the browser');
    const [x0, y0, x1, y1] = attrs.dataWindow ?? fail('no dataWindow');
    const width = x1 - x0 + 1, height = y1 - y0 + 1, channels = attrs.channels ?? fail('no channels');
    const frames = attrs['crowdbake.frames'], frameWidth = attrs['crowdbake.frameWidth'];
    if (!frames || !frameWidth) fail('not a crowdbake VAT (no crowdbake.frames attribute)');
    const positions = new Uint16Array(width * height * 4), normals = new Uint16Array(width * height * 4);
    const lineBytes = channels.reduce((n, c) => n + width * (c.type === HALF ? 2 : 4), 0);
    for (let y = 0; y < height; ++y) {
        const offset = Number(view.getBigUint64(at + y * 8, true));
        if (offset + 8 + lineBytes > bytes.length || view.getInt32(offset + 4, true) !== lineBytes)
            fail(`scanline ${y} (offset table byte ${at + y * 8}) is truncated or not uncompressed`);
        let o = offset + 8;
        for (const c of channels) {
            const [layer, comp] = c.name.split('.');
            const target = layer === 'position' ? positions : layer === 'normal' ? normals : null;
            const k = 'RGBA'.indexOf(comp);
            if (c.type !== HALF && c.type !== FLOAT) fail(`channel ${c.name} is not half or float`);
            if (target && k >= 0 && c.type === HALF)
                for (let x = 0; x < width; ++x) target[(y * width + x) * 4 + k] = view.getUint16(o + x * 2, true);
            o += width * (c.type === HALF ? 2 : 4);
        }
    }
    return { width, height, frames, vertices: attrs['crowdbake.vertices'], frameWidth,
             rowsPerFrame: attrs['crowdbake.rowsPerFrame'], blocks: attrs['crowdbake.blocks'], positions, normals };
}

const VAT_MAIN = `
uniform highp sampler2D u_vat_positions; uniform highp sampler2D u_vat_normals;
uniform int u_frame_width, u_rows_per_frame, u_rows_per_block;
in vec4 a_place; in vec4 a_inst; in vec4 a_from; in vec4 a_fade;
uniform float u_time; uniform mat4 u_view_projection;
out vec3 v_world; out vec3 v_normal;
vec3 vat_fetch(sampler2D t, int frame) {
    int row = frame * u_rows_per_frame + gl_VertexID / u_frame_width;
    int block = row / u_rows_per_block;
    return texelFetch(t, ivec2(block * u_frame_width + gl_VertexID % u_frame_width, row - block * u_rows_per_block), 0).xyz;
}
void vat_skin(vec4 inst, out vec3 p, out vec3 n) {
    int row0, row1; float fr;
    cb_frame(inst, u_time, row0, row1, fr);
    p = mix(vat_fetch(u_vat_positions, row0), vat_fetch(u_vat_positions, row1), fr);
    n = mix(vat_fetch(u_vat_normals, row0), vat_fetch(u_vat_normals, row1), fr);
}
void main() {
    float fade = a_fade.y > 0.0 ? clamp((u_time - a_fade.x) / a_fade.y, 0.0, 1.0) : 1.0;
    vec3 p, n;
    vat_skin(a_inst, p, n);
    if (fade < 1.0) {
        vec3 p0, n0;
        vat_skin(a_from, p0, n0);
        p = mix(p0, p, fade), n = mix(n0, n, fade);
    }
    float c = cos(a_place.w), s = sin(a_place.w);
    mat3 yaw = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
    v_world = a_place.xyz + a_fade.z * (yaw * p);
    v_normal = yaw * normalize(n);
    gl_Position = u_view_projection * vec4(v_world, 1.0);
}
`;

// The VAT that `crowdbake vat --like PALETTE` bakes, laid out against the palette: its frames clip after clip, a
// timed clip (.pal version 7) at its cells' rate, one frame a cell (a one-shot's one more: the end of its last cell),
// for a VAT has no map; every other clip one frame a row. { frames, instanceOf }: the VAT's frame count and a palette
// instance's four numbers as the VAT plays the same clip time (the identity without timed clips, whose VAT frames are
// the palette's rows one for one).
export function vatLayout(pal) {
    if (!pal.clips.some((c) => c.timed)) return { frames: pal.header.rows, instanceOf: (inst) => inst };
    const byFirst = new Map();
    let frames = 0;
    for (const c of pal.clips) {
        const n = c.timed ? c.cells + (c.loops ? 0 : 1) : c.frames;
        byFirst.set(instanceFirstRow(c), [c.step ? -frames - 1 : frames, n]);
        frames += n;
    }
    const instanceOf = (inst) => {
        const clip = byFirst.get(inst[0]);
        return clip ? [clip[0], inst[1] < 0 ? -clip[1] : clip[1], Math.abs(inst[2]), inst[3]] : inst;
    };
    return { frames, instanceOf };
}

// A herd drawn from a VAT: the Crowd API (setInstance, draw, vramBytes) with the skinning
// replaced by two texel fetches per vertex. `pal` is the palette of the same frames (for its
// header only) and `vat` readVat's result: new VatCrowd(gl, { pal, vat, glsl, mesh, capacity }).
export class VatCrowd extends Crowd {
    constructor(gl, options) {
        super(gl, { ...options, bonePass: false }); // a VAT has no bones to pass
    }

    makeProgram(glsl, header, fragment, varyings) {
        const defines = '#define CB_LAYOUT_MAT4\n#define CB_PRECISION_FLOAT\n'; // only cb_frame is used
        return compileProgram(this.gl, `#version 300 es\n${defines}${glsl}\n${VAT_MAIN}`, fragment, varyings);
    }

    upload(options) {
        const gl = this.gl, vat = options.vat;
        const tex = (data) => {
            const t = gl.createTexture();
            gl.bindTexture(gl.TEXTURE_2D, t);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
            gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA16F, vat.width, vat.height, 0, gl.RGBA, gl.HALF_FLOAT, data);
            return t;
        };
        if (vat.vertices !== this.vertexCount)
            throw new Error(`the VAT has ${vat.vertices} vertices, the mesh ${this.vertexCount}`);
        this.vat = vat;
        return { positions: tex(vat.positions), normals: tex(vat.normals), bytes: vat.width * vat.height * 16, format: 'RGBA16F' };
    }

    bindTextures(u) {
        const gl = this.gl;
        gl.activeTexture(gl.TEXTURE0);
        gl.bindTexture(gl.TEXTURE_2D, this.textures.positions);
        gl.uniform1i(u('u_vat_positions'), 0);
        gl.activeTexture(gl.TEXTURE1);
        gl.bindTexture(gl.TEXTURE_2D, this.textures.normals);
        gl.uniform1i(u('u_vat_normals'), 1);
        gl.uniform1i(u('u_frame_width'), this.vat.frameWidth);
        gl.uniform1i(u('u_rows_per_frame'), this.vat.rowsPerFrame);
        gl.uniform1i(u('u_rows_per_block'), this.vat.height);
    }
}
