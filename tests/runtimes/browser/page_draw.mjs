// page_draw.mjs - what the browser checks that draw three.js scenes share, run in their page: an
// offscreen renderer that reads back lit colour images and white-on-black masks, the camera on a
// clip's bounds, and the pixel compares. driver.mjs's checkRoutes serve this folder at /tests/, and the
// page's import map (THREE_PAGE) finds three:
//
//     const { offscreen, cameraOn, compareColours } = await import('/tests/page_draw.mjs');
import * as THREE from 'three';

// A size x size offscreen renderer (no antialiasing: the pixels are the same on every run).
export function offscreen(size) {
    const renderer = new THREE.WebGLRenderer({ antialias: false });
    renderer.setSize(size, size);
    const target = new THREE.WebGLRenderTarget(size, size);
    const draw = (scene, camera, alpha) => {
        renderer.setRenderTarget(target);
        renderer.setClearColor(0x000000, alpha);
        renderer.render(scene, camera);
        const px = new Uint8Array(size * size * 4);
        renderer.readRenderTargetPixels(target, 0, 0, size, size, px);
        return px;
    };
    return {
        renderer,
        // `object` under a hemisphere light and a sun, on a transparent background: RGBA bytes.
        image(object, camera) {
            const scene = new THREE.Scene();
            scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 1.5));
            const sun = new THREE.DirectionalLight(0xffffff, 2.5);
            sun.position.set(1, 2, 1.5);
            scene.add(sun, object);
            const px = draw(scene, camera, 0);
            scene.remove(object);
            return px;
        },
        // `scene` on black: RGBA bytes.
        pixels(scene, camera) {
            return draw(scene, camera, 1);
        },
        // `scene` on black: per pixel, whether its red is over half (a white silhouette).
        mask(scene, camera) {
            const px = draw(scene, camera, 1);
            return Array.from({ length: size * size }, (_, i) => px[i * 4] > 127);
        },
    };
}

// A clip's bounds (a .pal clip's bounds_min and bounds_max): their centre and diagonal.
export function clipBox(clip) {
    const lo = new THREE.Vector3(...clip.bounds_min), hi = new THREE.Vector3(...clip.bounds_max);
    return { center: lo.clone().add(hi).multiplyScalar(0.5), extent: hi.clone().sub(lo).length() };
}

// A square camera looking at `center` from `offset` (in units of `extent`, a box's diagonal), the box in view.
export function cameraOn(center, extent, { fov = 30, offset = [1.3, 0.4, 1.1] } = {}) {
    const camera = new THREE.PerspectiveCamera(fov, 1, extent * 0.05, extent * 20);
    camera.position.copy(center).add(new THREE.Vector3(...offset.map((k) => extent * k)));
    camera.lookAt(center);
    return camera;
}

// Two images: covered, the pixels drawn in either; share, those of them where any channel (or the
// coverage) is off by more than `tolerance` (of 255).
export function compareColours(a, b, tolerance) {
    let covered = 0, differ = 0;
    for (let i = 0; i < a.length; i += 4) {
        if (!a[i + 3] && !b[i + 3]) continue;
        covered++;
        differ += [0, 1, 2, 3].some((k) => Math.abs(a[i + k] - b[i + k]) > tolerance);
    }
    return { covered, share: differ / Math.max(covered, 1) };
}

// Two masks: covered, the pixels set in either; differ, those set in one only; share, differ of covered.
export function compareMasks(a, b) {
    let covered = 0, differ = 0;
    for (let i = 0; i < a.length; ++i) covered += a[i] || b[i], differ += a[i] !== b[i];
    return { covered, differ, share: differ / Math.max(covered, 1) };
}
