// strip_skeleton.mjs IN.glb OUT.glb - the same GLB without skins[].skeleton, so that a loader finds
// the skeleton root itself (@babylonjs/loaders: the joints' nearest common ancestor).
import fs from 'node:fs';

const [input, output] = process.argv.slice(2);
const glb = fs.readFileSync(input);
const jsonLength = glb.readUInt32LE(12);
const gltf = JSON.parse(glb.subarray(20, 20 + jsonLength).toString('utf8'));
for (const skin of gltf.skins || []) delete skin.skeleton;
let json = Buffer.from(JSON.stringify(gltf), 'utf8');
json = Buffer.concat([json, Buffer.alloc((4 - (json.length % 4)) % 4, 0x20)]);
const rest = glb.subarray(20 + jsonLength);
const header = Buffer.alloc(20);
header.write('glTF', 0, 'ascii');
header.writeUInt32LE(2, 4);
header.writeUInt32LE(20 + json.length + rest.length, 8);
header.writeUInt32LE(json.length, 12);
header.writeUInt32LE(0x4e4f534a, 16); // JSON
fs.writeFileSync(output, Buffer.concat([header, json, rest]));
