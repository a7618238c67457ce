// driver.mjs - the browser tests' harness: a static file server on 127.0.0.1 (port 0) and the
// system's Chromium, headless, with WebGL2 on SwiftShader, driven by playwright-core.
//
//     import { withPage } from './driver.mjs';
//     const result = await withPage({ '/': RUNTIMES, '/job/': dir }, '/__blank.html', async (page) => {
//         return page.evaluate(async () => (await import('/web/crowdbake_pal.mjs')).PAL_VERSION);
//     });
//
// Routes map URL prefixes to folders (the longest prefix wins); "/__blank.html" is an empty page
// for tests that only import modules. Every console error and uncaught page error is collected in
// page.crowdbakeErrors. Nothing is fetched from the network: the pages work offline.
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const REPO = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
// What the pages see at '/': the runtimes' folder, so /web/ is runtimes/web and /glsl/ runtimes/glsl.
export const RUNTIMES = path.join(REPO, 'runtimes');
// A blank page whose import map finds three.js and its addons where RUNTIMES serves them: the checks
// that drive three.js set it as their page's content.
export const THREE_PAGE = `<!DOCTYPE html><script type="importmap">{ "imports": { "three": "/web/node_modules/three/build/three.module.js",
  "three/addons/": "/web/node_modules/three/examples/jsm/" } }</script>`;

// The routes of a check that draws the models of a folder: the runtimes at '/', DIR at '/check/' and
// this folder at '/tests/', where the page imports page_draw.mjs (the drawing and pixel compares the
// checks share).
export function checkRoutes(dir) {
    return { '/': RUNTIMES, '/check/': path.resolve(dir), '/tests/': path.dirname(fileURLToPath(import.meta.url)) };
}

const TYPES = {
    '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
    '.glsl': 'text/plain', '.png': 'image/png', '.wasm': 'application/wasm', '.css': 'text/css',
};

export async function startServer(routes) {
    const prefixes = Object.keys(routes).sort((a, b) => b.length - a.length);
    const server = http.createServer((req, res) => {
        const url = decodeURIComponent(new URL(req.url, 'http://localhost').pathname);
        if (url === '/favicon.ico') return res.writeHead(204).end();
        if (url === '/__blank.html') return res.writeHead(200, { 'Content-Type': 'text/html' }).end('<!DOCTYPE html><title>crowdbake</title>');
        const prefix = prefixes.find((p) => url.startsWith(p));
        if (prefix === undefined) return res.writeHead(404).end();
        const root = path.resolve(routes[prefix]);
        const file = path.resolve(root, '.' + url.slice(prefix.length - 1));
        if (file !== root && !file.startsWith(root + path.sep)) return res.writeHead(403).end();
        fs.stat(file, (e, st) => {
            if (e || !st.isFile()) return res.writeHead(404).end();
            res.writeHead(200, { 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream', 'Content-Length': st.size });
            fs.createReadStream(file).pipe(res);
        });
    });
    await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
    return { url: `http://127.0.0.1:${server.address().port}`, close: () => new Promise((r) => server.close(r)) };
}

// Chromium flags: SwiftShader (software WebGL2, the same on every machine) unless `gpu` is set.
export async function launchBrowser({ gpu = false } = {}) {
    const args = ['--no-sandbox', '--disable-background-networking', '--disable-component-update', '--no-first-run'];
    if (gpu) args.push('--use-angle=default', '--enable-gpu', '--ignore-gpu-blocklist');
    else args.push('--use-angle=swiftshader', '--enable-unsafe-swiftshader');
    return chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args });
}

export async function openPage(browser, url, { width = 960, height = 540 } = {}) {
    const page = await browser.newPage({ viewport: { width, height } });
    page.crowdbakeErrors = [];
    page.on('console', (m) => { if (m.type() === 'error') page.crowdbakeErrors.push(`console: ${m.text()}`); });
    page.on('pageerror', (e) => page.crowdbakeErrors.push(`page error: ${e.message}`));
    page.on('crash', () => page.crowdbakeErrors.push('the tab crashed'));
    await page.goto(url);
    return page;
}

// Serves `routes`, opens `pagePath` in a fresh headless Chromium, runs fn(page, baseUrl) and
// closes everything, whatever happens.
export async function withPage(routes, pagePath, fn, options = {}) {
    const server = await startServer(routes);
    const browser = await launchBrowser(options);
    try {
        const page = await openPage(browser, server.url + pagePath, options);
        return await fn(page, server.url);
    } finally {
        await browser.close();
        await server.close();
    }
}
