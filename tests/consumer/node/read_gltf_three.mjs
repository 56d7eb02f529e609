// Reads a .glb with three.js's own GLTFLoader, as an engine would load fit-zh --gltf:
//   node read_gltf_three.mjs FILE.glb
// Prints {"meshes", "vertexColors", "userData", "index": [...], "attributes": {three's
// name: {"itemSize", "values": [...]}}} as JSON (float32 values print exactly as doubles).
import { readFileSync } from 'node:fs';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

const bytes = readFileSync(process.argv[2]);
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
new GLTFLoader().parse(buffer, '', (gltf) => {
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isMesh) meshes.push(o); });
  const geometry = meshes[0].geometry;
  const attributes = {};
  for (const [name, a] of Object.entries(geometry.attributes))
    attributes[name] = { itemSize: a.itemSize, values: Array.from(a.array) };
  console.log(JSON.stringify({ meshes: meshes.length, vertexColors: meshes[0].material.vertexColors,
    userData: meshes[0].userData, index: Array.from(geometry.index.array), attributes }));
}, (e) => { console.error(String(e)); process.exit(1); });
