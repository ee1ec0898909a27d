// segmorph's runtime decoder in JavaScript: the C++ decoder (include/segmorph/decoder_c.h) compiled to WebAssembly,
// so that a browser decodes the same floats as an engine or `segmorph decode`. An ES module without dependencies;
// the .wasm beside it is fetched (browsers) or read (Node.js) when the module loads: segmorph_decoder_simd.wasm where
// the runtime has WebAssembly SIMD (every current browser and Node.js), else segmorph_decoder.wasm. To choose, set
// globalThis.SEGMORPH_WASM (or, under Node.js, the environment variable SEGMORPH_WASM) to 'simd' or 'baseline' before
// the module loads; SegmorphDecoder.module says which one it loaded.
//
//   import { SegmorphDecoder } from './segmorph_decoder.js';
//   await SegmorphDecoder.ready;
//   const { clips } = SegmorphDecoder.decodeStream(stream, positions, indices);
//
// Shapes: positions are Float32Arrays of vertex count × 3 (x, y, z per vertex); a clip's frames follow each other in
// one Float32Array (frame count × vertex count × 3). `positions` and `indices` are the primitive's base mesh exactly as
// the Draco decoder returned it (docs/runtime.md, docs/web.md). Every function throws an Error whose message starts
// with "segmorph:" when the stream is damaged or does not belong to the mesh.

const STATUS = { 0: 'ok', 1: 'invalid argument', 3: 'bad data', 4: 'unsupported', 7: 'internal error', 8: 'out of memory' };

let wasm = null;  // the instance's exports

// The imports of a WASI "reactor" module that never reads files, the clock or the environment: only what libc's
// abort path may call (its message goes to the console).
function wasiImports() {
  const text = [];
  return {
    fd_write(fd, iovs, iovsLength, written) {
      const view = new DataView(wasm.memory.buffer);
      let total = 0;
      for (let i = 0; i < iovsLength; ++i) {
        const pointer = view.getUint32(iovs + i * 8, true), length = view.getUint32(iovs + i * 8 + 4, true);
        text.push(new TextDecoder().decode(new Uint8Array(wasm.memory.buffer, pointer, length)));
        total += length;
      }
      view.setUint32(written, total, true);
      const joined = text.join('');
      if (joined.includes('\n')) {
        console.error(`segmorph: ${joined.trimEnd()}`);
        text.length = 0;
      }
      return 0;
    },
    fd_close: () => 0,
    fd_seek: () => 70,  // ESPIPE
    proc_exit(code) {
      throw new Error(`segmorph: the decoder exited (${code})`);
    },
  };
}

// A module of one function that returns i32x4.splat(0): valid only where WebAssembly has SIMD.
const SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 8, 1, 6, 0, 65,
                                   0, 253, 17, 11]);

// 'simd' or 'baseline': the caller's choice, else SIMD where the runtime validates it.
function wasmModule() {
  const asked = globalThis.SEGMORPH_WASM ?? globalThis.process?.env?.SEGMORPH_WASM;
  if (asked !== undefined && asked !== '') {
    if (asked !== 'simd' && asked !== 'baseline')
      throw new Error(`segmorph: SEGMORPH_WASM is '${asked}'; it takes 'simd' or 'baseline'`);
    return asked;
  }
  return WebAssembly.validate(SIMD_PROBE) ? 'simd' : 'baseline';
}
const module = wasmModule();

async function wasmBytes() {
  const url = new URL(module === 'simd' ? './segmorph_decoder_simd.wasm' : './segmorph_decoder.wasm', import.meta.url);
  if (url.protocol === 'file:') {  // Node.js
    const { readFile } = await import('node:fs/promises');
    return readFile(url);
  }
  const response = await fetch(url);
  if (!response.ok) throw new Error(`segmorph: cannot load ${url}: ${response.status} ${response.statusText}`);
  return response.arrayBuffer();
}

const ready = wasmBytes()
  .then((bytes) => WebAssembly.instantiate(bytes, { wasi_snapshot_preview1: wasiImports() }))
  .then(({ instance }) => {
    wasm = instance.exports;
    wasm._initialize();
  });

function cString(pointer) {
  const bytes = new Uint8Array(wasm.memory.buffer);
  let end = pointer;
  while (bytes[end] !== 0) ++end;
  return new TextDecoder().decode(bytes.subarray(pointer, end));
}

// Bytes in the module's memory, freed by release().
function allocate(bytes) {
  const pointer = wasm.segmorph_wasm_malloc(Math.max(bytes, 1));
  if (pointer === 0) throw new Error('segmorph: out of memory');
  return pointer;
}

function copyIn(array) {
  const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
  const pointer = allocate(bytes.length);
  new Uint8Array(wasm.memory.buffer, pointer, bytes.length).set(bytes);
  return pointer;
}

function floatsOut(pointer, count) {
  return new Float32Array(wasm.memory.buffer, pointer, count).slice();
}

function asBytes(stream) {
  if (stream instanceof Uint8Array) return stream;
  if (stream instanceof ArrayBuffer) return new Uint8Array(stream);
  if (ArrayBuffer.isView(stream)) return new Uint8Array(stream.buffer, stream.byteOffset, stream.byteLength);
  throw new TypeError('segmorph: the stream must be a Uint8Array or an ArrayBuffer');
}

function asPositions(positions) {
  if (!(positions instanceof Float32Array)) throw new TypeError('segmorph: positions must be a Float32Array (V × 3)');
  if (positions.length % 3 !== 0) throw new TypeError('segmorph: positions must hold V × 3 floats');
  return positions;
}

function asIndices(indices) {
  if (indices instanceof Uint32Array) return indices;
  if (indices && typeof indices.length === 'number') return Uint32Array.from(indices);
  throw new TypeError('segmorph: indices must be an array of triangle corners');
}

function requireReady() {
  if (!wasm) throw new Error('segmorph: the decoder is not ready yet (await SegmorphDecoder.ready)');
}

// Runs `body(decoder, fail)` with a fresh C decoder; `pointers` collects what to free afterwards.
function withDecoder(body) {
  requireReady();
  const decoder = wasm.segmorph_decoder_create();
  if (decoder === 0) throw new Error('segmorph: out of memory');
  const pointers = [];
  const check = (status, what) => {
    if (status !== 0) {
      const message = cString(wasm.segmorph_decoder_message(decoder));
      const error = new Error(`segmorph: ${what ? what + ': ' : ''}${STATUS[status] ?? `status ${status}`}: ${message}`);
      error.unsupported = status === 4;  // e.g. the model of a version 1-3 stream
      throw error;
    }
  };
  try {
    return body(decoder, check, pointers);
  } finally {
    for (const pointer of pointers) wasm.segmorph_wasm_free(pointer);
    wasm.segmorph_decoder_destroy(decoder);
  }
}

function open(decoder, check, pointers, stream, positions, indices) {
  const bytes = asBytes(stream), base = asPositions(positions), corners = asIndices(indices);
  const streamPointer = copyIn(bytes), positionPointer = copyIn(base), indexPointer = copyIn(corners);
  pointers.push(streamPointer, positionPointer, indexPointer);
  check(wasm.segmorph_decoder_open(decoder, streamPointer, bytes.length, positionPointer, base.length / 3, indexPointer,
                                   corners.length), 'open');
}

function asNormals(normals, floats) {
  if (!(normals instanceof Float32Array) || normals.length !== floats)
    throw new TypeError(`segmorph: normals must be a Float32Array of the base mesh's ${floats} floats (V × 3)`);
  return normals;
}

// The base normals (at `normalPointer`, V × 3) turned to the `count` frames at `framePointer`, as segmorph decode turns
// them (the C API's segmorph_decoder_turn_normals): a Float32Array of count × V × 3.
function turnedNormals(decoder, check, pointers, normalPointer, framePointer, count, floats) {
  const out = allocate(floats * 4);
  pointers.push(out);
  check(wasm.segmorph_decoder_turn_normals(decoder, normalPointer, framePointer, count, out, floats), 'normals');
  return floatsOut(out, floats);
}

// The whole stream: { version, lossless, vertexCount, clips: [{ frameCount, frames, normals }] }, frames a
// Float32Array of frameCount × vertexCount × 3 positions. With `normals` (the base mesh's NORMAL, V × 3), each clip's
// `normals` holds its frames' normals (frameCount × V × 3), turned with the surface as segmorph decode turns them.
function decodeStream(stream, positions, indices, normals) {
  return withDecoder((decoder, check, pointers) => {
    open(decoder, check, pointers, stream, positions, indices);
    const normalPointer = normals ? copyIn(asNormals(normals, positions.length)) : 0;
    if (normals) pointers.push(normalPointer);
    const vertexCount = wasm.segmorph_decoder_vertex_count(decoder), clips = [];
    for (let clip = 0, count = wasm.segmorph_decoder_clip_count(decoder); clip < count; ++clip) {
      const floats = wasm.segmorph_decode_clip_bound(decoder, clip), out = allocate(floats * 4);
      pointers.push(out);
      check(wasm.segmorph_decode_clip(decoder, clip, out, floats), `clip ${clip}`);
      const frameCount = wasm.segmorph_decoder_frame_count(decoder, clip);
      clips.push({ frameCount, frames: floatsOut(out, floats),
                   normals: normals ? turnedNormals(decoder, check, pointers, normalPointer, out, frameCount, floats) : null });
    }
    return { version: wasm.segmorph_decoder_stream_version(decoder), lossless: wasm.segmorph_decoder_lossless(decoder) === 1,
             vertexCount, clips };
  });
}

// Kept morph targets: { vertexCount, targetCount, deltas, normals }, deltas a Float32Array of targetCount × vertexCount
// × 3 POSITION displacements (frame − base in binary32). With `normals` (the base mesh's NORMAL), `normals` holds each
// target's normals (targetCount × V × 3, absolute), turned as segmorph decode turns them.
function decodeTargets(stream, positions, indices, normals) {
  return withDecoder((decoder, check, pointers) => {
    open(decoder, check, pointers, stream, positions, indices);
    const floats = wasm.segmorph_decode_clip_bound(decoder, 0), out = allocate(floats * 4);
    pointers.push(out);
    const targetCount = wasm.segmorph_decoder_frame_count(decoder, 0);
    let turned = null;
    if (normals) {  // turned on the decoded shapes, as segmorph decode turns them
      const normalPointer = copyIn(asNormals(normals, positions.length));
      pointers.push(normalPointer);
      check(wasm.segmorph_decode_clip(decoder, 0, out, floats), 'targets');
      turned = turnedNormals(decoder, check, pointers, normalPointer, out, targetCount, floats);
    }
    check(wasm.segmorph_decode_targets(decoder, out, floats), 'targets');
    return { vertexCount: wasm.segmorph_decoder_vertex_count(decoder), targetCount, deltas: floatsOut(out, floats),
             normals: turned };
  });
}

// A track stream: { times: [Float32Array per time array], values: [Float32Array per sampler] }. timeCounts: the keys
// of each time array; samplers: [{ times, path, components }] (path 0 translation, 1 rotation, 2 scale, 3 weights).
function decodeTracks(stream, timeCounts, samplers) {
  return withDecoder((decoder, check, pointers) => {
    const bytes = asBytes(stream);
    const counts = new Uint32Array(timeCounts), layout = new Uint32Array(samplers.length * 3);
    samplers.forEach((s, i) => layout.set([s.times, s.path, s.components], i * 3));
    const streamPointer = copyIn(bytes), countPointer = copyIn(counts), layoutPointer = copyIn(layout);
    pointers.push(streamPointer, countPointer, layoutPointer);
    const floats = wasm.segmorph_decode_tracks_bound(countPointer, counts.length, layoutPointer, samplers.length);
    if (floats === 0) throw new Error('segmorph: the track layout is invalid');
    const out = allocate(floats * 4);
    pointers.push(out);
    check(wasm.segmorph_decode_tracks(decoder, streamPointer, bytes.length, countPointer, counts.length, layoutPointer,
                                      samplers.length, out, floats), 'tracks');
    const all = floatsOut(out, floats), times = [], values = [];
    let at = 0;
    for (const count of counts) { times.push(all.subarray(at, at + count)); at += count; }
    for (const s of samplers) {
      const n = counts[s.times] * s.components;
      values.push(all.subarray(at, at + n));
      at += n;
    }
    return { times, values };
  });
}

// The model of a version-4 stream (docs/runtime.md, "Playing the model"; the C API's segmorph_decoder_model_*), for
// a player that evaluates frames on the GPU: every array in the C API's shapes, in one object. A stream of versions
// 1 to 3 has none: the Error's `unsupported` is true then (decode frames instead).
//   { version, vertexCount, weldedCount, clusterCount, frameCount, basisCount, coefficientCount, maxBasisSize,
//     maxPairs, clipFrames: [frame count per clip], welded (V), clusters (W × 4), weights (W × 4), centroids (K × 3),
//     bases (K × 2: first value, m), coefficientOffsets (W + 1), coefficients (vectors × 3), motion (F × K × 12),
//     basis (F × N), bounds (6: min x y z, max x y z), surface (V × 3: each vertex's unit base surface normal at its
//     point, for a shader that turns normals: the C API's segmorph_decoder_surface_normals) }
const MODEL_INFO_FIELDS = ['vertexCount', 'weldedCount', 'clusterCount', 'frameCount', 'basisCount', 'coefficientCount',
                           'maxBasisSize', 'maxPairs'];

function readModel(decoder, check, pointers) {
  const infoPointer = allocate(MODEL_INFO_FIELDS.length * 4);
  pointers.push(infoPointer);
  check(wasm.segmorph_decoder_model_info(decoder, infoPointer), 'model');
  const fields = new Uint32Array(wasm.memory.buffer, infoPointer, MODEL_INFO_FIELDS.length).slice();
  const model = { version: wasm.segmorph_decoder_stream_version(decoder) };
  MODEL_INFO_FIELDS.forEach((name, i) => { model[name] = fields[i]; });
  model.clipFrames = [];
  for (let c = 0, count = wasm.segmorph_decoder_clip_count(decoder); c < count; ++c)
    model.clipFrames.push(wasm.segmorph_decoder_frame_count(decoder, c));
  const { vertexCount: V, weldedCount: W, clusterCount: K, frameCount: F, basisCount: N, coefficientCount: C } = model;
  const out = (count, Type) => {
    const pointer = allocate(count * 4);
    pointers.push(pointer);
    return { pointer, take: () => new Type(wasm.memory.buffer, pointer, count).slice() };
  };
  const welded = out(V, Uint32Array);
  check(wasm.segmorph_decoder_model_welded(decoder, welded.pointer, V), 'model');
  const clusters = out(W * 4, Uint32Array), weights = out(W * 4, Float32Array);
  check(wasm.segmorph_decoder_model_weights(decoder, clusters.pointer, weights.pointer, W * 4), 'model');
  const centroids = out(K * 3, Float32Array), bases = out(K * 2, Uint32Array);
  check(wasm.segmorph_decoder_model_clusters(decoder, centroids.pointer, bases.pointer, K), 'model');
  const offsets = out(W + 1, Uint32Array), coefficients = out(C * 3, Float32Array);
  check(wasm.segmorph_decoder_model_coefficients(decoder, offsets.pointer, W + 1, coefficients.pointer, C * 3), 'model');
  const surface = out(V * 3, Float32Array);
  check(wasm.segmorph_decoder_surface_normals(decoder, 0, surface.pointer, V * 3), 'model');
  const motion = out(F * K * 12, Float32Array), basis = out(F * N, Float32Array), bounds = out(6, Float32Array);
  check(wasm.segmorph_decoder_model_motion(decoder, 0, F, motion.pointer, F * K * 12), 'model');
  check(wasm.segmorph_decoder_model_basis(decoder, 0, F, basis.pointer, F * N), 'model');
  check(wasm.segmorph_decoder_model_bounds(decoder, bounds.pointer), 'model');
  Object.assign(model, {
    welded: welded.take(), clusters: clusters.take(), weights: weights.take(), centroids: centroids.take(),
    bases: bases.take(), coefficientOffsets: offsets.take(), coefficients: coefficients.take(), motion: motion.take(),
    basis: basis.take(), bounds: bounds.take(), surface: surface.take(),
  });
  return model;
}

function decodeModel(stream, positions, indices) {
  return withDecoder((decoder, check, pointers) => {
    open(decoder, check, pointers, stream, positions, indices);
    return readModel(decoder, check, pointers);
  });
}

// The model and the float32 reference of its evaluation (the vertex shader's arithmetic, docs/runtime.md), for tests
// and for a player without a shader path: evaluate(motion, basis, out?) gives the V × 3 positions at one set of
// parameters (K × 12 and N floats: a frame's, or a blend). dispose() frees it.
class ModelDecoder {
  constructor(stream, positions, indices) {
    requireReady();
    this._decoder = wasm.segmorph_decoder_create();
    if (this._decoder === 0) throw new Error('segmorph: out of memory');
    const pointers = [];
    try {
      const check = (status, what) => this._check(status, what);
      open(this._decoder, check, pointers, stream, positions, indices);
      this.model = readModel(this._decoder, check, pointers);
      const { clusterCount: K, basisCount: N, vertexCount: V } = this.model;
      this._parameters = allocate((K * 12 + N) * 4);
      this._positions = allocate(V * 12);
    } catch (error) {
      this.dispose();
      throw error;
    } finally {
      for (const pointer of pointers) wasm.segmorph_wasm_free(pointer);
    }
  }

  _check(status, what) {
    if (status !== 0) {
      const error = new Error(`segmorph: ${what}: ${STATUS[status] ?? status}: ${cString(wasm.segmorph_decoder_message(this._decoder))}`);
      error.unsupported = status === 4;
      throw error;
    }
  }

  evaluate(motion, basis, target) {
    const { clusterCount: K, basisCount: N, vertexCount: V } = this.model;
    if (motion.length < K * 12 || basis.length < N) throw new RangeError(`segmorph: the parameters need ${K * 12} and ${N} floats`);
    const parameters = new Float32Array(wasm.memory.buffer, this._parameters, K * 12 + N);
    parameters.set(motion.subarray(0, K * 12));
    parameters.set(basis.subarray(0, N), K * 12);
    this._check(wasm.segmorph_decoder_model_evaluate(this._decoder, this._parameters, K * 12, this._parameters + K * 48, N,
                                                      this._positions, V * 3), 'evaluate');
    const out = target ?? new Float32Array(V * 3);
    out.set(new Float32Array(wasm.memory.buffer, this._positions, V * 3));
    return out;
  }

  dispose() {
    if (this._decoder === 0) return;
    if (this._parameters) wasm.segmorph_wasm_free(this._parameters);
    if (this._positions) wasm.segmorph_wasm_free(this._positions);
    wasm.segmorph_decoder_destroy(this._decoder);
    this._decoder = 0;
  }
}

// Frame by frame: a decoder that holds the stream and one frame (vertex count × 3 floats) in the module's memory and
// decodes the next frame on demand, for a player that must not hold every frame; given the base mesh's normals, it
// turns a shape's normals too (turnNormals). dispose() frees it.
class StreamDecoder {
  constructor(stream, positions, indices, normals) {
    requireReady();
    this._decoder = wasm.segmorph_decoder_create();
    if (this._decoder === 0) throw new Error('segmorph: out of memory');
    this._pointers = [];
    try {
      open(this._decoder, (status, what) => this._check(status, what), this._pointers, stream, positions, indices);
      // The decoder copied its inputs: free them now, keep one frame (and the base normals and a frame's normals).
      for (const pointer of this._pointers) wasm.segmorph_wasm_free(pointer);
      this._pointers = [];
      this.vertexCount = wasm.segmorph_decoder_vertex_count(this._decoder);
      this.clipCount = wasm.segmorph_decoder_clip_count(this._decoder);
      this.version = wasm.segmorph_decoder_stream_version(this._decoder);
      this._frame = allocate(this.vertexCount * 12);
      this._pointers = [this._frame];
      if (normals) {
        this._normals = copyIn(asNormals(normals, this.vertexCount * 3));
        this._turned = allocate(this.vertexCount * 12);
        this._pointers.push(this._normals, this._turned);
      }
    } catch (error) {
      this.dispose();
      throw error;
    }
  }

  _check(status, what) {
    if (status !== 0)
      throw new Error(`segmorph: ${what}: ${STATUS[status] ?? status}: ${cString(wasm.segmorph_decoder_message(this._decoder))}`);
  }

  frameCount(clip) { return wasm.segmorph_decoder_frame_count(this._decoder, clip); }
  get nextClip() { return wasm.segmorph_decoder_next_clip(this._decoder); }
  get nextFrame() { return wasm.segmorph_decoder_next_frame(this._decoder); }

  // To the first frame of `clip` (cheap for a clip start already passed).
  seek(clip) { this._check(wasm.segmorph_decoder_seek(this._decoder, clip), `seek to clip ${clip}`); }

  // The next frame into `target` (a Float32Array of vertex count × 3; a new one when absent), which it returns.
  decodeFrame(target) {
    const floats = this.vertexCount * 3;
    const out = target ?? new Float32Array(floats);
    if (out.length < floats) throw new RangeError(`segmorph: the frame needs ${floats} floats`);
    this._check(wasm.segmorph_decode_frame(this._decoder, this._frame, floats), 'frame');
    out.set(new Float32Array(wasm.memory.buffer, this._frame, floats));
    return out;
  }

  // Every frame of `clip` into `target` (a Float32Array of frameCount(clip) × vertex count × 3; a new one when
  // absent), which it returns: as decodeStream's clip, without a fresh array per call for a caller that keeps its own
  // (as MeshoptDecoder decodes into the caller's target). Afterwards the decoder is at the next clip's first frame.
  decodeClip(clip, target) {
    if (!(clip >= 0 && clip < this.clipCount)) throw new RangeError(`segmorph: no clip ${clip} (the stream has ${this.clipCount})`);
    const floats = wasm.segmorph_decode_clip_bound(this._decoder, clip);
    const out = target ?? new Float32Array(floats);
    if (!(out instanceof Float32Array) || out.length < floats)
      throw new RangeError(`segmorph: clip ${clip} needs a Float32Array of ${floats} floats`);
    const room = allocate(floats * 4);
    try {
      this._check(wasm.segmorph_decode_clip(this._decoder, clip, room, floats), `clip ${clip}`);
      out.set(new Float32Array(wasm.memory.buffer, room, floats));
    } finally {
      wasm.segmorph_wasm_free(room);
    }
    return out;
  }

  // With the base normals given at creation: the normals of the shape `positions` (V × 3; a decoded frame, or a blend
  // of two) into `target` (a new Float32Array when absent), which it returns: turned as segmorph decode turns them.
  turnNormals(positions, target) {
    const floats = this.vertexCount * 3;
    if (!this._normals) throw new Error('segmorph: the decoder was created without normals');
    const out = target ?? new Float32Array(floats);
    if (positions.length < floats || out.length < floats) throw new RangeError(`segmorph: the shape needs ${floats} floats`);
    new Float32Array(wasm.memory.buffer, this._frame, floats).set(positions.subarray(0, floats));
    this._check(wasm.segmorph_decoder_turn_normals(this._decoder, this._normals, this._frame, 1, this._turned, floats), 'normals');
    out.set(new Float32Array(wasm.memory.buffer, this._turned, floats));
    return out;
  }

  dispose() {
    if (this._decoder === 0) return;
    for (const pointer of this._pointers) wasm.segmorph_wasm_free(pointer);
    wasm.segmorph_decoder_destroy(this._decoder);
    this._pointers = [];
    this._decoder = 0;
  }
}

// Workers (as MeshoptDecoder.useWorkers): the *Async functions run in a pool of module workers, so that a large file
// does not block the page; without workers they run on the calling thread.
let workers = [], nextRequest = 0;
const pending = new Map();

function useWorkers(count) {
  for (const worker of workers) worker.terminate();
  workers = [];
  for (let i = 0; i < count; ++i) {
    const worker = new Worker(new URL('./segmorph_worker.js', import.meta.url), { type: 'module' });
    worker.pending = 0;
    worker.onmessage = ({ data }) => {
      worker.pending -= 1;
      const request = pending.get(data.id);
      pending.delete(data.id);
      if (data.error) request.reject(Object.assign(new Error(data.error), { unsupported: data.unsupported === true }));
      else request.resolve(data.result);
    };
    worker.onerror = (event) => {
      for (const [id, request] of pending) { request.reject(new Error(`segmorph: a worker failed: ${event.message}`)); pending.delete(id); }
    };
    workers.push(worker);
  }
}

function inWorker(method, args) {
  if (workers.length === 0) {
    return ready.then(() => api[method](...args));
  }
  const worker = workers.reduce((a, b) => (b.pending < a.pending ? b : a));
  const id = nextRequest++;
  worker.pending += 1;
  return new Promise((resolve, reject) => {
    pending.set(id, { resolve, reject });
    worker.postMessage({ id, method, args });
  });
}

const api = {
  ready,
  module,  // 'simd' or 'baseline': which .wasm this module loads (a worker decides for itself)
  decodeStream,
  decodeTargets,
  decodeTracks,
  decodeModel,
  createModelDecoder: (stream, positions, indices) => new ModelDecoder(stream, positions, indices),
  createStreamDecoder: (stream, positions, indices, normals) => new StreamDecoder(stream, positions, indices, normals),
  useWorkers,
  decodeStreamAsync: (...args) => inWorker('decodeStream', args),
  decodeTargetsAsync: (...args) => inWorker('decodeTargets', args),
  decodeTracksAsync: (...args) => inWorker('decodeTracks', args),
  decodeModelAsync: (...args) => inWorker('decodeModel', args),
  // The library's version (major × 1000 + minor × 10 + patch), once ready.
  get version() { requireReady(); return wasm.segmorph_version(); },
};

export const SegmorphDecoder = api;
export { ModelDecoder, StreamDecoder };
