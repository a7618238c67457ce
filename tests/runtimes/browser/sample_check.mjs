// sample_check.mjs - the copyable three.js page (samples/web/index.html + herd.mjs) loaded as it
// is, from the repository tree, in headless Chromium: it must draw a herd (the pixels that change
// when the herd is hidden for one frame), hear footsteps, hang its prop at its own size, and log
// no console error.
//
//   node tests/runtimes/browser/sample_check.mjs DIR TYPE
//
// DIR holds a baked roster.json (its models and palettes where it names them). Prints JSON.
import path from 'node:path';
import { withPage, REPO } from './driver.mjs';

const [dir, type] = process.argv.slice(2);
const url = `/samples/web/index.html?roster=/job/roster.json&type=${encodeURIComponent(type)}`;

const result = await withPage({ '/': REPO, '/job/': path.resolve(dir) }, url, async (p) => {
    // Footsteps need the clock to run: wait (bounded, never as synchronisation of a result) until
    // enough frames have been drawn and a foot has landed.
    const ready = p.waitForFunction(() => window.crowdbakeSample?.frames >= 3 && window.crowdbakeSample.footsteps > 0,
                                    null, { timeout: 120000, polling: 100 });
    const failed = new Promise((resolve) => { // or the page fails first: report its error, not a timeout
        const look = setInterval(() => { if (p.crowdbakeErrors.length) clearInterval(look), resolve(); }, 100);
        ready.finally(() => clearInterval(look), () => {});
    });
    await Promise.race([ready, failed]);
    if (p.crowdbakeErrors.length) throw new Error(p.crowdbakeErrors.join('; '));
    const r = await p.evaluate(async () => {
        const s = window.crowdbakeSample, canvas = document.querySelector('canvas');
        const grab = () => new Promise((resolve) => requestAnimationFrame(() => { // after the page's own frame
            const c = document.createElement('canvas');
            c.width = canvas.width, c.height = canvas.height;
            const g = c.getContext('2d');
            g.drawImage(canvas, 0, 0);
            resolve(g.getImageData(0, 0, c.width, c.height).data);
        }));
        const shown = await grab();
        s.herd.visible = false;
        await grab();
        const hidden = await grab();
        s.herd.visible = true;
        let herdPixels = 0;
        for (let i = 0; i < shown.length; i += 4)
            herdPixels += [0, 1, 2].some((k) => Math.abs(shown[i + k] - hidden[i + k]) > 8);
        return { frames: s.frames, footsteps: s.footsteps, instances: s.instances, type: s.type, socket: s.socket,
                 prop_scale: s.prop_scale, herd_pixels: herdPixels, pixels: shown.length / 4,
                 draw_calls: s.herd.material.length ?? 1 };
    });
    r.errors = p.crowdbakeErrors;
    return r;
}, { width: 640, height: 360 }); // SwiftShader draws 500 animals and their shadows on the CPU: a smaller window
console.log(JSON.stringify(result));
if (result.errors.length) process.exitCode = 1;
