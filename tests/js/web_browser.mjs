// segmorph's web package in a real browser (ctest web_browser): headless Chromium (Debian's /usr/bin/chromium, driven
// by playwright-core; no browser download) against web/serve.mjs on 127.0.0.1.
//   1. Every sample (and, when present, every shared sample and sequence) encoded by segmorph in several modes; the
//      page (web_pages/compare.js) loads each with GLTFLoader and the plugin, plays every clip with AnimationMixer and
//      reads the positions three.js computes at every frame time with { playback: 'morph' } (GPU playback, the
//      default, is web_gpu.mjs's); they must equal those of the file segmorph decode
//      wrote, loaded without the plugin, within three's own float arithmetic (1e-5 of the scene's diagonal), and so
//      must the normals three.js shades with (within NORMAL_TOLERANCE_DEGREES: the decoded file stores each frame's
//      normals as a difference from the base's, one rounding). Also with the plugin's streaming playback and with
//      workers.
//   2. A damaged and a truncated stream make the loader's promise reject with a message naming the extension, without
//      a hang or a crashed page.
//   3. The viewer (web/viewer) plays a compressed file dropped on it: its render is not empty and changes between two
//      times, and it shows the GPU bytes and how the file plays (on the GPU for the cow).
//
//   node tests/js/web_browser.mjs SEGMORPH WEB_DIR WORK_DIR SAMPLES_DIR SHARED_SAMPLES_DIR
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, rmSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

import { inputsUnder, launchChromium, openTestPage } from './chromium.mjs';
import { readAsset, writeHostileStreams } from './glb.mjs';
import { serve } from '../../web/serve.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [segmorph, webDir, work, samples, shared] = process.argv.slice(2);
if (!shared) {
  console.error('usage: node tests/js/web_browser.mjs SEGMORPH WEB_DIR WORK_DIR SAMPLES_DIR SHARED_SAMPLES_DIR');
  process.exit(2);
}
rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
const RELATIVE_TOLERANCE = 1e-5;
// The decoded file holds each frame's normals as a difference from the base's (one float rounding, about 3e-6 degrees).
const NORMAL_TOLERANCE_DEGREES = 1e-4;
let failures = 0;
const fail = (message) => { console.error(`web_browser: FAIL: ${message}`); failures += 1; };
const log = (message) => console.log(`web_browser: ${message}`);

const inputs = [...inputsUnder(samples), ...inputsUnder(path.join(shared, 'gltf')), ...inputsUnder(path.join(shared, 'sequences'))]
  .filter((f) => !f.includes('MorphPrimitivesTest'));
if (!existsSync(shared)) log(`${shared} is absent: the shared samples and sequences are skipped`);

// Each input encoded by default; some in other modes too: kept targets, baked skins in the table code, lossless.
const cases = [];
for (const input of inputs) {
  const name = path.basename(input).replace(/\.(glb|gltf)$/, '');
  const variants = [['default', []]];
  if (/AnimatedMorphCube|MorphStressTest/.test(input)) variants.push(['keep-targets', ['--targets', 'keep']]);
  if (/Fox|RiggedSimple|CesiumMan/.test(input)) variants.push(['bake-fast', ['--skins', 'bake', '--fast-decode']]);
  if (/SimpleMorph|SimpleSkin/.test(input)) variants.push(['lossless', ['--lossless']]);
  for (const [variant, options] of variants) {
    const encoded = path.join(work, `${name}.${variant}.glb`), decoded = path.join(work, `${name}.${variant}.decoded.glb`);
    execFileSync(segmorph, ['encode', '-q', input, '-o', encoded, ...options]);
    execFileSync(segmorph, ['decode', '-q', encoded, '-o', decoded]);
    cases.push({ label: `${name} ${variant}`, encoded: path.basename(encoded), decoded: path.basename(decoded) });
  }
}

// Damaged files: the cube's stream with its second half zeroed, and with its bufferView cut short.
writeHostileStreams(await readAsset(path.join(work, 'AnimatedMorphCube.default.glb')), work);

const server = await serve({ web: webDir, roots: { '/pages/': path.join(here, 'web_pages'), '/files/': work } });
const origin = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
try {
  const { page, consoleErrors } = await openTestPage(browser, `${origin}/pages/compare.html`);

  // 1. Every case, and the cow (or the first clip file) streamed and in workers.
  // Morph targets (GPU playback, the default, is tested in web_gpu.mjs: its positions are not on the CPU).
  const runs = cases.map((c) => ({ ...c, options: { playback: 'morph' } }));
  const clipCase = cases.find((c) => c.label === 'cow default') ?? cases.find((c) => c.label === 'Fox bake-fast');
  runs.push({ ...clipCase, label: `${clipCase.label}, streaming`, options: { streaming: true } });
  runs.push({ ...clipCase, label: `${clipCase.label}, 2 workers`, options: { workers: 2, playback: 'morph' } });
  let frames = 0;
  for (const run of runs) {
    try {
      const result = await page.evaluate(([a, b, options]) => window.compare(a, b, options),
                                         [`/files/${run.encoded}`, `/files/${run.decoded}`, run.options]);
      const relative = result.maxError / Math.max(result.diagonal, 1e-30);
      frames += result.frames;
      const line = `${run.label}: ${result.meshes} meshes, ${result.clips.length} clips, ${result.frames} frame times, ` +
                   `largest difference ${result.maxError.toExponential(2)} (${relative.toExponential(2)} of the diagonal), ` +
                   `loaded in ${result.loadMilliseconds.toFixed(0)} ms`;
      const normals = result.normalsCompared > 0
        ? `, normals within ${result.maxNormalDegrees.toExponential(2)} degrees over ${result.normalsCompared} mesh-frames` : '';
      if (relative > RELATIVE_TOLERANCE || result.frames === 0 || result.maxNormalDegrees > NORMAL_TOLERANCE_DEGREES)
        fail(line + normals);
      else log(line + normals);
    } catch (error) {
      fail(`${run.label}: ${error.message.split('\n')[0]}`);
    }
  }

  // 2. Damaged streams: a rejected promise naming the extension, in bounded time.
  for (const file of ['damaged.glb', 'truncated.glb']) {
    const message = await Promise.race([
      page.evaluate((url) => window.loadError(url), `/files/${file}`),
      new Promise((resolve) => setTimeout(() => resolve('timeout'), 60000)),
    ]);
    if (message === null) fail(`${file} loaded`);
    else if (message === 'timeout') fail(`${file}: no answer in 60 s`);
    else if (!message.includes('SEGMORPH_animation_compression') || !/bad data/.test(message)) fail(`${file}: ${message}`);
    else log(`${file} refused: ${message}`);
  }
  const alive = await page.evaluate(() => 1 + 1);
  if (alive !== 2) fail('the page did not survive the damaged files');

  // 3. The viewer: a non-empty render that changes between two times.
  const viewer = await browser.newPage({ viewport: { width: 640, height: 480 } });
  viewer.on('pageerror', (error) => consoleErrors.push(`viewer: ${error.message}`));
  await viewer.goto(`${origin}/viewer/`);
  await viewer.waitForFunction(() => window.viewer !== undefined, null, { timeout: 60000 });
  const shown = await viewer.evaluate(async (url) => {
    // Dropped on the page, as a user drops a file.
    const bytes = await (await fetch(url)).arrayBuffer();
    const transfer = new DataTransfer();
    transfer.items.add(new File([bytes], 'dropped.glb'));
    window.dispatchEvent(new DragEvent('drop', { dataTransfer: transfer, bubbles: true, cancelable: true }));
    for (let waited = 0; !window.viewer.state.action && waited < 60000; waited += 50)
      await new Promise((resolve) => setTimeout(resolve, 50));
    if (!window.viewer.state.action) return { error: document.getElementById('facts').textContent };
    const facts = window.viewer.state.facts;
    document.getElementById('play').click();  // pause, as a user would
    const frame = () => new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
    const pixels = () => {
      const canvas = document.createElement('canvas');
      canvas.width = 64, canvas.height = 48;
      const context = canvas.getContext('2d');
      context.drawImage(window.viewer.renderer.domElement, 0, 0, 64, 48);
      return Array.from(context.getImageData(0, 0, 64, 48).data);
    };
    const duration = window.viewer.state.action.getClip().duration;
    window.viewer.setTime(0);
    await frame();
    const a = pixels();
    window.viewer.setTime(duration * 0.5);
    await frame();
    const b = pixels();
    const background = [a[0], a[1], a[2]];
    let covered = 0, changed = 0;
    for (let i = 0; i < a.length; i += 4) {
      if (Math.abs(a[i] - background[0]) + Math.abs(a[i + 1] - background[1]) + Math.abs(a[i + 2] - background[2]) > 12) covered += 1;
      if (Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 12) changed += 1;
    }
    return { covered, changed, pixels: a.length / 4, facts, text: document.getElementById('facts').textContent };
  }, `/files/${clipCase.encoded}`);
  if (shown.error) fail(`viewer: the dropped file did not play: ${shown.error}`);
  await viewer.screenshot({ path: path.join(work, 'viewer.png') });
  const viewerLine = `viewer: ${shown.text}; ${shown.covered} of ${shown.pixels} pixels show the model, ${shown.changed} change ` +
                     `from time 0 to half the clip (screenshot ${path.join(work, 'viewer.png')})`;
  // It says what the file takes on the GPU and how it plays (the cow's version-4 stream: on the GPU).
  const playsOnGpu = clipCase.label === 'cow default';
  if (shown.covered < shown.pixels * 0.005 || shown.changed === 0 || !/GPU [0-9.]+ MB/.test(shown.text ?? '') ||
      (playsOnGpu && !/on the GPU/.test(shown.text))) fail(viewerLine);
  else log(viewerLine);

  const unexpected = consoleErrors.filter((text) => !/SEGMORPH_animation_compression/.test(text));
  if (unexpected.length) fail(`console errors: ${unexpected.slice(0, 5).join(' | ')}`);
  log(`${runs.length} loads compared over ${frames} frame times`);
} finally {
  await browser.close();
  server.close();
}
if (failures) console.error(`web_browser: ${failures} failed`);
process.exit(failures === 0 ? 0 : 1);
