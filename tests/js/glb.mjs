// Reading and writing glTF containers in Node, shared by the scripts of tests/js.

import { writeFileSync } from 'node:fs';
import { readFile } from 'node:fs/promises';
import path from 'node:path';

const GLB_MAGIC = 0x46546c67; // 'glTF'
const CHUNK_JSON = 0x4e4f534a;
const CHUNK_BIN = 0x004e4942;

// Reads a .glb or .gltf file: the JSON and the bytes of every buffer
// (null for a buffer without data, e.g. an EXT_meshopt_compression fallback).
export async function readAsset(file) {
  const bytes = await readFile(file);
  const dir = path.dirname(path.resolve(file));
  let json;
  let glbBin = null;
  if (bytes.length >= 12 && bytes.readUInt32LE(0) === GLB_MAGIC) {
    const length = Math.min(bytes.readUInt32LE(8), bytes.length);
    for (let offset = 12; offset + 8 <= length; ) {
      const chunkLength = bytes.readUInt32LE(offset);
      const chunkType = bytes.readUInt32LE(offset + 4);
      const chunk = bytes.subarray(offset + 8, offset + 8 + chunkLength);
      if (chunkType === CHUNK_JSON && json === undefined) json = JSON.parse(chunk.toString('utf8'));
      else if (chunkType === CHUNK_BIN && glbBin === null) glbBin = chunk;
      offset += 8 + chunkLength;
    }
    if (json === undefined) throw new Error('GLB without JSON chunk');
  } else {
    json = JSON.parse(bytes.toString('utf8').replace(/^\uFEFF/, ''));
  }
  const buffers = [];
  for (const [i, buffer] of (json.buffers || []).entries()) {
    let data = null;
    if (buffer.uri === undefined) {
      if (i === 0 && glbBin !== null) data = glbBin;
    } else if (buffer.uri.startsWith('data:')) {
      const comma = buffer.uri.indexOf(',');
      const payload = buffer.uri.slice(comma + 1);
      data = /;base64$/i.test(buffer.uri.slice(0, comma))
        ? Buffer.from(payload, 'base64')
        : Buffer.from(decodeURIComponent(payload), 'latin1');
    } else {
      data = await readFile(path.resolve(dir, decodeURIComponent(buffer.uri)));
    }
    if (data !== null && data.length < buffer.byteLength) {
      throw new Error(`buffer ${i} has ${data.length} bytes, byteLength says ${buffer.byteLength}`);
    }
    buffers.push(data === null ? null : data.subarray(0, buffer.byteLength));
  }
  return { json, buffers };
}

// The bytes of a GLB holding `json` and, when `bin` is not null, `bin` as its
// BIN chunk (json.buffers[0] must then describe it, without uri).
export function glbBytes(json, bin) {
  const jsonBytes = Buffer.from(JSON.stringify(json), 'utf8');
  const jsonPadded = Math.ceil(jsonBytes.length / 4) * 4;
  const binPadded = bin === null ? 0 : Math.ceil(bin.length / 4) * 4;
  const total = 12 + 8 + jsonPadded + (bin === null ? 0 : 8 + binPadded);
  const glb = Buffer.alloc(total);
  glb.writeUInt32LE(GLB_MAGIC, 0);
  glb.writeUInt32LE(2, 4);
  glb.writeUInt32LE(total, 8);
  glb.writeUInt32LE(jsonPadded, 12);
  glb.writeUInt32LE(CHUNK_JSON, 16);
  jsonBytes.copy(glb, 20);
  glb.fill(0x20, 20 + jsonBytes.length, 20 + jsonPadded);
  if (bin !== null) {
    const binStart = 20 + jsonPadded;
    glb.writeUInt32LE(binPadded, binStart);
    glb.writeUInt32LE(CHUNK_BIN, binStart + 4);
    glb.set(bin, binStart + 8);
  }
  return glb;
}

// Two hostile copies of `asset` (readAsset's), written as DIRECTORY/damaged.glb and DIRECTORY/truncated.glb: the
// SEGMORPH_animation_compression stream of its first compressed primitive with its second half zeroed, and with its
// bufferView cut to half its length.
export function writeHostileStreams(asset, directory) {
  const primitive = asset.json.meshes.flatMap((m) => m.primitives).find((p) => p.extensions?.SEGMORPH_animation_compression);
  const index = primitive.extensions.SEGMORPH_animation_compression.bufferView, view = asset.json.bufferViews[index];
  const start = view.byteOffset ?? 0, buffer = asset.buffers[view.buffer ?? 0];
  const zeroed = Buffer.from(buffer);
  zeroed.fill(0, start + Math.floor(view.byteLength / 2), start + view.byteLength);
  writeFileSync(path.join(directory, 'damaged.glb'), glbBytes(asset.json, zeroed));
  const cut = structuredClone(asset.json);
  cut.bufferViews[index].byteLength = Math.floor(view.byteLength / 2);
  writeFileSync(path.join(directory, 'truncated.glb'), glbBytes(cut, buffer));
}

// The bytes of bufferView `index` of an asset readAsset() read.
export function viewBytes(asset, index) {
  const view = asset.json.bufferViews[index];
  return asset.buffers[view.buffer].subarray(view.byteOffset ?? 0, (view.byteOffset ?? 0) + view.byteLength);
}

// The base mesh of a KHR_draco_mesh_compression `extension` as a page's Draco decoder gives it: POSITION in point
// order, the faces. `draco`: the draco3dgltf decoder module.
export function dracoBase(draco, asset, extension) {
  const bytes = viewBytes(asset, extension.bufferView);
  const decoder = new draco.Decoder(), buffer = new draco.DecoderBuffer();
  buffer.Init(new Int8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength), bytes.byteLength);
  const mesh = new draco.Mesh();
  const status = decoder.DecodeBufferToMesh(buffer, mesh);
  if (!status.ok()) throw new Error(`Draco: ${status.error_msg()}`);
  const attribute = decoder.GetAttributeByUniqueId(mesh, extension.attributes.POSITION);
  const points = mesh.num_points(), floats = points * 3, faces = mesh.num_faces();
  let pointer = draco._malloc(floats * 4);
  decoder.GetAttributeDataArrayForAllPoints(mesh, attribute, draco.DT_FLOAT32, floats * 4, pointer);
  const positions = new Float32Array(draco.HEAPF32.buffer, pointer, floats).slice();
  draco._free(pointer);
  pointer = draco._malloc(faces * 12);
  decoder.GetTrianglesUInt32Array(mesh, faces * 12, pointer);
  const indices = new Uint32Array(draco.HEAPU32.buffer, pointer, faces * 3).slice();
  draco._free(pointer);
  for (const object of [mesh, buffer, decoder]) draco.destroy(object);
  return { positions, indices };
}
