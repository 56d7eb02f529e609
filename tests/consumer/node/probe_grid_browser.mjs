// Serves the consumers' folder over HTTP (module scripts do not load from file: URLs) and
// renders probe_grid_page.html in headless Chromium (WebGL2 on SwiftShader), printing the
// page's #result JSON.
//   node probe_grid_browser.mjs CHROMIUM GRID_DIR   (GRID_DIR holds probes.json and probes.bin)
import { createServer } from 'node:http';
import { execFile } from 'node:child_process';
import { readFile } from 'node:fs/promises';
import { dirname, join, normalize } from 'node:path';
import { fileURLToPath } from 'node:url';

const [chromium, gridDir] = process.argv.slice(2);
const root = dirname(fileURLToPath(import.meta.url));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json' };

const server = createServer(async (req, res) => {
  const path = normalize(decodeURIComponent(new URL(req.url, 'http://x').pathname));
  const file = path.startsWith('/grid/') ? join(gridDir, path.slice(6)) : join(root, path);
  try {
    const body = await readFile(file);
    const ext = file.slice(file.lastIndexOf('.'));
    res.writeHead(200, { 'Content-Type': types[ext] || 'application/octet-stream' });
    res.end(body);
  } catch {
    res.writeHead(404);
    res.end();
  }
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
const url = `http://127.0.0.1:${server.address().port}/probe_grid_page.html`;
const args = ['--headless', '--no-sandbox', '--disable-gpu-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
              '--ignore-gpu-blocklist', '--no-first-run', '--disable-extensions', '--virtual-time-budget=60000',
              '--run-all-compositor-stages-before-draw', '--dump-dom', url];
execFile(chromium, args, { maxBuffer: 64 << 20, timeout: 240000 }, (err, stdout, stderr) => {
  server.close();
  const m = /<pre id="result">([^<]*)<\/pre>/.exec(stdout);
  if (!m) {
    process.stdout.write(JSON.stringify({ error: `no result from chromium (${err ? err.message : 'exit 0'}): ${stderr.slice(-2000)}` }) + '\n');
    return;
  }
  const text = m[1].replace(/&quot;/g, '"').replace(/&lt;/g, '<').replace(/&gt;/g, '>').replace(/&amp;/g, '&');
  process.stdout.write(text + '\n');
});
