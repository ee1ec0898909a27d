// Loading glTF files into three.js scenes in plain Node, shared by compare_three.mjs and resampled_three.mjs:
// textures stripped (no DOM), every buffer packed into one in-memory GLB (GLTFLoader fetches nothing),
// EXT_meshopt_compression decoded by three's MeshoptDecoder; then the objects of a node's primitives, the node of
// an object, and rotations of unit length.

import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { glbBytes, readAsset } from './glb.mjs';

const TEXTURE_EXTENSIONS = ['KHR_texture_transform', 'KHR_texture_basisu', 'EXT_texture_webp', 'EXT_texture_avif'];

// Removes everything that would make GLTFLoader load an image: there is no
// DOM in Node, and only geometry matters here. Indices of other objects are
// unchanged (only images, textures and samplers are dropped).
export function stripTextures(json) {
  delete json.images;
  delete json.textures;
  delete json.samplers;
  const strip = (object) => {
    if (object === null || typeof object !== 'object') return;
    for (const key of Object.keys(object)) {
      // textureInfo properties: baseColorTexture, normalTexture, clearcoatTexture, ...
      if (/texture$/i.test(key) && object[key] && typeof object[key] === 'object' && 'index' in object[key]) {
        delete object[key];
      } else strip(object[key]);
    }
  };
  (json.materials || []).forEach(strip);
  for (const list of ['extensionsUsed', 'extensionsRequired']) {
    if (json[list]) json[list] = json[list].filter((name) => !TEXTURE_EXTENSIONS.includes(name));
  }
}

// Builds a GLB whose single BIN chunk holds every buffer that has data, so that
// GLTFLoader never has to fetch anything (Node's fetch cannot read files).
// Buffers without data (meshopt fallbacks) stay as separate buffers.
export function buildGlb(json, buffers) {
  const remap = [];
  const parts = [];
  let binLength = 0;
  const newBuffers = buffers.length > 0 ? [{ byteLength: 0 }] : [];
  buffers.forEach((data, i) => {
    if (data === null) {
      const { uri, ...rest } = json.buffers[i];
      remap.push({ buffer: newBuffers.length, offset: 0 });
      newBuffers.push(rest);
    } else {
      binLength = Math.ceil(binLength / 16) * 16; // keep every accessor aligned
      remap.push({ buffer: 0, offset: binLength });
      parts.push({ data, offset: binLength });
      binLength += data.length;
    }
  });
  if (newBuffers.length > 0) newBuffers[0].byteLength = binLength;
  for (const view of json.bufferViews || []) {
    const r = remap[view.buffer];
    view.buffer = r.buffer;
    if (r.buffer === 0) view.byteOffset = (view.byteOffset || 0) + r.offset;
    const meshopt = view.extensions && view.extensions.EXT_meshopt_compression;
    if (meshopt) {
      const m = remap[meshopt.buffer];
      meshopt.buffer = m.buffer;
      if (m.buffer === 0) meshopt.byteOffset = (meshopt.byteOffset || 0) + m.offset;
    }
  }
  if (newBuffers.length > 0) json.buffers = newBuffers;

  const bin = new Uint8Array(binLength);
  for (const { data, offset } of parts) bin.set(data, offset);
  const glb = glbBytes(json, newBuffers.length > 0 ? bin : null);
  return { glb: glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength), bin };
}

export async function loadGltf(file) {
  try {
    return await loadGltfUnchecked(file);
  } catch (err) {
    throw new Error(`${file}: ${err && err.message ? err.message : err}`);
  }
}

async function loadGltfUnchecked(file) {
  const { json, buffers } = await readAsset(file);
  stripTextures(json);
  const { glb, bin } = buildGlb(json, buffers);
  // `bin` is our own copy of the merged buffer, read by readAccessor: GLTFLoader's
  // accessors are views into its cached bufferViews, and GLTFParser.loadMesh
  // normalizes WEIGHTS_0 in place (SkinnedMesh.normalizeSkinWeights), so after
  // loading, the parser's bufferViews no longer hold the file's weights.
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.parseAsync(glb, '');
  const json2 = gltf.parser.json; // same indices as the file
  const nodeObjects = new Map(); // glTF node index -> Object3D
  for (const [object, assoc] of gltf.parser.associations) {
    if (object.isObject3D && assoc.nodes !== undefined) nodeObjects.set(assoc.nodes, object);
  }
  return { file, gltf, json: json2, bin, parser: gltf.parser, scene: gltf.scene, clips: gltf.animations, nodeObjects };
}

// The three objects drawing the primitives of a glTF node's mesh, indexed by
// primitive. A node with one primitive is the Mesh itself; with several, it is
// a Group whose children are the Meshes (GLTFParser.loadMesh); a joint node with
// a mesh is a Bone with the mesh as a child.
export function primitiveObjects(asset, nodeIndex) {
  const nodeDef = asset.json.nodes[nodeIndex];
  const nodeObject = asset.nodeObjects.get(nodeIndex);
  const result = [];
  if (nodeDef.mesh === undefined || !nodeObject) return result;
  const visit = (object) => {
    const assoc = asset.parser.associations.get(object);
    if (object !== nodeObject && assoc && assoc.nodes !== undefined) return; // a child glTF node
    if (assoc && assoc.meshes === nodeDef.mesh && assoc.primitives !== undefined) result[assoc.primitives] = object;
    object.children.forEach(visit);
  };
  visit(nodeObject);
  return result;
}

// The glTF node an object belongs to (the object itself or the Group above it).
export function owningNode(asset, object) {
  for (let o = object; o; o = o.parent) {
    const assoc = asset.parser.associations.get(o);
    if (assoc && assoc.nodes !== undefined) return { index: assoc.nodes, object: o };
  }
  return null;
}

// three uses rotation keys and node rotations as stored: a quaternion that is
// not of unit length (SimpleSkin's keys are off by up to 2.3e-4) makes a
// non-rigid matrix (Quaternion.slerpFlat returns the key itself at a key time,
// Matrix4.compose does not normalize). --normalize-rotations normalizes them
// first, for comparing with a converter that normalizes.
export function normalizeRotations(asset) {
  for (const clip of asset.gltf.animations) {
    for (const track of clip.tracks) {
      if (!(track instanceof THREE.QuaternionKeyframeTrack)) continue;
      const v = track.values;
      for (let i = 0; i + 3 < v.length; i += 4) {
        const n = Math.hypot(v[i], v[i + 1], v[i + 2], v[i + 3]);
        if (n > 0) for (let k = 0; k < 4; k++) v[i + k] /= n;
      }
    }
  }
  asset.scene.traverse((o) => o.quaternion.normalize());
}
