// Large files, whole commands: production-size skinned characters (many skinned primitives, as a game character
// split by material is), encoded with their skins kept and baked into frames, next to gltfpack on the same file;
// and production-size cloth-like sequences as glTF one-hot morph targets, the form vertex caches reach glTF in.
// The harness writes the many-primitive files from a shared sample: copies of its skinned mesh, each with positions
// of its own (a small offset per copy), so that no tool can merge them as one mesh. It writes the sequences with
// bench/codec_scaling (its torus, as an OBJ + PC2 vertex cache) and segmorph bake.

import { mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { deliveredBytes, fileBytes, progress } from './tools.mjs';
import { SPEED_ERROR, SPEED_GLTFPACK_BITS, repeated } from './speed.mjs';

export const LARGE = {
  full: { repeats: 3, sources: ['gltf/RobotExpressive/RobotExpressive.glb'],
          copies: [{ source: 'gltf/CesiumMan/CesiumMan.glb', counts: [20, 60] }],
          sequences: { frames: 300, vertices: [50000, 100000, 200000] } },
  quick: { repeats: 1, sources: [], copies: [{ source: 'Fox/Fox.glb', counts: [3] }],
           sequences: { frames: 10, vertices: [2000] } },
};

// { json, bin } of a .glb (one JSON chunk, then at most one BIN chunk).
function readGlb(file) {
  const data = readFileSync(file);
  if (data.toString('latin1', 0, 4) !== 'glTF') throw new Error(`${file} is not a .glb`);
  const jsonLength = data.readUInt32LE(12);
  const json = JSON.parse(data.toString('utf8', 20, 20 + jsonLength));
  const binAt = 20 + jsonLength;
  const bin = binAt + 8 <= data.length ? data.subarray(binAt + 8, binAt + 8 + data.readUInt32LE(binAt)) : Buffer.alloc(0);
  return { json, bin };
}

function writeGlb(file, json, bin) {
  const pad = (buffer, byte) => Buffer.concat([buffer, Buffer.alloc((4 - (buffer.length % 4)) % 4, byte)]);
  const text = pad(Buffer.from(JSON.stringify(json)), 0x20), binary = pad(bin, 0);
  const header = Buffer.alloc(12), jsonHeader = Buffer.alloc(8), binHeader = Buffer.alloc(8);
  header.write('glTF', 0, 'latin1');
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + 8 + text.length + 8 + binary.length, 8);
  jsonHeader.writeUInt32LE(text.length, 0);
  jsonHeader.write('JSON', 4, 'latin1');
  binHeader.writeUInt32LE(binary.length, 0);
  binHeader.write('BIN\0', 4, 'latin1');
  writeFileSync(file, Buffer.concat([header, jsonHeader, text, binHeader, binary]));
}

// Writes `output`: `source` (a .glb) with `count` skinned primitives per skinned node, the original and count - 1
// copies of its node and mesh under the same skin, each copy's POSITION moved by copy × 0.1 % of the mesh's extent
// along x (float data of its own, appended to the buffer).
export function writeSkinnedCopies(source, count, output) {
  const { json, bin } = readGlb(source);
  const scene = json.scenes[json.scene ?? 0];
  const skinned = json.nodes.map((node, index) => ({ node, index })).filter(({ node }) => node.skin !== undefined && node.mesh !== undefined);
  const chunks = [bin];
  let length = bin.length;
  const addPositions = (accessorIndex, offset) => {
    const accessor = json.accessors[accessorIndex], view = json.bufferViews[accessor.bufferView];
    if (accessor.componentType !== 5126 || accessor.type !== 'VEC3' || accessor.sparse) throw new Error(`${source}: POSITION is not plain float VEC3`);
    const stride = view.byteStride || 12, start = (view.byteOffset || 0) + (accessor.byteOffset || 0);
    const values = new Float32Array(accessor.count * 3);
    for (let v = 0; v < accessor.count; v++)
      for (let c = 0; c < 3; c++) values[v * 3 + c] = bin.readFloatLE(start + v * stride + c * 4) + (c === 0 ? offset : 0);
    chunks.push(Buffer.alloc((4 - (length % 4)) % 4));
    length += (4 - (length % 4)) % 4;
    json.bufferViews.push({ buffer: 0, byteOffset: length, byteLength: values.byteLength, target: 34962 });
    chunks.push(Buffer.from(values.buffer));
    length += values.byteLength;
    const min = [0, 1, 2].map((c) => accessor.min[c] + (c === 0 ? offset : 0)), max = [0, 1, 2].map((c) => accessor.max[c] + (c === 0 ? offset : 0));
    json.accessors.push({ ...accessor, bufferView: json.bufferViews.length - 1, byteOffset: 0, min, max });
    return json.accessors.length - 1;
  };
  for (const { node } of skinned) {
    for (let copy = 1; copy < count; copy++) {
      const mesh = structuredClone(json.meshes[node.mesh]);
      for (const primitive of mesh.primitives) {
        const position = json.accessors[primitive.attributes.POSITION];
        const extent = Math.max(...[0, 1, 2].map((c) => position.max[c] - position.min[c]));
        primitive.attributes.POSITION = addPositions(primitive.attributes.POSITION, copy * 1e-3 * extent);
      }
      json.meshes.push({ ...mesh, name: `${mesh.name ?? 'mesh'} copy ${copy}` });
      json.nodes.push({ ...structuredClone(node), mesh: json.meshes.length - 1, name: `${node.name ?? 'node'} copy ${copy}` });
      scene.nodes.push(json.nodes.length - 1);
    }
  }
  if (json.buffers.length !== 1) throw new Error(`${source}: more than one buffer`);
  json.buffers[0].byteLength = length;
  writeGlb(output, json, Buffer.concat(chunks));
}

const pick = ({ wall_ms, cpu_ms, max_rss_kb }) => ({ wall_ms, cpu_ms, max_rss_kb });

// One large file: segmorph encode (skins kept, the default), segmorph bake, gltfpack -cc -af 0 -vp 12.
function measureLargeFile(tools, input, dir, repeats) {
  mkdirSync(dir, { recursive: true });
  const encoded = path.join(dir, 'encoded.glb'), baked = path.join(dir, 'baked.glb'), packed = path.join(dir, 'gltfpack.glb');
  const encode = repeated(tools, path.join(dir, 'encode.log'), 'segmorph',
                          ['encode', '-q', input, '-o', encoded, '--error', String(SPEED_ERROR), '--json'], repeats);
  if (!encode.ok) return { failed: `segmorph encode failed (${encode.log})` };
  const report = JSON.parse(encode.stdout.trim().split('\n').pop());
  const modes = {};
  for (const p of report.primitives) modes[p.mode] = (modes[p.mode] ?? 0) + 1;
  const vertexFrames = report.primitives.filter((p) => p.mode !== 'rigid').reduce((sum, p) => sum + p.vertices * p.frames, 0);
  const bake = repeated(tools, path.join(dir, 'bake.log'), 'segmorph', ['bake', '-q', input, '-o', baked], repeats);
  if (!bake.ok) return { failed: `segmorph bake failed (${bake.log})` };
  const gltfpack = repeated(tools, path.join(dir, 'gltfpack.log'), 'gltfpack',
                            ['-i', input, '-o', packed, '-cc', '-af', '0', '-vp', String(SPEED_GLTFPACK_BITS)], repeats);
  if (!gltfpack.ok) return { failed: `gltfpack failed (${gltfpack.log})` };
  return {
    input_bytes: fileBytes(input), modes, vertex_frames: vertexFrames,
    encode: { ...pick(encode), kg: report.kg_percent, bytes: deliveredBytes(encoded) },
    bake: { ...pick(bake), bytes: fileBytes(baked) },
    gltfpack: { ...pick(gltfpack), bytes: deliveredBytes(packed) },
  };
}

// One sequence of about `vertices` × `frames`, once each (the largest take minutes): written, baked from its cache,
// encoded, decoded; gltfpack on the glTF. Raw bytes only: brotli -q 11 of gltfpack's hundreds of MB takes minutes.
function measureSequence(tools, vertices, frames, dir) {
  mkdirSync(dir, { recursive: true });
  const prefix = path.join(dir, 'torus'), gltf = path.join(dir, 'torus.glb'), encoded = path.join(dir, 'encoded.glb');
  const write = tools.run(path.join(dir, 'write.log'), 'codec_scaling',
                          ['--vertices', String(vertices), '--frames', String(frames), '--write-cache', prefix]);
  if (!write.ok) return { failed: `codec_scaling --write-cache failed (${path.join(dir, 'write.log')})` };
  const steps = {
    bake: ['segmorph', ['bake', '-q', `${prefix}.obj`, '--cache', `${prefix}.pc2`, '-o', gltf]],
    encode: ['segmorph', ['encode', '-q', gltf, '-o', encoded, '--error', String(SPEED_ERROR), '--json']],
    decode: ['segmorph', ['decode', '-q', encoded, '-o', path.join(dir, 'decoded.glb')]],
    gltfpack: ['gltfpack', ['-i', gltf, '-o', path.join(dir, 'gltfpack.glb'), '-cc', '-af', '0', '-vp', String(SPEED_GLTFPACK_BITS)]],
  };
  const result = {};
  for (const [name, [command, args]] of Object.entries(steps)) {
    const run = repeated(tools, path.join(dir, `${name}.log`), command, args, 1);
    if (!run.ok) return { failed: `${name} failed (${run.log})` };
    result[name] = pick(run);
    if (name === 'encode') {
      const report = JSON.parse(run.stdout.trim().split('\n').pop());
      Object.assign(result.encode, { kg: report.kg_percent, vertices: report.primitives[0].vertices, frames: report.primitives[0].frames });
    }
    progress(`  sequence ${vertices} × ${frames}: ${name} ${(run.wall_ms / 1000).toFixed(1)} s`);
  }
  result.gltf_bytes = fileBytes(gltf);
  result.encode.bytes = fileBytes(encoded);
  result.gltfpack.bytes = fileBytes(path.join(dir, 'gltfpack.glb'));
  rmSync(gltf, { force: true });  // hundreds of MB each
  rmSync(path.join(dir, 'decoded.glb'), { force: true });
  rmSync(`${prefix}.pc2`, { force: true });
  return result;
}

// { repeats, files: [{ label, result }], sequences: [{ vertices, frames, result }] }: the plan's shared sources as
// they are, then its copies, then its sequences.
export function measureLarge(tools, samples, dir, plan) {
  mkdirSync(dir, { recursive: true });
  const files = [];
  for (const source of plan.sources) files.push({ label: source, file: path.join(samples, source) });
  for (const { source, counts } of plan.copies)
    for (const count of counts) {
      const file = path.join(dir, `${path.basename(source, '.glb')}-x${count}.glb`);
      try {
        writeSkinnedCopies(path.join(samples, source), count, file);
      } catch (error) {
        files.push({ label: `${source} × ${count}`, failed: error.message });
        continue;
      }
      files.push({ label: `${source} × ${count}`, file });
    }
  return {
    repeats: plan.repeats,
    files: files.map(({ label, file, failed }, i) => {
      progress(`large ${i + 1}/${files.length}: ${label}`);
      if (failed) return { label, result: { failed } };
      return { label, result: measureLargeFile(tools, file, path.join(dir, String(i + 1)), plan.repeats) };
    }),
    sequences: plan.sequences.vertices.map((vertices) => {
      progress(`large: sequence of ${vertices} vertices × ${plan.sequences.frames} frames`);
      return { vertices, frames: plan.sequences.frames,
               result: measureSequence(tools, vertices, plan.sequences.frames, path.join(dir, `sequence-${vertices}`)) };
    }),
  };
}
