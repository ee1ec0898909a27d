// segmorph's runtime decoder in JavaScript: the C++ decoder (include/segmorph/decoder_c.h) compiled to WebAssembly,
// so that a browser decodes the same floats as an engine or `segmorph decode`. An ES module without dependencies;
// the .wasm beside it is fetched (browsers) or read (Node.js) when the module loads.
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

async function wasmBytes() {
  const url = new URL('./segmorph_decoder.wasm', import.meta.url);
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
      throw new Error(`segmorph: ${what ? what + ': ' : ''}${STATUS[status] ?? `status ${status}`}: ${message}`);
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

// The whole stream: { version, lossless, vertexCount, clips: [{ frameCount, frames }] }, frames a Float32Array of
// frameCount × vertexCount × 3 positions.
function decodeStream(stream, positions, indices) {
  return withDecoder((decoder, check, pointers) => {
    open(decoder, check, pointers, stream, positions, indices);
    const vertexCount = wasm.segmorph_decoder_vertex_count(decoder), clips = [];
    for (let clip = 0, count = wasm.segmorph_decoder_clip_count(decoder); clip < count; ++clip) {
      const floats = wasm.segmorph_decode_clip_bound(decoder, clip), out = allocate(floats * 4);
      pointers.push(out);
      check(wasm.segmorph_decode_clip(decoder, clip, out, floats), `clip ${clip}`);
      clips.push({ frameCount: wasm.segmorph_decoder_frame_count(decoder, clip), frames: floatsOut(out, floats) });
    }
    return { version: wasm.segmorph_decoder_stream_version(decoder), lossless: wasm.segmorph_decoder_lossless(decoder) === 1,
             vertexCount, clips };
  });
}

// Kept morph targets: { vertexCount, targetCount, deltas }, deltas a Float32Array of targetCount × vertexCount × 3
// POSITION displacements (frame − base in binary32).
function decodeTargets(stream, positions, indices) {
  return withDecoder((decoder, check, pointers) => {
    open(decoder, check, pointers, stream, positions, indices);
    const floats = wasm.segmorph_decode_clip_bound(decoder, 0), out = allocate(floats * 4);
    pointers.push(out);
    check(wasm.segmorph_decode_targets(decoder, out, floats), 'targets');
    return { vertexCount: wasm.segmorph_decoder_vertex_count(decoder),
             targetCount: wasm.segmorph_decoder_frame_count(decoder, 0), deltas: floatsOut(out, floats) };
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

// Frame by frame: a decoder that holds the stream and one frame (vertex count × 3 floats) in the module's memory and
// decodes the next frame on demand, for a player that must not hold every frame. dispose() frees it.
class StreamDecoder {
  constructor(stream, positions, indices) {
    requireReady();
    this._decoder = wasm.segmorph_decoder_create();
    if (this._decoder === 0) throw new Error('segmorph: out of memory');
    this._pointers = [];
    try {
      open(this._decoder, (status, what) => this._check(status, what), this._pointers, stream, positions, indices);
      // The decoder copied its inputs: free them now, keep one frame.
      for (const pointer of this._pointers) wasm.segmorph_wasm_free(pointer);
      this._pointers = [];
      this.vertexCount = wasm.segmorph_decoder_vertex_count(this._decoder);
      this.clipCount = wasm.segmorph_decoder_clip_count(this._decoder);
      this.version = wasm.segmorph_decoder_stream_version(this._decoder);
      this._frame = allocate(this.vertexCount * 12);
      this._pointers = [this._frame];
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
      if (data.error) request.reject(new Error(data.error));
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
  decodeStream,
  decodeTargets,
  decodeTracks,
  createStreamDecoder: (stream, positions, indices) => new StreamDecoder(stream, positions, indices),
  useWorkers,
  decodeStreamAsync: (...args) => inWorker('decodeStream', args),
  decodeTargetsAsync: (...args) => inWorker('decodeTargets', args),
  decodeTracksAsync: (...args) => inWorker('decodeTracks', args),
  // The library's version (major × 1000 + minor × 10 + patch), once ready.
  get version() { requireReady(); return wasm.segmorph_version(); },
};

export const SegmorphDecoder = api;
export { StreamDecoder };
