// Decode speed of segmorph's runtime decoder three ways on the same streams:
//   node bench/wasm_speed.mjs BUILD FILE.glb... [--runs N]
// FILE: files `segmorph encode` wrote. Each compressed primitive's stream (not the kept-morph-target ones) and its
// Draco base mesh are extracted (Draco's own JavaScript decoder, as a page has it), then decoded
// - natively: BUILD/bench/decode_speed, the C API on one thread and on every hardware thread (set_threads: a
//   version-4 stream's frames), open then every clip into memory allocated first; on one thread again with glibc
//   keeping the memory the decoder frees (GLIBC_TUNABLES: no trim, no mmap), so that each open does not fault its
//   working memory in afresh, as WebAssembly's memory, which never shrinks, does not: the WebAssembly figures are
//   given as fractions of that one, the faster;
// - in Node.js's WebAssembly: BUILD/web/segmorph_decoder.js, once with the SIMD module and once with the one without
//   (SEGMORPH_WASM), each in a process of its own, two ways in turn: as the native decoder (createStreamDecoder, then
//   decodeClip of every clip into arrays allocated first: the stream and the base copied into the module's memory,
//   open, each clip decoded and copied out), and SegmorphDecoder.decodeStream (the same into fresh arrays each call,
//   as a page that loads a file once pays them).
// N runs each (default 9) after one not counted; the median. Prints a Markdown table: millions of vertex-frames per
// second and each WebAssembly figure as a fraction of the native one with freed memory kept. Release build; an idle
// machine.
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
let runs = 9;
const runsAt = args.indexOf('--runs');
if (runsAt >= 0) {
  runs = Number(args[runsAt + 1]);
  args.splice(runsAt, 2);
  if (!(runs >= 1 && runs <= 1000)) throw new Error('wasm_speed: --runs takes 1 to 1000');
}
const median = (x) => [...x].sort((a, b) => a - b)[Math.floor((x.length - 1) / 2)];

// The child: one module's timing of the stream in DIR, as JSON on stdout.
if (args[0] === '--child') {
  const [, web, directory] = args;
  const { SegmorphDecoder } = await import(pathToFileURL(path.join(web, 'segmorph_decoder.js')).href);
  await SegmorphDecoder.ready;
  const read = (name) => readFileSync(path.join(directory, name));
  const stream = new Uint8Array(read('stream.bin'));
  const base = read('base.f32'), indices = read('indices.u32');
  const positions = new Float32Array(base.buffer, base.byteOffset, base.byteLength / 4);
  const triangles = new Uint32Array(indices.buffer, indices.byteOffset, indices.byteLength / 4);
  const kept = [], fresh = [];
  let vertexFrames = 0, targets = null;
  for (let run = 0; run <= runs; ++run) {
    let start = performance.now();
    const decoder = SegmorphDecoder.createStreamDecoder(stream, positions, triangles);
    targets ??= Array.from({ length: decoder.clipCount },
                           (_, c) => new Float32Array(decoder.frameCount(c) * decoder.vertexCount * 3));
    for (let c = 0; c < decoder.clipCount; ++c) decoder.decodeClip(c, targets[c]);
    decoder.dispose();
    let end = performance.now();
    if (run > 0) kept.push(end - start);
    start = performance.now();
    const { clips } = SegmorphDecoder.decodeStream(stream, positions, triangles);
    end = performance.now();
    if (run > 0) fresh.push(end - start);
    vertexFrames = clips.reduce((sum, clip) => sum + clip.frames.length / 3, 0);
    if (clips.some((clip, c) => clip.frames.length !== targets[c].length || clip.frames.some((x, i) => !Object.is(x, targets[c][i]))))
      throw new Error('wasm_speed: decodeClip and decodeStream differ');
  }
  console.log(JSON.stringify({ module: SegmorphDecoder.module, vertex_frames: vertexFrames, median_ms: median(kept),
                               fresh_ms: median(fresh) }));
  process.exit(0);
}

const [build, ...files] = args;
if (!build || files.length === 0) {
  console.error('usage: node bench/wasm_speed.mjs BUILD FILE.glb... [--runs N]');
  process.exit(2);
}
const tests = path.join(here, '..', 'tests', 'js');
const { dracoBase, readAsset, viewBytes } = await import(pathToFileURL(path.join(tests, 'glb.mjs')).href);
const draco = await createRequire(path.join(tests, 'package.json'))('draco3dgltf').createDecoderModule({});
const web = path.join(build, 'web'), native = path.join(build, 'bench', 'decode_speed');
const work = mkdtempSync(path.join(os.tmpdir(), 'wasm_speed-'));
const NAME = 'SEGMORPH_animation_compression';

const rows = [];
try {
  for (const file of files) {
    const asset = await readAsset(file);
    for (const [m, mesh] of (asset.json.meshes ?? []).entries())
      for (const [p, primitive] of mesh.primitives.entries()) {
        const extension = primitive.extensions?.[NAME];
        if (!extension || extension.morphTargets) continue;
        const directory = path.join(work, `${rows.length}`);
        mkdirSync(directory);
        const { positions, indices } = dracoBase(draco, asset, primitive.extensions.KHR_draco_mesh_compression);
        writeFileSync(path.join(directory, 'stream.bin'), viewBytes(asset, extension.bufferView));
        writeFileSync(path.join(directory, 'base.f32'), positions);
        writeFileSync(path.join(directory, 'indices.u32'), indices);
        const nativeRun = JSON.parse(execFileSync(native, [directory, '--runs', `${runs}`], { encoding: 'utf8' }));
        const keptRun = JSON.parse(execFileSync(native, [directory, '--runs', `${runs}`], { encoding: 'utf8',
          env: { ...process.env, GLIBC_TUNABLES: 'glibc.malloc.trim_threshold=4000000000:glibc.malloc.mmap_threshold=4000000000' } }));
        const threadsRun = JSON.parse(execFileSync(native, [directory, '--runs', `${runs}`, '--threads', '0'],
                                                   { encoding: 'utf8' }));
        const wasmRun = (module) => JSON.parse(execFileSync(process.execPath,
          [fileURLToPath(import.meta.url), '--child', web, directory, '--runs', `${runs}`],
          { encoding: 'utf8', env: { ...process.env, SEGMORPH_WASM: module } }));
        const simd = wasmRun('simd'), baseline = wasmRun('baseline');
        if (simd.module !== 'simd' || baseline.module !== 'baseline') throw new Error('wasm_speed: the wrong module loaded');
        const version = viewBytes(asset, extension.bufferView)[4];
        rows.push({ file: path.basename(file), primitive: `${m}/${p}`, version, vertexCount: positions.length / 3,
                    vertexFrames: nativeRun.vertex_frames, fresh: nativeRun.median_ms, native: keptRun.median_ms,
                    threads: threadsRun.median_ms,
                    simd: simd.median_ms, simdFresh: simd.fresh_ms,
                    baseline: baseline.median_ms, baselineFresh: baseline.fresh_ms });
      }
  }
} finally {
  rmSync(work, { recursive: true, force: true });
}
const rate = (vertexFrames, ms) => (vertexFrames / ms / 1e3).toFixed(1);
const cell = (r, ms) => `${rate(r.vertexFrames, ms)} (${ms.toFixed(2)}), ${(r.native / ms).toFixed(2)}`;
console.log(`| file | mesh/primitive | stream version | V | vertex-frames | native, one thread: M vf/s (ms) | ` +
            `native, one thread, freed memory kept | ` +
            `native, ${os.availableParallelism?.() ?? os.cpus().length} threads | ` +
            `WebAssembly SIMD M vf/s (ms), of native | without SIMD | SIMD, decodeStream (fresh arrays) | ` +
            `without SIMD, decodeStream |`);
console.log('|---|---|---|---|---|---|---|---|---|---|---|---|');
for (const r of rows)
  console.log(`| ${r.file} | ${r.primitive} | ${r.version} | ${r.vertexCount} | ${r.vertexFrames} | ` +
              `${rate(r.vertexFrames, r.fresh)} (${r.fresh.toFixed(2)}) | ` +
              `${rate(r.vertexFrames, r.native)} (${r.native.toFixed(2)}) | ` +
              `${rate(r.vertexFrames, r.threads)} (${r.threads.toFixed(2)}) | ` +
              `${cell(r, r.simd)} | ${cell(r, r.baseline)} | ${cell(r, r.simdFresh)} | ${cell(r, r.baselineFresh)} |`);
