// Runs @playcanvas/splat-transform's own command line (its bin/cli.mjs, as `npx
// splat-transform` would), overwriting the output:
//   node splat_transform_cli.mjs IN OUT
// Its exit code and output are passed through.
import { spawnSync } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const cli = join(here, 'node_modules', '@playcanvas', 'splat-transform', 'bin', 'cli.mjs');
const r = spawnSync(process.execPath, [cli, '-w', ...process.argv.slice(2)], { stdio: 'inherit' });
process.exit(r.status ?? 1);
