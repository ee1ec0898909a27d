#!/usr/bin/env node
// Writes a copy of a glTF file with EXT_meshopt_compression and
// KHR_meshopt_compression undone, for readers that do not decode them
// (segmorph's loader refuses both).
//
//   node meshopt_decode.mjs IN.glb|IN.gltf OUT.glb
//
// Every bufferView is copied into the one buffer of OUT, the compressed ones
// decoded by the meshoptimizer decoder that three.js ships
// (examples/jsm/libs/meshopt_decoder.module.js), so the fallback buffers go.
// Nothing else changes: accessors keep their component types, so a file with
// KHR_mesh_quantization keeps it (and its dequantizing node transforms).
// The two extensions have the same JSON (buffer, byteOffset, byteLength,
// byteStride, count, mode, filter); KHR adds the attribute codec's version 1
// (header byte 0xa1, which gltfpack -cz writes) and the COLOR filter, both of
// which the decoder reads (it is built from meshoptimizer 1.1).
// Exit status: 0 on success, 1 when IN cannot be decoded, 2 on bad usage.

import { writeFile } from 'node:fs/promises';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { glbBytes, readAsset } from './glb.mjs';

const USAGE = 'usage: node meshopt_decode.mjs IN.glb|IN.gltf OUT.glb';
const EXTENSIONS = ['EXT_meshopt_compression', 'KHR_meshopt_compression'];

const args = process.argv.slice(2);
if (args.length !== 2 || args.some((a) => a.startsWith('-')) || !args[1].toLowerCase().endsWith('.glb')) {
  console.error(USAGE);
  process.exit(2);
}
const [input, output] = args;

try {
  const { json, buffers } = await readAsset(input);
  await MeshoptDecoder.ready;
  const parts = [];
  let length = 0;
  for (const [index, view] of (json.bufferViews || []).entries()) {
    const name = EXTENSIONS.find((e) => view.extensions && view.extensions[e]);
    const meshopt = name && view.extensions[name];
    const source = buffers[meshopt ? meshopt.buffer : view.buffer];
    if (!source) throw new Error(`bufferView ${index} names a buffer without data`);
    let bytes;
    if (meshopt) {
      const start = meshopt.byteOffset || 0;
      bytes = new Uint8Array(meshopt.count * meshopt.byteStride);
      MeshoptDecoder.decodeGltfBuffer(bytes, meshopt.count, meshopt.byteStride,
        source.subarray(start, start + meshopt.byteLength), meshopt.mode, meshopt.filter);
      delete view.extensions[name];
      if (Object.keys(view.extensions).length === 0) delete view.extensions;
    } else {
      const start = view.byteOffset || 0;
      bytes = source.subarray(start, start + view.byteLength);
    }
    length = Math.ceil(length / 16) * 16; // every component type stays aligned
    parts.push({ bytes, offset: length });
    view.buffer = 0;
    view.byteOffset = length;
    view.byteLength = bytes.length;
    length += bytes.length;
  }
  const bin = new Uint8Array(length);
  for (const { bytes, offset } of parts) bin.set(bytes, offset);
  json.buffers = length > 0 ? [{ byteLength: length }] : undefined;
  for (const list of ['extensionsUsed', 'extensionsRequired']) {
    if (!json[list]) continue;
    json[list] = json[list].filter((name) => !EXTENSIONS.includes(name));
    if (json[list].length === 0) delete json[list];
  }
  await writeFile(output, glbBytes(json, length > 0 ? bin : null));
} catch (err) {
  console.error(`meshopt_decode: ${input}: ${err && err.message ? err.message : err}`);
  process.exit(1);
}
