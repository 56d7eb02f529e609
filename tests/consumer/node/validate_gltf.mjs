// The Khronos glTF validator's own code (npm gltf-validator) on a file:
//   node validate_gltf.mjs FILE.glb
// Prints its report as JSON (issues.numErrors, numWarnings, numInfos, numHints and every
// message, info.drawCallCount ...), all issues listed.
import { readFileSync } from 'node:fs';
import validator from 'gltf-validator';

const report = await validator.validateBytes(new Uint8Array(readFileSync(process.argv[2])), { maxIssues: 0 });
console.log(JSON.stringify(report));
