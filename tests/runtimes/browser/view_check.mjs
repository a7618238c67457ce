// view_check.mjs - `crowdbake view` used as a user would, in headless Chromium.
//
//   node tests/runtimes/browser/view_check.mjs CROWDBAKE INPUT CACHE_DIR SCREENSHOT.png [COUNT [WIDTHxHEIGHT [MORE,COUNTS]]]
//
// Starts `crowdbake view INPUT --cache CACHE_DIR --port 0`, reads the URL it prints, opens the
// viewer with the clock stopped (?paused), puts the herd in a mix of states, renders two chosen
// times and reads the canvas back: prints, per half (palette | VAT), the share of pixels that are
// not the background, how many pixels differ between the two times, the page's own stats and
// every console error; saves a screenshot. MORE,COUNTS: the page opened again with each as
// ?count=, what it shows (instances, the count menu, the panel's notice; draw calls of a frame
// where there are at most 1000 instances: more take minutes in a software renderer). Then Ctrl-C (SIGINT) must stop the command with exit 0.
// Prints JSON on the last line; the judging is tests/cli/test_view.c's.
import { spawn } from 'node:child_process';
import { launchBrowser, openPage } from './driver.mjs';

const [exe, input, cache, shot, count = '1000', size = '960x540', more = ''] = process.argv.slice(2);
const [width, height] = size.split('x').map(Number);
const view = spawn(exe, ['view', input, '--cache', cache, '--port', '0'], { stdio: ['ignore', 'pipe', 'inherit'] });
let output = '';
const url = await new Promise((resolve, reject) => {
    view.stdout.on('data', (d) => {
        output += d;
        const m = output.match(/^(http:\/\/127\.0\.0\.1:\d+\/\S+)$/m);
        if (m) resolve(m[1]);
    });
    view.on('exit', (code) => reject(new Error(`crowdbake view exited with ${code} before printing a URL:\n${output}`)));
});
const exited = new Promise((resolve) => view.on('exit', (code, signal) => resolve({ code, signal })));

const browser = await launchBrowser();
let result;
try {
    const page = await openPage(browser, `${url}?paused&count=${count}`, { width, height });
    await page.evaluate(() => window.crowdbakeReady);
    result = await page.evaluate(() => {
        const v = window.crowdbakeViewer, canvas = document.getElementById('view');
        const gl = canvas.getContext('webgl2');
        const read = () => {
            const px = new Uint8Array(canvas.width * canvas.height * 4);
            gl.readPixels(0, 0, canvas.width, canvas.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
            return px;
        };
        const background = [33, 38, 43]; // the clear colour, 0.13 0.15 0.17
        const coverage = (px) => [0, 1].map((half) => {
            let n = 0, all = 0;
            for (let y = 0; y < canvas.height; ++y)
                for (let x = half * canvas.width / 2; x < (half + 1) * canvas.width / 2; ++x, ++all) {
                    const i = (y * canvas.width + x) * 4;
                    if (Math.abs(px[i] - background[0]) + Math.abs(px[i + 1] - background[1]) + Math.abs(px[i + 2] - background[2]) > 12) ++n;
                }
            return n / all;
        });
        v.setState(null); // the mix: idle, walk, gallop
        v.renderAt(1.0);
        const a = read();
        v.renderAt(1.4);
        const b = read();
        // Palette (left) against VAT (right) at the same time: the same silhouettes, pixel for pixel.
        let mismatch = 0, covered = 0;
        const w = canvas.width, halfW = w / 2;
        const fg = (i) => Math.abs(b[i] - background[0]) + Math.abs(b[i + 1] - background[1]) + Math.abs(b[i + 2] - background[2]) > 12;
        for (let y = 0; y < canvas.height; ++y)
            for (let x = 0; x < halfW; ++x) {
                const l = fg((y * w + x) * 4), r = fg((y * w + x + halfW) * 4);
                covered += l || r, mismatch += l !== r;
            }
        let changed = 0;
        for (let i = 0; i < a.length; i += 4) if (a[i] !== b[i] || a[i + 1] !== b[i + 1] || a[i + 2] !== b[i + 2]) ++changed;
        const s = v.stats();
        return { palette_vs_vat_mismatch: mismatch / Math.max(covered, 1), coverage_at_1: coverage(a), coverage_at_1_4: coverage(b), changed_pixels: changed, pixels: a.length / 4,
                 stats: { frameMs: s.frameMs, drawCalls: s.drawCalls, instances: s.instances, paletteBytes: s.paletteBytes,
                          vatBytes: s.vatBytes },
                 states: Object.keys(v.types[0].states), panel: document.getElementById('stats').textContent,
                 error: document.getElementById('error').textContent };
    });
    await page.screenshot({ path: shot });
    result.console_errors = page.crowdbakeErrors;
    result.counts = [];
    for (const query of more ? more.split(',') : []) {
        const p = await openPage(browser, `${url}?paused&count=${encodeURIComponent(query)}`, { width: 320, height: 180 });
        await p.evaluate(() => window.crowdbakeReady);
        result.counts.push(await p.evaluate((query) => {
            const v = window.crowdbakeViewer, drawn = v.stats().instances <= 1000;
            if (drawn) v.renderAt(1.0);
            const s = v.stats(), $ = (id) => document.getElementById(id);
            return { query, instances: s.instances, selected: $('count').value, drawCalls: drawn ? s.drawCalls : null,
                     notice: $('notice')?.textContent ?? null, error: $('error').textContent };
        }, query));
        result.counts.at(-1).console_errors = p.crowdbakeErrors;
        await p.close();
    }
} catch (e) {
    result = { failure: String(e.message ?? e).split('\n')[0] };
} finally {
    await browser.close();
    view.kill('SIGINT');
}
const end = await exited;
result.exit = end;
result.printed = output.trim().split('\n');
console.log(JSON.stringify(result));
