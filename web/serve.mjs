#!/usr/bin/env node
// Serves the web package for the viewer and the browser tests, on 127.0.0.1 only:
//   node web/serve.mjs [--port N] [--web DIR] [--three DIR] [--root PREFIX=DIR ...]
// / is the built package (DIR, default build/web: the .wasm, the JS modules, the viewer at /viewer/), /vendor/three/ the three
// package (default tests/js/node_modules/three, installed by .ci/setup), /vendor/@babylonjs/ Babylon.js's ES module packages
// (tests/js/node_modules/@babylonjs), and each --root PREFIX=DIR one more folder (tests serve their pages and files so). Prints the address; Ctrl-C stops it.
import { createServer } from 'node:http';
import { createReadStream, existsSync, statSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
                '.wasm': 'application/wasm', '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json',
                '.bin': 'application/octet-stream', '.png': 'image/png', '.jpg': 'image/jpeg', '.css': 'text/css' };

export function serve({ port = 0, web = path.join(here, '..', 'build', 'web'),
                        three = path.join(here, '..', 'tests', 'js', 'node_modules', 'three'),
                        babylon = path.join(here, '..', 'tests', 'js', 'node_modules', '@babylonjs'), roots = {} } = {}) {
  const mounts = [...Object.entries(roots), ['/vendor/three/', three], ['/vendor/@babylonjs/', babylon], ['/', web]]
    .map(([prefix, directory]) => [prefix.endsWith('/') ? prefix : `${prefix}/`, path.resolve(directory)]);
  const server = createServer((request, response) => {
    const url = decodeURIComponent(new URL(request.url, 'http://localhost').pathname);
    for (const [prefix, directory] of mounts) {
      if (!url.startsWith(prefix)) continue;
      let file = path.join(directory, url.slice(prefix.length));
      if (!file.startsWith(directory)) break;  // no way out of the folder
      if (existsSync(file) && statSync(file).isDirectory()) file = path.join(file, 'index.html');
      if (!existsSync(file)) continue;
      response.writeHead(200, { 'Content-Type': TYPES[path.extname(file)] ?? 'application/octet-stream',
                                'Cache-Control': 'no-store' });
      createReadStream(file).pipe(response);
      return;
    }
    response.writeHead(404, { 'Content-Type': 'text/plain' });
    response.end(`not found: ${url}\n`);
  });
  return new Promise((resolve) => server.listen(port, '127.0.0.1', () => resolve(server)));
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const options = { port: 8080, roots: {} };
  const args = process.argv.slice(2);
  for (let i = 0; i < args.length; ++i) {
    const value = () => {
      if (i + 1 >= args.length) { console.error(`serve: ${args[i]} needs a value`); process.exit(2); }
      return args[++i];
    };
    if (args[i] === '--port') options.port = Number(value());
    else if (args[i] === '--web') options.web = value();
    else if (args[i] === '--three') options.three = value();
    else if (args[i] === '--root') { const [prefix, directory] = value().split('='); options.roots[prefix] = directory; }
    else { console.error(`serve: unknown argument ${args[i]} (see the comment at the top of web/serve.mjs)`); process.exit(2); }
  }
  const web = options.web ?? path.join(here, '..', 'build', 'web');
  if (!existsSync(path.join(web, 'segmorph_decoder.wasm'))) {
    console.error(`serve: ${web} has no segmorph_decoder.wasm: build first (bash .ci/build release)`);
    process.exit(1);
  }
  const server = await serve(options);
  console.log(`segmorph viewer: http://127.0.0.1:${server.address().port}/viewer/ (Ctrl-C stops the server)`);
}
