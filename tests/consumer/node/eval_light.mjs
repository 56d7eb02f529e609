// Evaluates an exported light with the consumer's own code, at directions of its frame.
//   node eval_light.mjs FORMAT FILE DIRS.json   (DIRS.json: [[x, y, z], ...], unit)
// Prints a JSON list, per direction, of {"radiance": [r, g, b], "irradiance": [r, g, b]}
// (threejs: SphericalHarmonics3.getAt and getIrradianceAt, times the probe's intensity)
// or {"irradiance_over_pi": [r, g, b]} (gltf, babylon: what Babylon's PBR shader gets).
import { readFileSync } from 'node:fs';

const [format, file, dirsFile] = process.argv.slice(2);
const doc = JSON.parse(readFileSync(file, 'utf8'));
const dirs = JSON.parse(readFileSync(dirsFile, 'utf8'));

// Babylon's default (SPHERICAL_HARMONICS) diffuse path, ShadersInclude/harmonicsFunctions.fx
// computeEnvironmentIrradiance, on the uniforms materialHelper sets from
// polynomial.preScaledHarmonics: written out here, the shader being GLSL.
function babylonShader(h, [x, y, z]) {
  const k = ['l00', 'l1_1', 'l10', 'l11', 'l2_2', 'l2_1', 'l20', 'l21', 'l22'].map((n) => h[n].asArray());
  return [0, 1, 2].map((c) => k[0][c] + k[1][c] * y + k[2][c] * z + k[3][c] * x + k[4][c] * y * x + k[5][c] * y * z +
                              k[6][c] * (3 * z * z - 1) + k[7][c] * z * x + k[8][c] * (x * x - y * y));
}

let out;
if (format === 'threejs') {
  const { ObjectLoader, Vector3 } = await import('three');
  const probe = new ObjectLoader().parse(doc);  // LightProbe.toJSON's layout, read as three reads it
  out = dirs.map((d) => {
    const n = new Vector3(...d);
    const L = probe.sh.getAt(n, new Vector3()).multiplyScalar(probe.intensity);
    const E = probe.sh.getIrradianceAt(n, new Vector3()).multiplyScalar(probe.intensity);
    return { radiance: [L.x, L.y, L.z], irradiance: [E.x, E.y, E.z] };
  });
} else if (format === 'gltf') {
  // @babylonjs/loaders EXT_lights_image_based._loadLightAsync, step by step.
  const { SphericalHarmonics, SphericalPolynomial } = await import('@babylonjs/core/Maths/sphericalPolynomial.js');
  const light = doc.extensions.EXT_lights_image_based.lights[0];
  const sh = SphericalHarmonics.FromArray(light.irradianceCoefficients);
  sh.scaleInPlace(light.intensity);
  sh.convertIrradianceToLambertianRadiance();
  const poly = SphericalPolynomial.FromHarmonics(sh);
  const level = light.intensity;  // babylonTexture.level
  out = dirs.map((d) => ({ irradiance_over_pi: babylonShader(poly.preScaledHarmonics, d).map((v) => v * level) }));
} else if (format === 'babylon') {
  // The .env manifest's irradiance, as environmentTextureTools loads it.
  const { SphericalPolynomial } = await import('@babylonjs/core/Maths/sphericalPolynomial.js');
  const p = doc.irradiance;
  const poly = SphericalPolynomial.FromArray([p.x, p.y, p.z, p.xx, p.yy, p.zz, p.yz, p.zx, p.xy]);
  out = dirs.map((d) => ({ irradiance_over_pi: babylonShader(poly.preScaledHarmonics, d) }));
} else {
  throw new Error(`no consumer for format ${format}`);
}
console.log(JSON.stringify(out));
