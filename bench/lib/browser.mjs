// The browser part: what a web page pays for a sequence, segmorph's file against gltfpack's at the same error.
// For each sequence: segmorph encode --error SPEED_ERROR; gltfpack -cc -af 0 swept over -vp, the file smallest after
// brotli -q 11 at equal or lower KG (measured by segmorph verify after meshopt_decode.mjs) as the anchor; both files'
// bytes raw, after gzip -9 and after brotli -q 11; then, in headless Chromium (Debian's, driven by playwright-core,
// pages served by web/serve.mjs on 127.0.0.1), the time GLTFLoader takes from the bytes to a scene ready to play
// (segmorph: the plugin and DRACOLoader; gltfpack: MeshoptDecoder), the first load in the page and the median of the
// next ones, and the decoder's own share. Time to the first played frame over a link: brotli bytes / link rate + that time.

import { mkdirSync } from 'node:fs';
import path from 'node:path';
import { chromium } from '../../tests/js/node_modules/playwright-core/index.mjs';
import { serve } from '../../web/serve.mjs';
import { SPEED_ERROR } from './speed.mjs';
import { deliveredBytes, progress } from './tools.mjs';

export const LINKS_MBIT = [10, 50];
const GLTFPACK_BITS = { full: [9, 10, 11, 12, 13, 14, 15, 16], quick: [12] };

// The files of one input: segmorph's and the gltfpack anchor's, measured. { segmorph, gltfpack } or { failed }.
function files(tools, input, dir, quick) {
  mkdirSync(dir, { recursive: true });
  const local = (name) => path.join(dir, name);
  const encoded = local('segmorph.glb');
  if (!tools.run(local('segmorph.log'), 'segmorph', ['encode', '-q', input, '-o', encoded, '--error', String(SPEED_ERROR)]).ok)
    return { failed: `segmorph encode failed (${local('segmorph.log')})` };
  const report = tools.verify(local('segmorph.verify.log'), input, encoded);
  if (!report) return { failed: `segmorph verify failed (${local('segmorph.verify.log')})` };
  const segmorph = { file: encoded, kg: report.kg_percent, vertex_frames: report.vertex_frames, ...deliveredBytes(encoded) };
  // gltfpack: the file smallest after brotli whose KG is at most segmorph's (else the one of lowest KG, said so).
  const candidates = [];
  for (const bits of GLTFPACK_BITS[quick ? 'quick' : 'full']) {
    const name = `gltfpack-vp${bits}`;
    if (!tools.run(local(`${name}.log`), 'gltfpack', ['-i', input, '-o', local(`${name}.glb`), '-cc', '-af', '0', '-vp', String(bits)]).ok) continue;
    if (!tools.run(local(`${name}.plain.log`), 'meshopt_decode', [local(`${name}.glb`), local(`${name}.plain.glb`)]).ok) continue;
    const measured = tools.verify(local(`${name}.verify.log`), input, local(`${name}.plain.glb`));
    if (measured) candidates.push({ file: local(`${name}.glb`), setting: `-cc -af 0 -vp ${bits}`, kg: measured.kg_percent });
  }
  if (candidates.length === 0) return { failed: `gltfpack failed at every -vp (${dir})` };
  const delivered = (c) => ({ ...c, ...deliveredBytes(c.file) });
  const equal = candidates.filter((c) => c.kg <= segmorph.kg).map(delivered);
  const anchor = equal.length ? equal.reduce((a, b) => (b.brotli < a.brotli ? b : a))
                              : delivered(candidates.reduce((a, b) => (b.kg < a.kg ? b : a)));
  return { segmorph, gltfpack: { ...anchor, kg_higher: equal.length === 0 } };
}

// Every input's files, then their load times in one Chromium page. { inputs: [{ label, segmorph, gltfpack }] }.
export async function measureBrowser(tools, inputs, dir, quick) {
  const measured = inputs.map(({ label, file }, i) => {
    progress(`browser ${i + 1}/${inputs.length}: ${label}: encoding and gltfpack's sweep`);
    return { label, ...files(tools, file, path.join(dir, `${i + 1}-${path.basename(file).replace(/\.(glb|gltf)$/i, '')}`), quick) };
  });
  const server = await serve({ web: path.join(tools.paths.segmorph, '..', '..', 'web'), three: tools.paths.three,
                               roots: { '/bench/': path.join(tools.root, 'bench', 'browser'), '/files/': dir } });
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium', headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
           '--disable-sync', '--no-first-run'],
  });
  try {
    const page = await browser.newPage();
    page.setDefaultTimeout(600000);
    await page.goto(`http://127.0.0.1:${server.address().port}/bench/index.html`);
    await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
    const repeats = quick ? 1 : 5;
    for (const input of measured) {
      if (input.failed) continue;
      for (const kind of ['segmorph', 'gltfpack']) {
        const url = `/files/${path.relative(dir, input[kind].file)}`;
        input[kind].browser = await page.evaluate(([u, k, r]) => window.measure(u, k, r), [url, kind, repeats]);
      }
      const s = input.segmorph.browser, g = input.gltfpack.browser;
      progress(`  ${input.label}: segmorph ${s.median.toFixed(1)} ms (first ${s.first.toFixed(1)}), gltfpack ${g.median.toFixed(1)} ms (first ${g.first.toFixed(1)})`);
    }
    return { inputs: measured, repeats, chromium: browser.version() };
  } finally {
    await browser.close();
    server.close();
  }
}
