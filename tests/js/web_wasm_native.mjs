// The WebAssembly decoder (web/segmorph_decoder.js, built at BUILD/web) against the native one: every file given is
// decoded in Node.js as a web page would (the GLB parsed here, its Draco base meshes decoded with Draco's own
// JavaScript decoder, draco3dgltf, each compressed primitive's stream with SegmorphDecoder) and the frames must equal
// `segmorph decode FILE --frames` bit for bit (the same layout: primitives in mesh order, clips, frames; kept targets
// as displacements). Coded track streams are compared with the decoded file's float tracks, bit for bit (but for
// samplers only placeholder channels play, which decode drops). The model of each version-4 clip primitive
// (SegmorphDecoder.createModelDecoder, the float32 arithmetic of GPU playback) must give every frame within 1e-5 of
// the base mesh's diagonal of the decoded one, and a primitive of versions 1-3 must say it has no model.
//
//   node tests/js/web_wasm_native.mjs SEGMORPH WEB_DIR WORK_DIR FILE...
// Exit status 1 on any difference or failure, with one line saying where. SEGMORPH_WASM=baseline tests the module
// without WebAssembly SIMD (web/segmorph_decoder.js), by default the SIMD one.
import { execFileSync } from 'node:child_process';
import { mkdirSync, readFileSync } from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { createRequire } from 'node:module';

import { dracoBase, readAsset, viewBytes } from './glb.mjs';

const require = createRequire(import.meta.url);
const [segmorph, webDir, work, ...files] = process.argv.slice(2);
if (!segmorph || !webDir || !work || files.length === 0) {
  console.error('usage: node tests/js/web_wasm_native.mjs SEGMORPH WEB_DIR WORK_DIR FILE...');
  process.exit(2);
}
mkdirSync(work, { recursive: true });
const { SegmorphDecoder } = await import(pathToFileURL(path.join(webDir, 'segmorph_decoder.js')).href);
await SegmorphDecoder.ready;
// SEGMORPH_WASM chooses the module (the test runs once with each); without it, SIMD where Node.js has it (always).
const expected = process.env.SEGMORPH_WASM || 'simd';
if (SegmorphDecoder.module !== expected) {
  console.error(`web_wasm_native: the decoder loaded the ${SegmorphDecoder.module} module, not the ${expected} one`);
  process.exit(1);
}
const draco = await require('draco3dgltf').createDecoderModule({});
const NAME = 'SEGMORPH_animation_compression';

// The largest float32 model evaluation difference from the decoded frames, over every frame, relative to the diagonal.
function modelDifference(stream, positions, indices, clips) {
  let decoder;
  try {
    decoder = SegmorphDecoder.createModelDecoder(stream, positions, indices);
  } catch (error) {
    if (error.unsupported) return null;
    throw error;
  }
  try {
    const { model } = decoder, K = model.clusterCount, N = model.basisCount, V = model.vertexCount;
    let low = [Infinity, Infinity, Infinity], high = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < positions.length; ++i) low[i % 3] = Math.min(low[i % 3], positions[i]), high[i % 3] = Math.max(high[i % 3], positions[i]);
    const diagonal = Math.hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]) || 1;
    let frame = 0, largest = 0;
    const out = new Float32Array(V * 3);
    for (const clip of clips)
      for (let f = 0; f < clip.frameCount; ++f, ++frame) {
        decoder.evaluate(model.motion.subarray(frame * K * 12, (frame + 1) * K * 12), model.basis.subarray(frame * N, (frame + 1) * N), out);
        const expected = clip.frames.subarray(f * V * 3, (f + 1) * V * 3);
        for (let i = 0; i < out.length; ++i) largest = Math.max(largest, Math.abs(out[i] - expected[i]));
        const b = model.bounds;
        for (let i = 0; i < out.length; ++i)
          if (out[i] < b[i % 3] || out[i] > b[3 + i % 3]) throw new Error(`frame ${frame} leaves the model's bounds`);
      }
    return largest / diagonal;
  } finally {
    decoder.dispose();
  }
}

// StreamDecoder.decodeClip: every clip, last first (a seek back each time), into arrays of the caller's (one a
// frame too long, whose last floats it must leave alone) gives decodeStream's frames; a bad clip or a short array
// is refused.
function checkDecodeClip(stream, positions, indices, clips) {
  const decoder = SegmorphDecoder.createStreamDecoder(stream, positions, indices);
  try {
    const frame = decoder.vertexCount * 3;
    for (let c = clips.length - 1; c >= 0; --c) {
      const target = new Float32Array(clips[c].frames.length + frame).fill(-7);
      if (decoder.decodeClip(c, target) !== target) throw new Error(`decodeClip(${c}) did not return its target`);
      const decoded = target.subarray(0, clips[c].frames.length);
      if (!Buffer.from(decoded.buffer, 0, decoded.byteLength).equals(Buffer.from(clips[c].frames.buffer, clips[c].frames.byteOffset, clips[c].frames.byteLength)))
        throw new Error(`decodeClip(${c}) differs from decodeStream's clip`);
      if (!target.subarray(clips[c].frames.length).every((x) => x === -7)) throw new Error(`decodeClip(${c}) wrote past its clip`);
    }
    if (!Buffer.from(decoder.decodeClip(0).buffer).equals(Buffer.from(clips[0].frames.buffer, clips[0].frames.byteOffset, clips[0].frames.byteLength)))
      throw new Error('decodeClip(0) into a new array differs');
    const refused = (what, call) => {
      try { call(); } catch (error) { if (error instanceof RangeError) return; throw error; }
      throw new Error(`decodeClip took ${what}`);
    };
    refused('a clip past the last', () => decoder.decodeClip(clips.length));
    refused('an array a float short', () => decoder.decodeClip(0, new Float32Array(clips[0].frames.length - 1)));
  } finally {
    decoder.dispose();
  }
}

let failures = 0, compared = 0, floats = 0, models = 0, modelLargest = 0;
for (const file of files) {
  const name = path.basename(file);
  try {
    const asset = await readAsset(file);
    const parts = [];
    for (const [m, mesh] of (asset.json.meshes ?? []).entries())
      for (const [p, primitive] of mesh.primitives.entries()) {
        const extension = primitive.extensions?.[NAME];
        if (!extension) continue;
        const { positions, indices } = dracoBase(draco, asset, primitive.extensions.KHR_draco_mesh_compression);
        const stream = viewBytes(asset, extension.bufferView);
        if (extension.morphTargets) {
          parts.push(SegmorphDecoder.decodeTargets(stream, positions, indices).deltas);
        } else {
          const decodedStream = SegmorphDecoder.decodeStream(stream, positions, indices);
          for (const clip of decodedStream.clips) parts.push(clip.frames);
          checkDecodeClip(stream, positions, indices, decodedStream.clips);
          const difference = modelDifference(stream, positions, indices, decodedStream.clips);
          if ((difference === null) !== (decodedStream.version < 4))
            throw new Error(`mesh ${m} primitive ${p}: a version-${decodedStream.version} stream ${difference === null ? 'has no' : 'has a'} model`);
          if (difference !== null) {
            models += 1;
            modelLargest = Math.max(modelLargest, difference);
            if (!(difference <= 1e-5)) throw new Error(`mesh ${m} primitive ${p}: the float32 model is ${difference.toExponential(2)} of the diagonal from the decoded frames`);
          }
        }
      }
    const reference = path.join(work, `${name}.frames.bin`), decodedFile = path.join(work, `${name}.decoded.glb`);
    execFileSync(segmorph, ['decode', '-q', file, '-o', decodedFile, '--frames', reference]);
    const expected = readFileSync(reference);
    const actual = Buffer.concat(parts.map((a) => Buffer.from(a.buffer, a.byteOffset, a.byteLength)));
    if (!actual.equals(expected)) {
      console.error(`web_wasm_native: ${file}: the WebAssembly frames (${actual.length} bytes) differ from segmorph decode --frames (${expected.length} bytes)`);
      failures += 1;
      continue;
    }
    floats += actual.length / 4;
    // Coded tracks: the decoded file holds them as floats; the WebAssembly decoder must give the same bits.
    const decoded = await readAsset(decodedFile);
    for (const [a, animation] of (asset.json.animations ?? []).entries()) {
      const coded = animation.extensions?.[NAME];
      if (!coded) continue;
      const inputs = [], samplers = [];
      for (const s of coded.samplers) {
        const sampler = animation.samplers[s];
        const paths = animation.channels.filter((c) => c.sampler === s).map((c) => c.target.path);
        const pathCode = { translation: 0, rotation: 1, scale: 2 }[paths[0]];
        let times = inputs.indexOf(sampler.input);
        if (times < 0) times = inputs.push(sampler.input) - 1;
        samplers.push({ times, path: pathCode, components: pathCode === 1 ? 4 : 3 });
      }
      const tracks = SegmorphDecoder.decodeTracks(viewBytes(asset, coded.bufferView),
                                                  inputs.map((i) => asset.json.accessors[i].count), samplers);
      coded.samplers.forEach((s, i) => {
        // A sampler that only placeholder channels play is dropped by decode (its animation is rebuilt).
        if (animation.channels.every((c) => c.sampler !== s || c.extensions?.[NAME]?.placeholder)) return;
        const out = decoded.json.animations[a].samplers[s].output, accessor = decoded.json.accessors[out];
        const view = decoded.json.bufferViews[accessor.bufferView];
        const start = (view.byteOffset ?? 0) + (accessor.byteOffset ?? 0);
        const bytes = decoded.buffers[view.buffer].subarray(start, start + tracks.values[i].byteLength);
        if (!Buffer.from(tracks.values[i].buffer, tracks.values[i].byteOffset, tracks.values[i].byteLength).equals(bytes)) {
          console.error(`web_wasm_native: ${file}: animation ${a} sampler ${s}: the WebAssembly track values differ from segmorph decode's`);
          failures += 1;
        }
        floats += tracks.values[i].length;
      });
    }
    compared += 1;
  } catch (error) {
    console.error(`web_wasm_native: ${file}: ${error.message}`);
    failures += 1;
  }
}
console.log(`web_wasm_native: ${compared} of ${files.length} files, ${floats} floats: ${failures === 0 ? 'the WebAssembly decoder gives the native floats bit for bit' : `${failures} failed`}; ${models} version-4 models in float32 within ${modelLargest.toExponential(2)} of the diagonal`);
process.exit(failures === 0 ? 0 : 1);
