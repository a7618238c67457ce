// skin_check.mjs - runs runtimes/web/crowdbake_crowd.mjs in headless Chromium (WebGL2) on the runtime
// conformance cases (tests/runtimes/conformance.h writes them; tests/runtimes/test_web.c compares the
// results with their expected positions), and reads the skinned positions back with transform feedback.
//
//   node tests/runtimes/browser/skin_check.mjs JOB_DIR
//
// JOB_DIR/cases.json: { cases: [{ name, pal, mesh: { vertex_count, positions, joints, weights },
// groups: [{ time, instances: [[16 floats], ...] }], transpose, glsl_break: { marker, line } | null,
// bone_pass (Crowd's bonePass option), out }] } (file names relative to JOB_DIR). For each case, the palette is read with readPal, the
// runtime draws every instance of each group at its time as points (one instanced draw), and
// v_world of every instance and vertex lands in JOB_DIR/OUT as float32, group after group. The C
// test compares them with its CPU skinning. A case can break the runtime on purpose: transpose
// (each mat4 bone stored transposed, the reference runtime's shipped bug) or glsl_break (the
// line of the shipped shader holding `marker` replaced by `line`). A case of local rows (local: true) is run twice
// more: through the bone pass (OUT.bones) and with the shader's compose step skipped (OUT.nocompose, broken); a case
// of timed rows (timed: true, .pal version 7) also twice more: through the bone pass (OUT.bones) and with the
// shader's map read skipped, the cell taken as a row (OUT.nomap, broken).
import fs from 'node:fs';
import path from 'node:path';
import { withPage, REPO, RUNTIMES } from './driver.mjs';

const dir = path.resolve(process.argv[2]);
const jobs = JSON.parse(fs.readFileSync(path.join(dir, 'cases.json'), 'utf8'));

const hostileDir = path.join(REPO, 'tests/fuzz/regressions/pal');
// Each case as given, and a local case also through the bone pass and with its composition skipped.
const bonePass = (c) => ({ ...c, name: `${c.name} (bone pass)`, out: `${c.out}.bones`, bone_pass: true });
const runs = jobs.cases.flatMap((c) => [c,
    ...(c.local || (c.timed && !c.broken) ? [bonePass(c)] : []),
    ...(c.local ? [{ ...c, name: `${c.name} (compose skipped)`, out: `${c.out}.nocompose`,
                     glsl_break: { marker: 'cb:local-compose', line: '        // compose skipped (a broken runtime)' } }] : []),
    ...(c.timed && !c.broken ? [{ ...c, name: `${c.name} (map skipped)`, out: `${c.out}.nomap`,
                                  glsl_break: { marker: 'cb:timed-map', line: '        vec4 m = vec4(cell, cell + 1.0, 0.0, 1.0);' } }] : [])]);

const failures = await withPage({ '/': RUNTIMES, '/job/': dir, '/hostile/': hostileDir }, '/__blank.html', async (page) => {
    for (const c of runs) {
        const result = await page.evaluate(async (c) => {
            const { readPal } = await import('/web/crowdbake_pal.mjs');
            const { Crowd, loadPaletteGLSL } = await import('/web/crowdbake_crowd.mjs');
            const get = async (name) => new Uint8Array(await (await fetch(`/job/${name}`)).arrayBuffer());
            const pal = readPal(await get(c.pal), { name: c.pal, verifyChecksum: true });
            if (c.transpose) { // rows stored where columns belong
                const t = Float32Array.from(pal.texels);
                for (let b = 0; b + 16 <= t.length; b += 16)
                    for (let r = 0; r < 4; ++r) for (let k = 0; k < 4; ++k) t[b + r * 4 + k] = pal.texels[b + k * 4 + r];
                pal.texels = t;
            }
            let glsl = await loadPaletteGLSL();
            if (c.glsl_break) {
                const lines = glsl.split('\n');
                const i = lines.findIndex((l) => l.includes(c.glsl_break.marker));
                if (i < 0) throw new Error(`marker ${c.glsl_break.marker} is not in the shader`);
                lines[i] = c.glsl_break.line;
                glsl = lines.join('\n');
            }
            const f32 = async (name) => new Float32Array((await get(name)).buffer);
            const mesh = { positions: await f32(c.mesh.positions), weights: await f32(c.mesh.weights),
                           joints: new Uint16Array((await get(c.mesh.joints)).buffer) };
            const canvas = document.createElement('canvas');
            const gl = canvas.getContext('webgl2');
            const capacity = Math.max(...c.groups.map((g) => g.instances.length));
            const crowd = new Crowd(gl, { pal, glsl, mesh, capacity, captureWorld: true, bonePass: c.bone_pass ?? false });
            const out = [];
            for (const g of c.groups) {
                crowd.count = 0;
                g.instances.forEach((v, i) => {
                    crowd.instances.set(v, i * 16);
                    crowd.count = i + 1;
                });
                crowd.dirty = true;
                const got = crowd.capture(g.time);
                out.push(...got);
            }
            return { values: out, renderer: gl.getParameter(gl.RENDERER), format: crowd.textures.format, bones: crowd.bones !== null };
        }, c).catch((e) => ({ error: String(e.message ?? e).split('\n')[0] }));
        if (result.error) {
            console.log(`FAIL ${c.name}: ${result.error}`);
            continue;
        }
        fs.writeFileSync(path.join(dir, c.out), Buffer.from(new Float32Array(result.values).buffer));
        console.log(`ran  ${c.name}: ${result.values.length / 3} vertices on ${result.format}${result.bones ? ' with the bone pass' : ''} (${result.renderer})`);
    }
    // The hostile palettes the fuzzers found, read in the page with the decoder a page would use:
    // each must be refused with a one-line Error naming the file, the page left working (a valid file kept there as the
    // fuzzer's seed, timed-held.pal, is opened: ACCEPTED, which test_web.c holds to the C reader's verdict).
    const hostile = fs.readdirSync(hostileDir);
    const verdicts = await page.evaluate(async (files) => {
        const { readPal } = await import('/web/crowdbake_pal.mjs');
        const { decompress } = await import('/web/node_modules/fzstd/esm/index.mjs');
        const out = [];
        for (const f of files) for (const verifyChecksum of [true, false]) { // without it, the decoder meets the damage
            const bytes = new Uint8Array(await (await fetch(`/hostile/${f}`)).arrayBuffer());
            try {
                readPal(bytes, { name: f, verifyChecksum, decompress: (b, n) => decompress(b, new Uint8Array(n)) });
                out.push(`ACCEPTED ${f}`);
            } catch (e) {
                const clean = e.constructor === Error && e.message.startsWith(`${f}: `) && !e.message.includes('\n');
                out.push(`${clean ? 'refused' : 'BAD ERROR'} ${e.message}`);
            }
        }
        return out;
    }, hostile);
    for (const v of verdicts) console.log(v);
    return page.crowdbakeErrors;
});
for (const e of failures) console.log(`FAIL ${e}`);
process.exit(failures.length ? 1 : 0);
