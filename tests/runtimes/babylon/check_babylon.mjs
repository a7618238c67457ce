// check_babylon.mjs - crowdbake's Babylon.js bake (.bvat.json) against Babylon.js's own.
//
//   node tests/runtimes/babylon/check_babylon.mjs MODEL.glb FILE.bvat.json [--bound B] [--controls] [--values-only]
//                                        [--roster ROSTER.json --type NAME]
//
// In headless Chromium (playwright-core driving the system's Chromium, as tests/tools/ktx2 does), real
// Babylon.js (@babylonjs/core and @babylonjs/loaders, pinned in package-lock.json) loads the model,
// and Babylon's own VertexAnimationBaker bakes every clip of the file's clip table at the file's
// row times (start + k / fps, Babylon's glTF frames being seconds x 60). The check compares the two
// value by value (the worst difference must stay within --bound), then draws the same herd of thin
// instances with BakedVertexAnimationManager from each texture and compares their silhouettes
// pixel by pixel. --controls also runs three broken variants of the file, each of which must fail
// the same checks: the joints in reverse order, the matrices mirrored as if the handedness were
// the file's to apply (it is __root__'s), and rows without Babylon's non-joint bones and extra
// matrix. --values-only leaves out the herd (a model too small for its framing). --roster and
// --type: a catalog's file; each state of the type in the manifest must be in the file's
// crowdbake.states with the manifest's clip and from/to/fps, and the file's rows from..to must be
// Babylon's own bake of the glTF clip the manifest names, at the state's fps. Prints a line per
// check; exit 0 when all pass.
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const option = (name, fallback) => { const i = args.indexOf(name); return i < 0 ? fallback : args.splice(i, 2)[1]; };
const bound = Number(option('--bound', '1e-4'));
const rosterPath = option('--roster', null), typeName = option('--type', null);
const controls = args.includes('--controls'), valuesOnly = args.includes('--values-only');
const [modelPath, filePath] = args.filter((a) => !a.startsWith('--'));
let failed = 0;
const check = (ok, what) => { console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`); if (!ok) failed++; };

const file = JSON.parse(fs.readFileSync(filePath, 'utf8'));
const variants = [{ name: path.basename(filePath), json: file }];
if (controls) variants.push(...brokenVariants(file));

const states = rosterPath ? rosterStates(JSON.parse(fs.readFileSync(rosterPath, 'utf8')).types[typeName]) : [];
const results = await inBrowser(fs.readFileSync(modelPath), variants, states);
const [mine, ...broken] = results;
const herd = mine.herd;
if (!valuesOnly)
  check(herd.covered > 2000 && herd.covered < herd.pixels / 2,
        `the herd covers ${herd.covered} of ${herd.pixels} pixels in Babylon's own bake`);
report(mine, variants[0].name);
for (const s of mine.states)
  if (s.corrected) check(true, `state ${s.name}: ${s.clip} is a loop closed over its key span (its closing key's mismatch ` +
                         `spread), which Babylon's animations play as it is: not compared`);
  else check(s.compared > 0 && s.worst <= bound, `state ${s.name}: rows ${s.from}..${s.to} at ${s.fps} fps are Babylon's bake of ` +
        `${s.clip}: worst difference ${s.worst.toExponential(2)} over ${s.compared} values`);
for (const r of broken) {
  const valuesFail = !(r.sizeMatch && r.worst <= bound), pixelsFail = r.silhouetteDiff > Math.max(4, herd.covered * 0.001);
  const ok = valuesFail && (pixelsFail || r.name === 'joints-only'); // Babylon draws joints-only alike: only its size tells
  check(ok, `control ${r.name} fails: ${r.sizeMatch ? `worst difference ${r.worst.toExponential(2)}` : `size ${r.width}x${r.height}`}` +
            `, ${r.silhouetteDiff} silhouette pixels differ${pixelsFail ? '' : ' (drawn alike)'}`);
}
console.log(`babylon: ${failed ? failed + ' checks failed' : 'all checks passed'}`);
process.exit(failed ? 1 : 0);

function report(r, name) {
  check(r.sizeMatch, `${name}: ${r.width}x${r.height} texels, as Babylon's bake of ${r.bones} bones (+1) and ${r.rows} rows`);
  check(r.sizeMatch && r.worst <= bound, `${name}: worst difference from Babylon's VertexAnimationBaker ${r.worst.toExponential(2)} (relative past 1) ` +
        `(bound ${bound}) over ${r.compared} values of ${r.rows} rows, at row ${r.worstRow} value ${r.worstIndex}` +
        `; left out: ${r.wrapRows} rows past a loop's last key (an open loop's wrap to its first key, which Babylon's ` +
        `animations do not make), ${r.cycled} rows at a clip's last key where Babylon's bake went round to the clip's first pose` +
        ` and ${r.corrected} rows of loops closed over their key span (the closing key's mismatch spread, which Babylon's ` +
        `animations play as it is)`);
  if (!valuesOnly) check(r.silhouetteDiff <= Math.max(4, r.herd.covered * 0.001),
        `${name}: thin instances through BakedVertexAnimationManager: ${r.silhouetteDiff} of ${r.herd.covered} silhouette pixels ` +
        `differ from Babylon's own bake`);
}

// The manifest's states (its clip, its rows in the .bvat.json), each checked against the file's own table.
function rosterStates(type) {
  check(type && type.palette_babylon, `the manifest lists ${typeName}'s .bvat.json`);
  const mine = file.crowdbake.states || {};
  return Object.entries(type ? type.states : {}).map(([name, s]) => {
    const f = mine[name], b = s.babylon;
    check(f && b && f.clip === s.clip && f.from === b.from && f.to === b.to && f.fps === b.fps,
          `state ${name}: the file's crowdbake.states and the manifest agree (${s.clip}, rows ${b && b.from}..${b && b.to})`);
    return { name, clip: s.clip, from: b.from, to: b.to, fps: b.fps };
  });
}

// Broken files a careless writer could produce; each must fail.
function brokenVariants(good) {
  const data = new Float32Array(new Uint8Array(Buffer.from(good.vertexData, 'base64')).buffer);
  const slots = good.width / 4, joints = good.crowdbake.joints, rows = good.height;
  const make = (name, width, fill) => {
    const out = new Float32Array((width / 4) * 16 * rows);
    for (let r = 0; r < rows; ++r) fill(data.subarray(r * slots * 16, (r + 1) * slots * 16), out.subarray(r * (width / 4) * 16));
    return { name, json: { ...good, width, vertexData: Buffer.from(out.buffer).toString('base64') } };
  };
  return [
    make('reversed-bones', good.width, (row, out) => {
      out.set(row);
      for (let j = 0; j < joints; ++j) out.set(row.subarray(j * 16, j * 16 + 16), (joints - 1 - j) * 16);
    }),
    make('mirrored-handedness', good.width, (row, out) => { // H M H, H = diag(-1, 1, 1, 1)
      out.set(row);
      for (let s = 0; s < slots; ++s)
        for (let k = 0; k < 16; ++k) if ((Math.floor(k / 4) === 0) !== (k % 4 === 0)) out[s * 16 + k] = -row[s * 16 + k];
    }),
    make('joints-only', joints * 4, (row, out) => out.set(row.subarray(0, joints * 16))),
  ];
}

async function inBrowser(model, variants, states) {
  const { chromium } = await import('playwright-core');
  const modules = path.join(here, 'node_modules');
  const page = `<!DOCTYPE html><canvas id="c" width="320" height="240"></canvas>
<script type="importmap">{"imports": {"@babylonjs/core/": "/m/@babylonjs/core/", "@babylonjs/loaders/": "/m/@babylonjs/loaders/",
"babylonjs-gltf2interface": "/m/babylonjs-gltf2interface/babylon.glTF2Interface.js"}}</script>`;
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://localhost').pathname;
    if (url === '/') return res.writeHead(200, { 'Content-Type': 'text/html' }).end(page);
    if (url === '/model.glb') return res.writeHead(200, { 'Content-Type': 'model/gltf-binary' }).end(model);
    const v = url.match(/^\/bake\/(\d+)$/);
    if (v) return res.writeHead(200, { 'Content-Type': 'application/json' }).end(JSON.stringify(variants[+v[1]].json));
    const f = path.join(modules, path.normalize(url.replace(/^\/m\//, '/')));
    if (!url.startsWith('/m/') || !f.startsWith(modules) || !fs.existsSync(f)) return res.writeHead(404).end();
    res.writeHead(200, { 'Content-Type': 'text/javascript' }).end(fs.readFileSync(f));
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
    if (process.env.BABYLON_DEBUG) tab.on('console', (m) => process.stderr.write(`page: ${m.text()}\n`));
    await tab.goto(`http://127.0.0.1:${server.address().port}/`);
    const out = await tab.evaluate(pageMain, { count: variants.length, names: variants.map((v) => v.name), states });
    for (const e of errors) check(false, `page error: ${e}`);
    return out;
  } finally {
    await b.close();
    server.close();
  }
}

// Runs in the page: Babylon's own bake, the comparison, and the herds.
async function pageMain({ count, names, states }) {
  const B = await import('@babylonjs/core/index.js');
  await import('@babylonjs/loaders/glTF/index.js');
  const engine = new B.Engine(document.getElementById('c'), false, { preserveDrawingBuffer: true, antialias: false });
  const scene = new B.Scene(engine);
  scene.clearColor = new B.Color4(0, 0, 0, 1);
  new B.HemisphericLight('light', new B.Vector3(0, 1, 0), scene);
  const camera = new B.ArcRotateCamera('camera', -Math.PI / 2 + 0.5, 1.15, 22, new B.Vector3(0, 0.6, 0), scene);
  console.log('babylon imported');
  const loaded = await B.ImportMeshAsync('/model.glb', scene);
  console.log('model loaded');
  for (const g of loaded.animationGroups) g.stop();
  const mesh = loaded.meshes.find((m) => m.skeleton);
  const skeleton = mesh.skeleton;
  const table = (await (await fetch('/bake/0')).json()).crowdbake;

  // Babylon's bake: each clip's channels as the bones' own animations (VertexAnimationBaker plays
  // the skeleton's), the bones unlinked from the glTF nodes that would override them. Babylon's
  // glTF frames are seconds x 60; the keys are re-timed so that frame k is the file's row k of the
  // clip (start + k / fps; linear and step keys interpolate the same at any time scale), which
  // bakeVertexDataSync samples at whole frames.
  const boneOf = new Map(skeleton.bones.map((bone) => [bone.getTransformNode(), bone]));
  for (const bone of skeleton.bones) bone.linkTransformNode(null);
  const baker = new B.VertexAnimationBaker(scene, mesh);
  const parts = [], wrap = [], closedOff = new Set();
  // A loop whose last key is its closing key slightly off (its keys' ends differ, no row past its
  // last key): crowdbake spreads the mismatch over the cycle (CB_LOOP_CLOSED_CORRECTED,
  // docs/sampling.md), Babylon plays the keys as they are; test_loop_close measures those rows
  // against the reference matrices instead.
  // (Rotations only: a travelling loop's root translation ends elsewhere by its travel.)
  const closesOff = (group) => !!group && group.targetedAnimations.some((t) => {
    if (t.animation.targetProperty !== 'rotationQuaternion') return false;
    const k = t.animation.getKeys(), a = k[0].value, b = k[k.length - 1].value;
    const va = typeof a === 'number' ? [a] : a.asArray(), vb = typeof b === 'number' ? [b] : b.asArray();
    const off = (sign) => va.some((x, i) => Math.abs(x - sign * vb[i]) > 1e-3 * Math.max(1, Math.abs(x)));
    return off(1) && (va.length !== 4 || off(-1)); // q and -q are one rotation
  });
  for (const clip of table.clips) {
    const group = loaded.animationGroups.find((g) => g.name === clip.name);
    for (const bone of skeleton.bones) bone.animations = [];
    for (const t of group.targetedAnimations) {
      const bone = boneOf.get(t.target);
      if (!bone) continue;
      const a = t.animation.clone();
      a.setKeys(t.animation.getKeys().map((k) => ({ ...k, frame: (k.frame / 60 - clip.start) * clip.fps })));
      bone.animations.push(a);
    }
    // Rows past a clip's last key (an open loop's wrap back to its first key) have no Babylon
    // counterpart: its glTF animations cycle. At a clip's last key Babylon's bake may go round to
    // the first pose (when the last key's frame rounds below the row's): such rows are counted.
    const first = wrap.length;
    for (let r = clip.from; r <= clip.to; ++r) {
      const frame = (clip.start + (r - clip.from) / clip.fps) * 60;
      wrap.push(frame > group.to + 1e-3 ? -1 : frame >= group.to - 1e-3 ? clip.from + 1 : 0);
    }
    if (clip.loops && !wrap.slice(first).includes(-1) && closesOff(group)) wrap.fill(-2, first), closedOff.add(clip.name);
    parts.push(baker.bakeVertexDataSync([{ from: 0, to: clip.to - clip.from }], false));
  }
  // A state's rows: Babylon's bake of the glTF clip the manifest names, re-timed at the state's fps.
  const stateBakes = states.map((s) => {
    const group = loaded.animationGroups.find((g) => g.name === s.clip);
    for (const bone of skeleton.bones) bone.animations = [];
    for (const t of group ? group.targetedAnimations : []) {
      const bone = boneOf.get(t.target);
      if (!bone) continue;
      const a = t.animation.clone();
      a.setKeys(t.animation.getKeys().map((k) => ({ ...k, frame: (k.frame / 60) * s.fps })));
      bone.animations.push(a);
    }
    const last = group ? Math.floor((group.to / 60) * s.fps - 1e-3) : -1; // rows before the clip's last key
    const corrected = closedOff.has(s.clip);
    return { ...s, own: group ? baker.bakeVertexDataSync([{ from: 0, to: s.to - s.from }], false) : null, last, corrected };
  });
  const own = new Float32Array(parts.reduce((n, p) => n + p.length, 0));
  parts.reduce((at, p) => (own.set(p, at), at + p.length), 0);
  const ownTexture = baker.textureFromBakedVertexData(own);
  const bones = skeleton.bones.length, rows = own.length / ((bones + 1) * 16);

  // The herd: one instance per clip, each at its own offset, drawn at one moment.
  const herd = async (texture) => {
    const manager = new B.BakedVertexAnimationManager(scene);
    manager.texture = texture;
    manager.time = 1.37;
    mesh.bakedVertexAnimationManager = manager;
    const n = table.clips.length, cols = Math.ceil(Math.sqrt(n));
    const matrices = new Float32Array(16 * n), settings = new Float32Array(4 * n);
    table.clips.forEach((clip, i) => {
      const x = ((i % cols) - (cols - 1) / 2) * 0.025, y = (Math.floor(i / cols) - (cols - 1) / 2) * 0.025;
      B.Matrix.Translation(x, y, 0).copyToArray(matrices, 16 * i);
      settings.set([clip.from, clip.to, i * 3, clip.fps], 4 * i);
    });
    mesh.thinInstanceRegisterAttribute('bakedVertexAnimationSettingsInstanced', 4);
    mesh.thinInstanceSetBuffer('matrix', matrices, 16, true);
    mesh.thinInstanceSetBuffer('bakedVertexAnimationSettingsInstanced', settings, 4, true);
    mesh.alwaysSelectAsActiveMesh = true;
    // Shaders compile in parallel: draw until two frames agree (the same moment, so the same pixels).
    const frame = async () => {
      await scene.whenReadyAsync();
      scene.render();
      const px = await engine.readPixels(0, 0, engine.getRenderWidth(), engine.getRenderHeight());
      const mask = new Uint8Array(px.length / 4);
      for (let i = 0; i < mask.length; ++i) mask[i] = px[4 * i] + px[4 * i + 1] + px[4 * i + 2] > 12 ? 1 : 0;
      return mask;
    };
    let mask = await frame();
    for (let tries = 0; tries < 20; ++tries) {
      const again = await frame();
      if (again.every((m, i) => m === mask[i])) break;
      mask = again;
    }
    return mask;
  };
  const ownMask = await herd(ownTexture);
  const covered = ownMask.reduce((a, b) => a + b, 0);
  const out = [];
  for (let v = 0; v < count; ++v) {
    const json = await (await fetch(`/bake/${v}`)).text();
    const data = baker.loadBakedVertexDataFromJSON(json), meta = JSON.parse(json);
    const sizeMatch = meta.width === (bones + 1) * 4 && meta.height === rows && data.length === own.length;
    let worst = sizeMatch ? 0 : Infinity, worstRow = -1, worstIndex = -1, compared = 0, wrapRows = 0, cycled = 0, corrected = 0;
    for (let r = 0; sizeMatch && r < rows; ++r) {
      const n = (bones + 1) * 16;
      if (wrap[r] === -2) { ++corrected; continue; }
      if (wrap[r] < 0) { ++wrapRows; continue; }
      if (wrap[r] > 0 && own.subarray(r * n, r * n + n).every((x, k) => Math.abs(x - own[(wrap[r] - 1) * n + k]) < 1e-6)) {
        ++cycled; // Babylon's bake went round to the clip's first pose at its last key
        continue;
      }
      for (let k = r * (bones + 1) * 16; k < (r + 1) * (bones + 1) * 16; ++k, ++compared) {
        const d = Math.abs(data[k] - own[k]) / Math.max(1, Math.abs(own[k])); // relative past 1: Float32's own steps
        if (!(d <= worst)) worst = d, worstRow = r, worstIndex = k - r * (bones + 1) * 16;
      }
    }
    const texture = B.RawTexture.CreateRGBATexture(data, meta.width, meta.height, scene, false, false,
                                                   B.Texture.NEAREST_NEAREST, B.Constants.TEXTURETYPE_FLOAT);
    const mask = await herd(texture);
    let silhouetteDiff = 0;
    for (let i = 0; i < mask.length; ++i) silhouetteDiff += mask[i] !== ownMask[i];
    const stateResults = v ? [] : stateBakes.map((s) => {
      const n = (bones + 1) * 16;
      let worst = s.own ? 0 : Infinity, compared = 0;
      for (let k = 0; s.own && sizeMatch && k <= Math.min(s.to - s.from, s.last - 1); ++k)
        for (let i = 0; i < n; ++i, ++compared) {
          const own = s.own[k * n + i], d = Math.abs(data[(s.from + k) * n + i] - own) / Math.max(1, Math.abs(own));
          if (!(d <= worst)) worst = d;
        }
      return { name: s.name, clip: s.clip, from: s.from, to: s.to, fps: s.fps, worst, compared, corrected: s.corrected };
    });
    out.push({ name: names[v], states: stateResults, width: meta.width, height: meta.height, bones, rows, sizeMatch, worst, worstRow, worstIndex,
               compared, wrapRows, cycled, corrected, silhouetteDiff, herd: { covered, pixels: ownMask.length } });
  }
  return out;
}
