// Rotates the SH of Gaussian splats with @playcanvas/splat-transform's own code: the data
// table is declared as stored in a space rotated by q and converted to the identity space
// (its public DataTable / Transform / convertToSpace, which runs its RotateSH on the
// f_rest_* columns).
//   node rotate_splat_sh.mjs IN.json   IN: {"quat": [w, x, y, z], "rest": [[45 numbers], ...]}
// Prints the rotated f_rest rows (channel-major, as the PLY stores them).
import { readFileSync } from 'node:fs';
import { DataTable, Column, Transform, convertToSpace } from '@playcanvas/splat-transform';
import { Quat, Vec3 } from 'playcanvas';

const inp = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const [w, x, y, z] = inp.quat;
const n = inp.rest.length;
const column = (name, values) => new Column(name, Float32Array.from(values));
const zeros = new Array(n).fill(0);
const cols = [column('x', zeros), column('y', zeros), column('z', zeros), column('rot_0', new Array(n).fill(1)),
  column('rot_1', zeros), column('rot_2', zeros), column('rot_3', zeros), column('scale_0', zeros),
  column('scale_1', zeros), column('scale_2', zeros), column('opacity', zeros), column('f_dc_0', zeros),
  column('f_dc_1', zeros), column('f_dc_2', zeros)];
for (let k = 0; k < 45; k++) cols.push(column(`f_rest_${k}`, inp.rest.map((r) => r[k])));
const table = new DataTable(cols, new Transform(new Vec3(0, 0, 0), new Quat(x, y, z, w).normalize(), 1));
const out = convertToSpace(table, Transform.IDENTITY);
const rows = inp.rest.map((_, i) => Array.from({ length: 45 }, (_, k) => out.getColumnByName(`f_rest_${k}`).data[i]));
console.log(JSON.stringify(rows));
