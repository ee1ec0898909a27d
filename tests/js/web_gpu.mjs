// The three.js plugin's GPU playback in a real browser (ctest web_gpu): headless Chromium (Debian's /usr/bin/chromium,
// SwiftShader's WebGL 2, driven by playwright-core) against web/serve.mjs on 127.0.0.1.
//   1. Every sample (and, when present, every shared sample and sequence) encoded by default and with
//      --gpu-playable --targets bake --skins bake (so that every one has clip streams of version 4), and decoded by
//      segmorph decode. The page (web_pages/gpu.js) plays each with the plugin's default and the decoded file with
//      plain GLTFLoader: the pictures at frame times and between them match; the positions read back from the GPU
//      match the float32 CPU reference within 1e-5 of the diagonal and the decoded file's within 1e-5; a cross-fade
//      between two clips matches the decoded file's; the shadow matches, moves and is there; every version-4 clip
//      primitive plays on the GPU, others as morph targets.
//   2. GPU bytes (WebGL's allocation calls counted): GPU playback, { playback: 'morph' }, the decoded file; on the
//      shared sequences the GPU playback takes at most 1/5 of the morph targets'.
//   3. Damaged and truncated version-4 streams reject the load with a message naming the extension, allocating
//      nothing on the GPU.
//
//   node tests/js/web_gpu.mjs SEGMORPH WEB_DIR WORK_DIR SAMPLES_DIR SHARED_SAMPLES_DIR
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
  console.error('usage: node tests/js/web_gpu.mjs SEGMORPH WEB_DIR WORK_DIR SAMPLES_DIR SHARED_SAMPLES_DIR');
  process.exit(2);
}
rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
// Positions: GPU against the CPU float32 reference, and against the decoded file (its morph targets, blended by
// three.js's arithmetic here in double), relative to the diagonal of the model's bounds.
const POSITION_TOLERANCE = 1e-5;
// Pictures (160 x 120, no antialiasing): the share of pixels whose largest channel differs by more than 24 of 255.
// GPU playback turns the normals by the surface around each vertex evaluated in float32 on the GPU, the decoded file
// by the same rule in double (a few vertices whose triangles nearly cancel differ by more, docs/runtime.md), and a
// silhouette moved by float rounding flips an edge pixel; the control (the decoded file a third of a clip later) must
// differ on more than four times as many pixels.
const PICTURE_TOLERANCE = 0.02;
const SHARE_OF_MORPH = 1 / 5;
let failures = 0;
const fail = (message) => { console.error(`web_gpu: FAIL: ${message}`); failures += 1; };
const log = (message) => console.log(`web_gpu: ${message}`);

const sequences = inputsUnder(path.join(shared, 'sequences'));
const inputs = [...inputsUnder(samples), ...inputsUnder(path.join(shared, 'gltf')), ...sequences]
  .filter((f) => !f.includes('MorphPrimitivesTest'));
if (!existsSync(shared)) log(`${shared} is absent: the shared samples and sequences are skipped`);

const cases = [];
for (const input of inputs) {
  const name = path.basename(input).replace(/\.(glb|gltf)$/, '');
  for (const [variant, options] of [['default', []], ['gpu-bake', ['--gpu-playable', '--targets', 'bake', '--skins', 'bake']]]) {
    const encoded = path.join(work, `${name}.${variant}.glb`), decoded = path.join(work, `${name}.${variant}.decoded.glb`);
    execFileSync(segmorph, ['encode', '-q', input, '-o', encoded, ...options], { stdio: ['ignore', 'ignore', 'inherit'] });
    execFileSync(segmorph, ['decode', '-q', encoded, '-o', decoded]);
    const asset = await readAsset(encoded);
    const versions = [];
    for (const mesh of asset.json.meshes ?? [])
      for (const primitive of mesh.primitives) {
        const extension = primitive.extensions?.SEGMORPH_animation_compression;
        if (!extension) continue;
        const view = asset.json.bufferViews[extension.bufferView];
        versions.push({ version: asset.buffers[view.buffer][(view.byteOffset ?? 0) + 4], kept: extension.morphTargets === true });
      }
    // Skinned files keep their skins by default: no stream, nothing for GPU playback to do.
    if (variant === 'default' && !versions.some((v) => !v.kept)) continue;
    cases.push({ label: `${name} ${variant}`, encoded: path.basename(encoded), decoded: path.basename(decoded), versions,
                 sequence: sequences.includes(input), input, asset });
  }
}

// Hostile files: a version-4 stream with its second half zeroed, and cut short.
const victim = cases.find((c) => c.label.startsWith('flag gpu-bake')) ?? cases.find((c) => c.versions.some((v) => v.version === 4));
writeHostileStreams(victim.asset, work);

const server = await serve({ web: webDir, roots: { '/pages/': path.join(here, 'web_pages'), '/files/': work } });
const origin = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
const megabytes = (bytes) => `${(bytes / 1e6).toFixed(2)} MB`;
try {
  const { page, consoleErrors } = await openTestPage(browser, `${origin}/pages/gpu.html`);

  for (const c of cases) {
    try {
      const r = await page.evaluate(([a, b]) => window.gpuCase(a, b), [`/files/${c.encoded}`, `/files/${c.decoded}`]);
      const problems = [];
      // Every version-4 clip primitive on the GPU, every other clip primitive as morph targets.
      const clipStreams = c.versions.filter((v) => !v.kept);
      const expectedGpu = clipStreams.filter((v) => v.version === 4).length;
      const played = r.playbacks.filter((p) => p.mode === 'gpu').length;
      if (played !== expectedGpu || r.playbacks.length !== clipStreams.length)
        problems.push(`${played} of ${r.playbacks.length} clip primitives on the GPU, ${expectedGpu} of ${clipStreams.length} have version 4`);
      if (c.label.includes('gpu-bake') && expectedGpu !== clipStreams.length) problems.push('--gpu-playable wrote a stream below version 4');
      const relative = (x) => x / Math.max(r.diagonal, 1e-30);
      if (r.gpuMeshes > 0) {
        if (!(relative(r.gpuReference) <= POSITION_TOLERANCE)) problems.push(`GPU vs CPU reference ${relative(r.gpuReference).toExponential(2)}`);
        if (!(relative(r.gpuDecoded) <= POSITION_TOLERANCE)) problems.push(`GPU vs decoded ${relative(r.gpuDecoded).toExponential(2)}`);
      }
      if (!(r.worstPicture <= PICTURE_TOLERANCE)) problems.push(`pictures differ on ${(r.worstPicture * 100).toFixed(2)} % of pixels`);
      if (r.control !== 1 && r.worstPicture > 0 && !(r.control > 4 * r.worstPicture))
        problems.push(`the control differs on only ${(r.control * 100).toFixed(2)} % of pixels`);
      if (r.shadow && r.gpuMeshes > 0) {
        if (!(r.shadow.matches <= PICTURE_TOLERANCE)) problems.push(`shadows differ on ${(r.shadow.matches * 100).toFixed(2)} % of pixels`);
        if (!(r.shadow.present > 0)) problems.push('no shadow');
      }
      if (r.crossFade) {
        if (!(relative(r.crossFade.gpuDecoded) <= POSITION_TOLERANCE)) problems.push(`cross-fade vs decoded ${relative(r.crossFade.gpuDecoded).toExponential(2)}`);
        if (!(r.crossFade.worstPicture <= PICTURE_TOLERANCE)) problems.push(`cross-fade pictures differ on ${(r.crossFade.worstPicture * 100).toFixed(2)} %`);
      }
      const { gpu, morph, decoded } = r.bytes;
      if (c.sequence && !(gpu.allocated <= morph.allocated * SHARE_OF_MORPH))
        problems.push(`GPU playback allocates ${megabytes(gpu.allocated)}, more than 1/5 of the morph targets' ${megabytes(morph.allocated)}`);
      const angles = r.normals.count ? `, normals within ${r.normals.largestDegrees.toFixed(2)} deg of the decoded file's (mean ${(r.normals.sumDegrees / r.normals.count).toFixed(3)})` : '';
      const line = `${c.label}: ${r.gpuMeshes} GPU meshes of ${r.meshes}, ${r.frames} times, ${r.pictures} pictures ` +
        `(worst ${(r.worstPicture * 100).toFixed(2)} % of pixels, control ${(r.control * 100).toFixed(1)} %), GPU vs CPU float32 ` +
        `${relative(r.gpuReference).toExponential(2)}, vs decoded ${relative(r.gpuDecoded).toExponential(2)} of the diagonal${angles}` +
        `${r.crossFade ? `, cross-fade ${relative(r.crossFade.gpuDecoded).toExponential(2)} over ${r.crossFade.frames} steps` : ''}` +
        `${r.shadow ? `, shadow on ${(r.shadow.present * 100).toFixed(2)} % of pixels, ${(r.shadow.matches * 100).toFixed(2)} % apart, moves on ${(r.shadow.moves * 100).toFixed(2)} %` : ''}; ` +
        `GPU bytes: gpu ${megabytes(gpu.allocated)} (${gpu.uploaded} B uploaded per frame), morph ${megabytes(morph.allocated)} ` +
        `(${(morph.allocated / Math.max(gpu.allocated, 1)).toFixed(1)}x), decoded file ${megabytes(decoded.allocated)}; loaded in ${r.loadMilliseconds.toFixed(0)} ms`;
      if (problems.length) fail(`${line}: ${problems.join('; ')}`);
      else log(line);
    } catch (error) {
      fail(`${c.label}: ${error.message.split('\n')[0]}`);
    }
  }

  for (const file of ['damaged.glb', 'truncated.glb']) {
    const answer = await Promise.race([
      page.evaluate((url) => window.loadError(url), `/files/${file}`),
      new Promise((resolve) => setTimeout(() => resolve('timeout'), 60000)),
    ]);
    if (answer === 'timeout') fail(`${file}: no answer in 60 s`);
    else if (answer.message === null) fail(`${file} loaded`);
    else if (!answer.message.includes('SEGMORPH_animation_compression') || !/bad data/.test(answer.message)) fail(`${file}: ${answer.message}`);
    else if (answer.allocated !== 0) fail(`${file}: refused after allocating ${answer.allocated} GPU bytes`);
    else log(`${file} (${victim.label}) refused, no GPU bytes allocated: ${answer.message}`);
  }
  const unexpected = consoleErrors.filter((text) => !/SEGMORPH_animation_compression/.test(text));
  if (unexpected.length) fail(`console errors: ${unexpected.slice(0, 5).join(' | ')}`);
  log(`${cases.length} files played on the GPU and compared`);
} finally {
  await browser.close();
  server.close();
}
if (failures) console.error(`web_gpu: ${failures} failed`);
process.exit(failures === 0 ? 0 : 1);
