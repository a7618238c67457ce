// herd.mjs - the sample page's herd (samples/web/index.html): a roster baked by `crowdbake bake
// CATALOG.toml` loaded, one type's model and palette drawn as a CrowdbakeHerd of 500 animals that
// wander a field with place(), casting shadows, a prop hung on a socket of the first animal, and a
// callback on every footstep.
//
// Query parameters: roster (the roster.json's URL; default: the sample catalog's, which
// `make demo` bakes into build/roster), type (default: the roster's first), count (default 500).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { readPal, readRoster } from 'crowdbake/crowdbake_pal.mjs';
import { loadPaletteGLSL } from 'crowdbake/crowdbake_crowd.mjs';
import { CrowdbakeHerd } from 'crowdbake/crowdbake_three.mjs';

const query = new URLSearchParams(location.search);
const rosterUrl = new URL(query.get('roster') ?? '../../build/roster/roster.json', location.href);
const count = Number(query.get('count') ?? 500);

// What the page did, for a test (or a curious console): frames drawn, footsteps heard, the prop's size.
const status = { frames: 0, footsteps: 0, instances: count, type: null, socket: null, prop_scale: null, herd: null };
window.crowdbakeSample = status;

// The roster names each type's model and palette relative to itself.
const roster = readRoster(await (await fetch(rosterUrl)).text(), { name: rosterUrl.pathname });
const typeName = query.get('type') ?? Object.keys(roster.types)[0];
const type = roster.types[typeName];
if (!type) throw new Error(`${rosterUrl}: no type '${typeName}' (have ${Object.keys(roster.types).join(', ')})`);
const palette = type.palette ?? roster.types[type.shares_palette_of].palette;
const pal = readPal(new Uint8Array(await (await fetch(new URL(palette, rosterUrl))).arrayBuffer()));
const gltf = await new GLTFLoader().loadAsync(new URL(type.model, rosterUrl).href);
status.type = typeName;

// The herd: one InstancedMesh, the model's own materials, skinned from the palette on the GPU.
const herd = new CrowdbakeHerd(gltf, pal, type, { count, glsl: await loadPaletteGLSL() });
herd.castShadow = true;
herd.receiveShadow = true;

// The field, sized to the animal: about three body lengths apart.
const height = pal.header.model_height || 1;
const spacing = 3 * height, radius = Math.sqrt(count) * spacing * 0.6;
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x9cc4e4);
scene.add(new THREE.HemisphereLight(0xffffff, 0x556644, 1.2));
const sun = new THREE.DirectionalLight(0xffffff, 2.5);
sun.position.set(radius * 0.5, radius, radius * 0.3);
sun.castShadow = true;
sun.shadow.mapSize.set(2048, 2048);
Object.assign(sun.shadow.camera, { left: -radius * 1.2, right: radius * 1.2, top: radius * 1.2, bottom: -radius * 1.2,
                                   near: radius * 0.1, far: radius * 4 });
scene.add(sun);
const ground = new THREE.Mesh(new THREE.CircleGeometry(radius * 1.3, 64).rotateX(-Math.PI / 2),
                              new THREE.MeshLambertMaterial({ color: 0x7da05a }));
ground.receiveShadow = true;
scene.add(ground, herd);
status.herd = herd;

// Wandering: each animal walks at about its type's speed reference (units/s: the speed at which
// the walk clip plays at its own rate, feet planted) and turns a little now and then; the state
// that follows the speed is the type's default one.
const wander = type.default_state;
const speedReference = type.speed_reference || height;
const random = (() => { let s = 12345; return () => ((s = (s * 1103515245 + 12345) % 2147483648) / 2147483648); })();
const animals = Array.from({ length: count }, (_, i) => {
    const angle = i * 2.39996, r = radius * Math.sqrt((i + 0.5) / count); // a sunflower: evenly spread
    return { x: r * Math.cos(angle), z: r * Math.sin(angle), yaw: random() * Math.PI * 2, turn: 0,
             speed: speedReference * (0.8 + 0.4 * random()) };
});
animals.forEach((a, i) => {
    herd.setState(i, wander, { speed: a.speed, fade: 0 });
    herd.place(i, [a.x, 0, a.z], { yaw: a.yaw });
});
function walk(dt) {
    animals.forEach((a, i) => {
        if (random() < dt * 0.5) a.turn = (random() - 0.5) * 1.5; // a new heading now and then (rad/s)
        if (Math.hypot(a.x, a.z) > radius) a.turn = 1.5;           // at the edge: turn back in
        a.yaw += a.turn * dt;
        // The model faces +z (glTF's forward); yaw turns it about +y.
        a.x += Math.sin(a.yaw) * a.speed * dt;
        a.z += Math.cos(a.yaw) * a.speed * dt;
        herd.place(i, [a.x, 0, a.z], { yaw: a.yaw });
    });
}

// A prop on a socket (a roster socket: a node under a bone, e.g. Head_end): its own size in the
// model's units, placed each frame at instance x bone x bind_transform (socketMatrixAt).
const socket = type.sockets.find((s) => /head/i.test(s.name)) ?? type.sockets[0];
const prop = new THREE.Mesh(new THREE.BoxGeometry(0.25 * height, 0.25 * height, 0.25 * height),
                            new THREE.MeshStandardMaterial({ color: 0xffcc00 }));
prop.castShadow = true;
prop.matrixAutoUpdate = false;
if (socket) {
    scene.add(prop);
    status.socket = socket.name;
}

// A footstep callback: every foot landing of every animal (the roster's contacts).
herd.onContact(({ kind }) => { if (kind === 'land') status.footsteps++; });

const renderer = new THREE.WebGLRenderer({ antialias: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(innerWidth, innerHeight);
renderer.shadowMap.enabled = true;
document.body.append(renderer.domElement);
const camera = new THREE.PerspectiveCamera(45, innerWidth / innerHeight, radius * 0.01, radius * 10);
camera.position.set(0, radius * 0.8, radius * 1.6);
camera.lookAt(0, 0, 0);
addEventListener('resize', () => {
    camera.aspect = innerWidth / innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(innerWidth, innerHeight);
});

// The herd's clock starts at 0 with the first frame (the time the states were set): footsteps
// fire for the crossings since the last update, so a clock starting at the page's age would
// raise every step the herd "missed" before it was shown.
let start = null, last = 0;
renderer.setAnimationLoop((ms) => {
    start ??= ms;
    const t = (ms - start) / 1000, dt = Math.min(t - last, 0.1);
    last = t;
    walk(dt);
    herd.update(t);
    if (socket) {
        herd.socketMatrixAt(0, socket, prop.matrix);
        prop.matrixWorldNeedsUpdate = true;
        status.prop_scale = new THREE.Vector3().setFromMatrixColumn(prop.matrix, 0).length();
    }
    renderer.render(scene, camera);
    status.frames++;
});
