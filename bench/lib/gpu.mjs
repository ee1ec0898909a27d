// The GPU part: what playing a sequence costs a page, segmorph's model on the GPU (the plugin's default playback)
// against the same file played as morph targets ({ playback: 'morph' }) and against gltfpack's file (morph targets,
// MeshoptDecoder). For each sequence: segmorph encode --error SPEED_ERROR and gltfpack -cc -af 0 -vp
// SPEED_GLTFPACK_BITS; then in headless Chromium (software rendering: SwiftShader's WebGL 2), per file and mode:
// the GPU bytes its load and first frame allocate (WebGL's allocation calls counted, web/gpu_bytes.js), the time
// from the bytes to the first drawn frame, and per frame (the mixer at a new time, the scene drawn, the drawing
// waited for) the CPU time of the render call and the whole frame's, with the bytes uploaded per frame. Then one
// large cache (bench/codec_scaling's torus, V x F): encoded from its OBJ + PC2 cache, played on the GPU; its morph
// targets are not loaded (their size as three.js would allocate them, V x F x 16 bytes, twice that with normals, is
// computed and said so).
import { mkdirSync, rmSync } from 'node:fs';
import path from 'node:path';
import { launchChromium } from '../../tests/js/chromium.mjs';
import { readAsset } from '../../tests/js/glb.mjs';
import { serve } from '../../web/serve.mjs';
import { SPEED_ERROR, SPEED_GLTFPACK_BITS } from './speed.mjs';
import { deliveredBytes, fileBytes, progress } from './tools.mjs';

export const GPU = {
  full: { repeats: 5, frames: 60, torus: { vertices: 200000, frames: 300 } },
  quick: { repeats: 1, frames: 4, torus: { vertices: 2000, frames: 10 } },
};

// The files of one sequence: { segmorph, gltfpack } (paths and bytes) or { failed }.
function files(tools, input, dir) {
  mkdirSync(dir, { recursive: true });
  const encoded = path.join(dir, 'segmorph.glb'), packed = path.join(dir, 'gltfpack.glb');
  if (!tools.run(path.join(dir, 'segmorph.log'), 'segmorph', ['encode', '-q', input, '-o', encoded, '--error', String(SPEED_ERROR)]).ok)
    return { failed: `segmorph encode failed (${path.join(dir, 'segmorph.log')})` };
  if (!tools.run(path.join(dir, 'gltfpack.log'), 'gltfpack',
                 ['-i', input, '-o', packed, '-cc', '-af', '0', '-vp', String(SPEED_GLTFPACK_BITS)]).ok)
    return { failed: `gltfpack failed (${path.join(dir, 'gltfpack.log')})` };
  return { segmorph: { file: encoded, ...deliveredBytes(encoded) }, gltfpack: { file: packed, ...deliveredBytes(packed) } };
}

// The large cache, encoded from its vertex cache: { file, bytes, vertices, frames } or { failed }.
function torus(tools, plan, dir) {
  mkdirSync(dir, { recursive: true });
  const prefix = path.join(dir, 'torus'), encoded = path.join(dir, 'torus.glb');
  const { vertices, frames } = plan.torus;
  if (!tools.run(path.join(dir, 'write.log'), 'codec_scaling',
                 ['--vertices', String(vertices), '--frames', String(frames), '--write-cache', prefix]).ok)
    return { failed: `codec_scaling --write-cache failed (${path.join(dir, 'write.log')})` };
  progress(`gpu: encoding the ${vertices} x ${frames} torus (minutes for the largest)`);
  if (!tools.run(path.join(dir, 'encode.log'), 'segmorph',
                 ['encode', '-q', `${prefix}.obj`, '--cache', `${prefix}.pc2`, '-o', encoded, '--error', String(SPEED_ERROR)]).ok)
    return { failed: `segmorph encode failed (${path.join(dir, 'encode.log')})` };
  rmSync(`${prefix}.pc2`, { force: true });
  return { file: encoded, bytes: fileBytes(encoded), vertices, frames };
}

// Every sequence's files and the torus, then their playback in one Chromium page.
export async function measureGpu(tools, inputs, dir, plan) {
  const measured = inputs.map(({ label, file }, i) => {
    progress(`gpu ${i + 1}/${inputs.length}: ${label}: encoding and gltfpack`);
    return { label, ...files(tools, file, path.join(dir, `${i + 1}-${path.basename(file).replace(/\.(glb|gltf)$/i, '')}`)) };
  });
  const large = torus(tools, plan, path.join(dir, 'torus'));
  const server = await serve({ web: path.join(tools.paths.segmorph, '..', '..', 'web'), three: tools.paths.three,
                               roots: { '/bench/': path.join(tools.root, 'bench', 'browser'), '/files/': dir } });
  const browser = await launchChromium();
  try {
    const page = await browser.newPage();
    page.setDefaultTimeout(1800000);
    await page.goto(`http://127.0.0.1:${server.address().port}/bench/gpu.html`);
    await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
    const play = (file, mode) => page.evaluate(([u, m, r, f]) => window.measurePlayback(u, m, r, f),
                                               [`/files/${path.relative(dir, file)}`, mode, plan.repeats, plan.frames]);
    for (const input of measured) {
      if (input.failed) continue;
      input.playback = {
        gpu: await play(input.segmorph.file, 'gpu'),
        morph: await play(input.segmorph.file, 'morph'),
        gltfpack: await play(input.gltfpack.file, 'gltfpack'),
      };
      const { gpu, morph, gltfpack } = input.playback;
      progress(`  ${input.label}: GPU bytes ${gpu.allocated} (model), ${morph.allocated} (morph), ${gltfpack.allocated} (gltfpack)`);
    }
    if (!large.failed) {
      large.playback = { gpu: await play(large.file, 'gpu') };
      // As three.js stores morph targets: a vec4 of floats per vertex and frame, and as much again for normals.
      const asset = await readAsset(large.file);
      large.normals = (asset.json.meshes ?? []).some((m) => m.primitives.some((p) => p.attributes.NORMAL !== undefined));
      large.morph_bytes_computed = large.vertices * large.frames * 16 * (large.normals ? 2 : 1);
      progress(`  torus ${large.vertices} x ${large.frames}: GPU bytes ${large.playback.gpu.allocated}`);
    }
    return { inputs: measured, torus: large, repeats: plan.repeats, frames: plan.frames, chromium: browser.version() };
  } finally {
    await browser.close();
    server.close();
  }
}
