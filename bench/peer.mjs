// peer.mjs MODEL FPS [OUT.f32] - the script a user would otherwise write: load a GLB with
// three.js's GLTFLoader, step an AnimationMixer through every clip at crowdbake's frame times
// (t = t0 + i * D / N, i = 0..N, N = max(1, round(D * fps))) and read each joint matrix
// (boneWorld * boneInverse) into Float32Arrays. Prints timings as JSON; with OUT, writes
// the matrices for a cross-check.
import { readFileSync, writeFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

const [path, fpsText, out] = process.argv.slice(2);
const fps = Number(fpsText);
const t0 = performance.now();
const bytes = readFileSync(path);
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
// Node has no image decoder: skip textures, as crowdbake never decodes images either.
const loader = new GLTFLoader().register(() => ({ name: 'skip-textures', loadTexture: () => Promise.resolve(null) }));
const gltf = await new Promise((resolve, reject) => loader.parse(buffer, '', resolve, reject));
const t1 = performance.now();

let skinned = null;
gltf.scene.traverse((o) => { if (!skinned && o.isSkinnedMesh) skinned = o; });
const skeleton = skinned.skeleton;
const bones = skeleton.bones.length;
const mixer = new THREE.AnimationMixer(gltf.scene);
const frames = [];
let matrices = 0;
const scratch = new THREE.Matrix4();
for (const clip of gltf.animations) {
  let start = Infinity, end = -Infinity;
  for (const track of clip.tracks) {
    start = Math.min(start, track.times[0]);
    end = Math.max(end, track.times[track.times.length - 1]);
  }
  const duration = end - start, steps = Math.max(1, Math.round(duration * fps));
  const action = mixer.clipAction(clip);
  action.play();
  const rows = new Float32Array((steps + 1) * bones * 16);
  for (let i = 0; i <= steps; ++i) {
    mixer.setTime(start + (i * duration) / steps);
    gltf.scene.updateMatrixWorld(true);
    for (let b = 0; b < bones; ++b) {
      scratch.multiplyMatrices(skeleton.bones[b].matrixWorld, skeleton.boneInverses[b]);
      rows.set(scratch.elements, (i * bones + b) * 16);
    }
    matrices += bones;
  }
  action.stop();
  frames.push(rows);
}
const t2 = performance.now();
if (out) writeFileSync(out, Buffer.concat(frames.map((f) => Buffer.from(f.buffer))));
console.log(JSON.stringify({ load: (t1 - t0) / 1000, sample: (t2 - t1) / 1000, matrices, bones, clips: gltf.animations.length }));
