// check_ktx2.mjs - reads crowdbake's KTX2 palettes with readers crowdbake did not write.
//
//   node tests/tools/ktx2/check_ktx2.mjs [--no-browser] FILE.ktx2 FILE.pal ...   (pairs of the same bake)
//
// For each pair: ktx-parse (the KTX2 parser glTF-Transform uses) reads the KTX2; its format,
// size, data format descriptor and the single level must match the .pal (read with
// runtimes/web/crowdbake_pal.mjs) bit for bit, and its key/value data must hold the same clip table.
// Then three.js's KTX2Loader loads every KTX2 in headless Chromium (playwright-core driving the
// system's Chromium, as tests/runtimes/godot does), and the texture it makes must hold the same bytes.
// Prints a line per check; exit 0 when all pass.
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { read } from 'ktx-parse';
import { readPal } from '../../../runtimes/web/crowdbake_pal.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const browser = !args.includes('--no-browser');
const files = args.filter((a) => a !== '--no-browser');
let failed = 0;
const check = (ok, what) => { console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`); if (!ok) failed++; };

const VK = { half: 97, float: 109 };
const pairs = [];
for (let i = 0; i + 1 < files.length; i += 2) {
  const [ktxPath, palPath] = [files[i], files[i + 1]];
  const bytes = new Uint8Array(fs.readFileSync(ktxPath));
  const palBytes = fs.readFileSync(palPath);
  const pal = readPal(palBytes.buffer.slice(palBytes.byteOffset, palBytes.byteOffset + palBytes.byteLength),
                      { name: palPath, verifyChecksum: true });
  const texels = new Uint8Array(pal.texels.buffer, pal.texels.byteOffset, pal.texels.byteLength);
  const name = path.basename(ktxPath);
  let c;
  try { c = read(bytes); } catch (e) { check(false, `${name}: ktx-parse refuses it: ${e.message}`); continue; }
  const h = pal.header;
  check(c.vkFormat === VK[h.precision_name], `${name}: vkFormat ${c.vkFormat} for ${h.precision_name} texels`);
  check(c.pixelWidth === h.width && c.pixelHeight === h.height && c.levels.length === 1 && c.faceCount === 1,
        `${name}: ${c.pixelWidth}x${c.pixelHeight}, ${c.levels.length} level, ${c.faceCount} face (pal ${h.width}x${h.height})`);
  const dfd = c.dataFormatDescriptor[0];
  // Zstandard supercompression (scheme 2, as toktx --zcmp writes it): bytesPlane0 is 0, and the
  // level is one zstd frame, decompressed here by the zstd command (not crowdbake's code).
  const zstd = c.supercompressionScheme === 2;
  const plane = zstd ? 0 : texels.byteLength / (h.width * h.height);
  check(dfd.samples.length === 4 && dfd.bytesPlane[0] === plane && dfd.samples.every((s) => (s.channelType & 0xc0) === 0xc0),
        `${name}: data format descriptor: 4 signed float samples, ${dfd.bytesPlane[0]} bytes a texel` +
        (zstd ? ' (0: zstd supercompressed)' : ''));
  let level = c.levels[0].levelData;
  if (zstd) {
    check(c.levels[0].uncompressedByteLength === texels.byteLength,
          `${name}: zstd level: ${level.byteLength} bytes stored, ${c.levels[0].uncompressedByteLength} uncompressed`);
    const z = spawnSync('zstd', ['-d', '-c', '-q'], { input: Buffer.from(level), maxBuffer: 1 << 30 });
    check(z.status === 0, `${name}: zstd -d reads its level${z.status === 0 ? '' : `: ${z.stderr}`}`);
    level = new Uint8Array(z.stdout || []);
  } else {
    check(c.supercompressionScheme === 0, `${name}: supercompression scheme ${c.supercompressionScheme} (0 or zstd's 2)`);
  }
  const same = level.byteLength === texels.byteLength && Buffer.compare(Buffer.from(level), Buffer.from(texels)) === 0;
  let firstDiff = -1;
  for (let k = 0; !same && k < Math.min(level.byteLength, texels.byteLength); ++k) if (level[k] !== texels[k]) { firstDiff = k; break; }
  check(same, `${name}: ktx-parse level 0 is bit-identical to the .pal texels (${texels.byteLength} bytes` +
        `${same ? '' : `; first difference at byte ${firstDiff}, lengths ${level.byteLength}/${texels.byteLength}`})`);
  const kv = c.keyValue;
  check(typeof kv.KTXwriter === 'string' && kv.KTXwriter.startsWith('crowdbake'), `${name}: KTXwriter '${kv.KTXwriter}'`);
  const text = (v) => new TextDecoder().decode(v).replace(/\0$/, '');
  let clips = [], meta = {};
  try { clips = JSON.parse(text(kv['crowdbake.clips'])); meta = JSON.parse(text(kv['crowdbake.palette'])); } catch (e) {
    check(false, `${name}: crowdbake key/value data is not JSON: ${e.message}`);
  }
  const clipsMatch = clips.length === pal.clips.length && clips.every((cl, k) => cl.name === pal.clips[k].name &&
    cl.first_row === pal.clips[k].first_row && cl.frames === pal.clips[k].frames && cl.loops === pal.clips[k].loops);
  check(clipsMatch, `${name}: crowdbake.clips holds the .pal's ${pal.clips.length} clips (names, rows, frames, loops)`);
  check(meta.layout === h.layout_name && meta.bones === h.bone_count && meta.rows_per_block === h.height,
        `${name}: crowdbake.palette: ${meta.layout}, ${meta.bones} bones, ${meta.rows_per_block} rows per block`);
  pairs.push({ name, bytes, texels, width: h.width, height: h.height, precision: h.precision_name });
}

if (browser && pairs.length) await loadInBrowser(pairs);
console.log(`ktx2: ${failed ? failed + ' checks failed' : 'all checks passed'}`);
process.exit(failed || !pairs.length ? 1 : 0);

// three.js's KTX2Loader in Chromium: every KTX2 becomes a texture whose data equals the .pal texels.
async function loadInBrowser(pairs) {
  const { chromium } = await import('playwright-core');
  const threeDir = path.join(here, 'node_modules', 'three');
  const page = `<!DOCTYPE html><canvas id="c" width="4" height="4"></canvas>
<script type="importmap">{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}</script>`;
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://localhost').pathname;
    if (url === '/') return res.writeHead(200, { 'Content-Type': 'text/html' }).end(page);
    const m = url.match(/^\/(ktx|pal)\/(\d+)$/);
    if (m) return res.writeHead(200).end(Buffer.from(m[1] === 'ktx' ? pairs[+m[2]].bytes : pairs[+m[2]].texels));
    const file = path.join(threeDir, path.normalize(url.replace(/^\/three\//, '/')));
    if (!url.startsWith('/three/') || !file.startsWith(threeDir) || !fs.existsSync(file)) return res.writeHead(404).end();
    res.writeHead(200, { 'Content-Type': 'text/javascript' }).end(fs.readFileSync(file));
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  const b = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
           '--disable-component-update', '--no-first-run'],
  });
  try {
    const tab = await b.newPage();
    const errors = [];
    tab.on('pageerror', (e) => errors.push(e.message));
    await tab.goto(`http://127.0.0.1:${server.address().port}/`);
    const results = await tab.evaluate(async (count) => {
      const THREE = await import('three');
      const { KTX2Loader } = await import('three/addons/loaders/KTX2Loader.js');
      const renderer = new THREE.WebGLRenderer({ canvas: document.getElementById('c') });
      const loader = new KTX2Loader().detectSupport(renderer);
      const out = [];
      for (let i = 0; i < count; ++i) {
        const ktx = await (await fetch(`/ktx/${i}`)).arrayBuffer();
        const want = new Uint8Array(await (await fetch(`/pal/${i}`)).arrayBuffer());
        try {
          const tex = await new Promise((resolve, reject) => loader.parse(ktx, resolve, reject));
          const data = tex.mipmaps[0].data;
          const got = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
          let diff = got.length === want.length ? -1 : 0;
          for (let k = 0; diff < 0 && k < got.length; ++k) if (got[k] !== want[k]) diff = k;
          out.push({ ok: true, width: tex.image.width, height: tex.image.height, type: tex.type, format: tex.format,
                     float: tex.type === THREE.FloatType, half: tex.type === THREE.HalfFloatType,
                     rgba: tex.format === THREE.RGBAFormat, diff });
        } catch (e) {
          out.push({ ok: false, error: String(e && e.message || e) });
        }
      }
      renderer.dispose();
      return out;
    }, pairs.length);
    results.forEach((r, i) => {
      const p = pairs[i];
      if (!r.ok) return check(false, `${p.name}: three.js KTX2Loader refuses it: ${r.error}`);
      check(r.rgba && (p.precision === 'float' ? r.float : r.half) && r.width === p.width && r.height === p.height,
            `${p.name}: three.js KTX2Loader makes a ${r.width}x${r.height} RGBA ${r.float ? 'FloatType' : r.half ? 'HalfFloatType' : r.type} texture`);
      check(r.diff < 0, `${p.name}: the three.js texture's data is bit-identical to the .pal texels${r.diff < 0 ? '' : ` (first difference at byte ${r.diff})`}`);
    });
    for (const e of errors) check(false, `page error: ${e}`);
  } finally {
    await b.close();
    server.close();
  }
}
