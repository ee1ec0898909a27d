// segmorph/babylon in a real browser (ctest web_babylon): headless Chromium (Debian's /usr/bin/chromium, SwiftShader's
// WebGL 2, driven by playwright-core) against web/serve.mjs on 127.0.0.1, Babylon.js 9 from tests/js/node_modules.
//   1. Every sample (and, when present, every shared sample and sequence) encoded by default and with
//      --targets bake --skins bake (every animated primitive then plays clips), and decoded by segmorph decode. The
//      page (web_pages/babylon.js) loads each file with Babylon's glTF loader, the compressed one through the
//      extension (its default: version-4 streams of clips on the GPU, from their model): the pictures at frame times
//      and between them (lit, with a shadow on a ground) match, and so do the positions within 1e-5 of the diagonal
//      (Babylon's CPU evaluation of morph targets and skins; a GPU-played mesh's shape texture read back), also in a
//      cross-fade of two animation groups; every version-4 stream of clips plays on the GPU (and, with { playback:
//      'morph' }, the first file with one plays as morph targets; the first sequence also with a StandardMaterial
//      given after the load, through its player); on the shared sequences the GPU bytes of the load and first frame
//      are at most a fifth of the decoded file's.
//   2. A damaged and a truncated stream make the load reject with a message naming the extension and the primitive.
//   3. The example page (examples/babylon) plays the cow (without the shared samples, the baked fox) on the GPU, and
//      its picture moves.
//
//   node tests/js/web_babylon.mjs SEGMORPH WEB_DIR WORK_DIR SAMPLES_DIR SHARED_SAMPLES_DIR
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
  console.error('usage: node tests/js/web_babylon.mjs SEGMORPH WEB_DIR WORK_DIR SAMPLES_DIR SHARED_SAMPLES_DIR');
  process.exit(2);
}
rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
// Positions: both files' morph targets (and skins) evaluated by Babylon in float32, relative to the diagonal.
const POSITION_TOLERANCE = 1e-5;
// Pictures (160 x 120, no antialiasing): the share of pixels whose largest channel differs by more than 24 of 255
// (an edge pixel flips where float rounding moves a silhouette); the control (the decoded file a third of a group
// later, in the group that moves most) must differ on more than four times as many.
const PICTURE_TOLERANCE = 0.02;
let failures = 0;
const fail = (message) => { console.error(`web_babylon: FAIL: ${message}`); failures += 1; };
const log = (message) => console.log(`web_babylon: ${message}`);

const sequences = inputsUnder(path.join(shared, 'sequences'));
const inputs = [...inputsUnder(samples), ...inputsUnder(path.join(shared, 'gltf')), ...sequences]
  .filter((f) => !f.includes('MorphPrimitivesTest'));
if (!existsSync(shared)) log(`${shared} is absent: the shared samples and sequences are skipped`);

const cases = [];
for (const input of inputs) {
  const name = path.basename(input).replace(/\.(glb|gltf)$/, '');
  for (const [variant, options] of [['default', []], ['bake', ['--targets', 'bake', '--skins', 'bake']]]) {
    const encoded = path.join(work, `${name}.${variant}.glb`), decoded = path.join(work, `${name}.${variant}.decoded.glb`);
    execFileSync(segmorph, ['encode', '-q', input, '-o', encoded, ...options], { stdio: ['ignore', 'ignore', 'inherit'] });
    execFileSync(segmorph, ['decode', '-q', encoded, '-o', decoded]);
    const asset = await readAsset(encoded);
    const versions = (asset.json.meshes ?? []).flatMap((m) => m.primitives)
      .filter((p) => p.extensions?.SEGMORPH_animation_compression && !p.extensions.SEGMORPH_animation_compression.morphTargets)
      .map((p) => {
        const view = asset.json.bufferViews[p.extensions.SEGMORPH_animation_compression.bufferView];
        return asset.buffers[view.buffer ?? 0][(view.byteOffset ?? 0) + 4];
      });
    cases.push({ label: `${name} ${variant}`, encoded: path.basename(encoded), decoded: path.basename(decoded), versions,
                 sequence: sequences.includes(input), asset });
  }
}

// Hostile files: a stream of clips with its second half zeroed, and cut short.
const victim = cases.find((c) => c.label === 'flag bake') ?? cases.find((c) => c.versions.length > 0);
writeHostileStreams(victim.asset, work);

const server = await serve({ web: webDir, roots: { '/pages/': path.join(here, 'web_pages'), '/files/': work,
                                                  '/example/': path.join(here, '..', '..', 'examples', 'babylon') } });
const origin = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
const megabytes = (bytes) => `${(bytes / 1e6).toFixed(2)} MB`;
try {
  const { page, consoleErrors } = await openTestPage(browser, `${origin}/pages/babylon.html`);

  // Every case at the extension's defaults, and the first with a version-4 stream also as morph targets.
  const morph = cases.find((c) => c.versions.includes(4));
  // and the first with a version-4 stream of the shared sequences (else of all) with a StandardMaterial given after the
  // load.
  const standard = cases.find((c) => c.sequence && c.versions.includes(4)) ?? morph;
  const runs = [...cases, ...(morph ? [{ ...morph, label: `${morph.label}, playback 'morph'`, options: { playback: 'morph' } }] : []),
                ...(standard ? [{ ...standard, label: `${standard.label}, StandardMaterial`, options: { standardMaterial: true } }] : [])];
  for (const c of runs) {
    try {
      const r = await page.evaluate(([a, b, options]) => window.babylonCase(a, b, options),
                                    [`/files/${c.encoded}`, `/files/${c.decoded}`, c.options ?? null]);
      const problems = [];
      const relative = r.worstPosition / Math.max(r.diagonal, 1e-30);
      // Every version-4 stream of clips on the GPU, the others as morph targets; on the sequences the GPU takes at most
      // a fifth of the decoded file's morph targets.
      const gpu = r.playbacks.filter((p) => p.mode === 'gpu').length;
      const expected = c.options?.playback === 'morph' ? 0 : c.versions.filter((v) => v === 4).length;
      if (r.playbacks.length < c.versions.length || gpu !== expected)
        problems.push(`${gpu} of ${r.playbacks.length} meshes play on the GPU, ${expected} of ${c.versions.length} streams of clips have version 4`);
      if (c.sequence && !c.options && !(r.bytes.compressed <= r.bytes.decoded / 5))
        problems.push(`GPU bytes ${megabytes(r.bytes.compressed)}, more than a fifth of the decoded file's ${megabytes(r.bytes.decoded)}`);
      if (!(relative <= POSITION_TOLERANCE)) problems.push(`positions differ by ${relative.toExponential(2)} of the diagonal (${JSON.stringify(r.worstAt)})`);
      if (!(r.worstPicture <= PICTURE_TOLERANCE)) problems.push(`pictures differ on ${(r.worstPicture * 100).toFixed(2)} % of pixels`);
      if (r.leftInScene.length) problems.push(`removeAllFromScene left ${r.leftInScene.join(', ')} in the scene`);
      if (r.pictures > 0 && !(r.control > 0)) problems.push('the control sees no motion');
      if (r.worstPicture > 0 && !(r.control > 4 * r.worstPicture))
        problems.push(`the control differs on only ${(r.control * 100).toFixed(2)} % of pixels`);
      const line = `${c.label}: ${r.groups} animation groups, ${r.frames} times${r.crossFade ? ' and a cross-fade' : ''}, ` +
        `${r.pictures} pictures (worst ${(r.worstPicture * 100).toFixed(2)} % of pixels, control ${(r.control * 100).toFixed(1)} %), ` +
        `positions within ${relative.toExponential(2)} of the diagonal over ${r.positions} mesh poses; ` +
        `${r.playbacks.map((p) => `${p.mode} v${p.version}`).join(', ') || 'no clip primitive'}; GPU bytes ${megabytes(r.bytes.compressed)} ` +
        `(decoded file ${megabytes(r.bytes.decoded)}); loaded in ${r.loadMilliseconds.toFixed(0)} ms`;
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
    else if (answer === null) fail(`${file} loaded`);
    else if (!/SEGMORPH_animation_compression: mesh \d+ primitive \d+/.test(answer) || !/bad data/.test(answer)) fail(`${file}: ${answer}`);
    else log(`${file} (${victim.label}) refused: ${answer}`);
  }
  // 3. The example page (examples/babylon) plays a compressed file: on the GPU, and its picture moves.
  const shown = cases.find((c) => c.label === 'cow default') ?? cases.find((c) => c.versions.includes(4));
  const example = await browser.newPage({ viewport: { width: 320, height: 240 } });
  await example.goto(`${origin}/example/?file=/files/${shown.encoded}`);
  const facts = await example.evaluate(() => window.example.loaded);
  const first = await example.screenshot();
  await new Promise((resolve) => setTimeout(resolve, 700));
  const later = await example.screenshot();
  const exampleLine = `example page: ${facts.error ?? facts.text}`;
  if (facts.error || facts.groups === 0 || !facts.modes.includes('gpu') || first.equals(later)) fail(`${exampleLine} (its picture ${first.equals(later) ? 'does not move' : 'moves'})`);
  else log(`${exampleLine}; its picture moves`);
  await example.close();

  const unexpected = consoleErrors.filter((text) => !/SEGMORPH_animation_compression/.test(text));
  if (unexpected.length) fail(`console errors: ${unexpected.slice(0, 5).join(' | ')}`);
  log(`${cases.length} files played in Babylon.js and compared`);
} finally {
  await browser.close();
  server.close();
}
if (failures) console.error(`web_babylon: ${failures} failed`);
process.exit(failures === 0 ? 0 : 1);
