// Loads a probe grid through web/shtool-three.js (copied beside this script) with three.js
// itself, and evaluates every probe with three's SphericalHarmonics3.getIrradianceAt.
//   node probe_grid_three.mjs DIR/probes.json NORMALS.json   (NORMALS.json: [[x, y, z], ...], three's frame)
// Prints {"resolution", "boundingBox", "probes": [{"index": [i, j, k], "position": [x, y, z],
// "irradiance": [[r, g, b] per normal]}], "padding_mismatches": n, "disposed": whether
// grid.dispose() freed the atlas texture}, or {"error": message}.
import { readFile } from 'node:fs/promises';
import { readFileSync } from 'node:fs';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { SphericalHarmonics3, Vector3 } from 'three';
import { loadProbeGrid } from './shtool-three.js';

const [jsonPath, normalsPath] = process.argv.slice(2);
const load = async (url) => {
  const b = await readFile(fileURLToPath(url));
  return b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength);
};

let grid;
try {
  grid = await loadProbeGrid(pathToFileURL(jsonPath).href, { load });
} catch (e) {
  process.stdout.write(JSON.stringify({ error: e.message }) + '\n');
  process.exit(0);
}

const normals = JSON.parse(readFileSync(normalsPath, 'utf8')).map((d) => new Vector3(...d));
const tex = grid.texture;
const [nx, ny, nz] = [grid.resolution.x, grid.resolution.y, grid.resolution.z];
const data = tex.image.data;
if (!(grid.isLightProbeGrid && tex.isData3DTexture && tex.image.width === nx && tex.image.height === ny &&
      tex.image.depth === 7 * (nz + 2))) throw new Error('not a LightProbeGridWebGL atlas');
// Texel (x, y, s) of the atlas, as three's texImage3D upload orders it.
const texel = (x, y, s) => ((s * ny + y) * nx + x) * 4;
let paddingMismatches = 0;
const probes = [];
for (let k = 0; k < nz; k++)
  for (let j = 0; j < ny; j++)
    for (let i = 0; i < nx; i++) {
      const values = [];
      for (let t = 0; t < 7; t++) {
        const at = texel(i, j, t * (nz + 2) + 1 + k);
        for (let c = 0; c < 4; c++) values.push(data[at + c]);
        // the padding slices repeat the first and last data slices of the slot
        const pad = k === 0 ? t * (nz + 2) : k === nz - 1 ? t * (nz + 2) + nz + 1 : -1;
        if (pad >= 0) for (let c = 0; c < 4; c++) if (data[texel(i, j, pad) + c] !== data[at + c]) paddingMismatches++;
      }
      if (values[27] !== 0) paddingMismatches++;
      const sh = new SphericalHarmonics3().fromArray(values.slice(0, 27));
      const p = grid.getProbePosition(i, j, k, new Vector3());
      probes.push({
        index: [i, j, k],
        position: [p.x, p.y, p.z],
        irradiance: normals.map((n) => sh.getIrradianceAt(n, new Vector3()).toArray()),
      });
    }
// dispose() frees the loaded atlas (three's own frees only the render target its bake makes).
let disposed = false;
tex.addEventListener('dispose', () => { disposed = true; });
grid.dispose();
disposed = disposed && grid.texture === null;
process.stdout.write(JSON.stringify({
  resolution: grid.resolution.toArray(),
  boundingBox: { min: grid.boundingBox.min.toArray(), max: grid.boundingBox.max.toArray() },
  textureType: { format: tex.format, type: tex.type, minFilter: tex.minFilter, magFilter: tex.magFilter,
                 generateMipmaps: tex.generateMipmaps },
  probes,
  padding_mismatches: paddingMismatches,
  disposed,
}) + '\n');
