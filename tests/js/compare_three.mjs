#!/usr/bin/env node
// Compares what three.js shows for a glTF file and for its `segmorph bake` output.
//
//   node compare_three.mjs ORIGINAL BAKED [--tolerance 1e-5] [--json] [--self]
//                          [--reference three|spec] [--require-coverage]
//                          [--normalize-rotations]
//
// Both files are loaded with three's GLTFLoader in plain Node. For every clip of
// BAKED and every mesh object that has a morphTargetInfluences track in that
// clip, both scenes are posed at each keyframe time of that track, and the
// world-space position of every vertex of the baked primitive is compared with
// the same vertex of the same primitive of the original node (the baked node
// names it in extras.segmorph.source_node). The score of a (clip, node,
// primitive) is the largest vertex distance over its frames divided by the
// bounding-box diagonal of the original primitive at its first compared frame.
//
// Skinned originals are evaluated twice:
//   three: SkinnedMesh.getVertexPosition() then matrixWorld, i.e. exactly what
//          three renders (GLTFLoader normalizes the skin weights on load);
//   spec:  the glTF 2.0 formula sum_j w_j * (globalTransform(joint_j) * IBM_j) * p
//          with the skinned node's own transform ignored, using three's posed
//          joint matrixWorld, the inverse bind matrices and the JOINTS_n/WEIGHTS_n
//          read from the file (raw, not normalized, all sets).
// The rows also give, for the ORIGINAL alone, three vs spec and three vs the
// spec formula fed with three's normalized weights (which isolates three's
// bindMatrix convention from its weight normalization).
//
// Options:
//   --tolerance X          largest allowed score (default 1e-5)
//   --json                 print one JSON object instead of the table
//   --reference three|spec which evaluation of a skinned original decides the
//                          exit status (default three)
//   --require-coverage     also fail when a clip deforms a skinned or morphed
//                          node of ORIGINAL that no baked node (source_node) is
//                          animated for in that clip (otherwise only reported)
//   --normalize-rotations  normalize rotation keys and node rotations of both
//                          files before posing (three uses non-unit quaternions
//                          as stored)
//   --self                 for a BAKED without segmorph extras (e.g. ORIGINAL
//                          itself): node i is compared with node i, for every mesh
//                          node the clip moves, at the union of the clip's key times
//
// Exit status: 0 if every score <= tolerance, 1 otherwise (also when nothing
// was compared although ORIGINAL has deforming animation), 2 on usage or load
// errors.

import * as THREE from 'three';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { loadGltf, normalizeRotations, owningNode, primitiveObjects } from './three_scene.mjs';

const USAGE =
  'usage: node compare_three.mjs ORIGINAL BAKED [--tolerance 1e-5] [--json] [--self] ' +
  '[--reference three|spec] [--require-coverage] [--normalize-rotations]';

class UsageError extends Error {}

// ---------------------------------------------------------------- arguments

function parseArgs(argv) {
  const opts = { tolerance: 1e-5, json: false, self: false, reference: 'three', requireCoverage: false, normalizeRotations: false, files: [] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) throw new UsageError(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--tolerance') {
      opts.tolerance = Number(value());
      if (!Number.isFinite(opts.tolerance) || opts.tolerance < 0) throw new UsageError('bad --tolerance');
    } else if (a === '--json') opts.json = true;
    else if (a === '--self') opts.self = true;
    else if (a === '--require-coverage') opts.requireCoverage = true;
    else if (a === '--normalize-rotations') opts.normalizeRotations = true;
    else if (a === '--reference') {
      opts.reference = value();
      if (opts.reference !== 'three' && opts.reference !== 'spec') throw new UsageError('--reference is three or spec');
    } else if (a === '--help' || a === '-h') {
      console.log(USAGE);
      process.exit(0);
    } else if (a.startsWith('--')) throw new UsageError(`unknown option ${a}`);
    else opts.files.push(a);
  }
  if (opts.files.length !== 2) throw new UsageError('need ORIGINAL and BAKED');
  return opts;
}

// ---------------------------------------------------------------- loading

// (three_scene.mjs: stripTextures, buildGlb, loadGltf, primitiveObjects, owningNode)

// ---------------------------------------------------------------- accessors

const COMPONENTS = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4, MAT2: 4, MAT3: 9, MAT4: 16 };
const COMPONENT_TYPES = {
  5120: { size: 1, get: 'getInt8', norm: (x) => Math.max(x / 127, -1) },
  5121: { size: 1, get: 'getUint8', norm: (x) => x / 255 },
  5122: { size: 2, get: 'getInt16', norm: (x) => Math.max(x / 32767, -1) },
  5123: { size: 2, get: 'getUint16', norm: (x) => x / 65535 },
  5125: { size: 4, get: 'getUint32', norm: (x) => x },
  5126: { size: 4, get: 'getFloat32', norm: (x) => x },
};

// The bytes of a bufferView as stored in the file (meshopt-decoded if needed).
async function bufferViewBytes(asset, viewIndex) {
  const view = asset.json.bufferViews[viewIndex];
  const meshopt = view.extensions && view.extensions.EXT_meshopt_compression;
  if (meshopt) {
    await MeshoptDecoder.ready;
    const source = asset.bin.subarray(meshopt.byteOffset || 0, (meshopt.byteOffset || 0) + meshopt.byteLength);
    const out = new Uint8Array(meshopt.count * meshopt.byteStride);
    MeshoptDecoder.decodeGltfBuffer(out, meshopt.count, meshopt.byteStride, source, meshopt.mode, meshopt.filter);
    return out.buffer;
  }
  if (view.buffer !== 0) throw new Error(`bufferView ${viewIndex} has no data`);
  const start = view.byteOffset || 0;
  return asset.bin.slice(start, start + view.byteLength).buffer;
}

// Reads an accessor into a Float64Array straight from the file's bytes. Used
// for skin data, so that the spec evaluation sees the file's weights and not
// the ones GLTFLoader normalized (see the note in loadGltf).
async function readAccessor(asset, index) {
  const acc = asset.json.accessors[index];
  const n = COMPONENTS[acc.type];
  const ct = COMPONENT_TYPES[acc.componentType];
  const out = new Float64Array(acc.count * n);
  const readInto = async (viewIndex, byteOffset, count, components, type, normalized, target, targetIndex) => {
    const view = asset.json.bufferViews[viewIndex];
    const data = await bufferViewBytes(asset, viewIndex);
    const dv = new DataView(data);
    const stride = view.byteStride || components * type.size;
    for (let i = 0; i < count; i++) {
      for (let c = 0; c < components; c++) {
        const x = dv[type.get](byteOffset + i * stride + c * type.size, true);
        target[(targetIndex ? targetIndex[i] : i) * components + c] = normalized ? type.norm(x) : x;
      }
    }
  };
  if (acc.bufferView !== undefined) {
    await readInto(acc.bufferView, acc.byteOffset || 0, acc.count, n, ct, acc.normalized === true, out, null);
  }
  if (acc.sparse) {
    const s = acc.sparse;
    const idx = new Float64Array(s.count);
    await readInto(s.indices.bufferView, s.indices.byteOffset || 0, s.count, 1, COMPONENT_TYPES[s.indices.componentType], false, idx, null);
    await readInto(s.values.bufferView, s.values.byteOffset || 0, s.count, n, ct, acc.normalized === true, out, idx);
  }
  return out;
}

// Skin data of a skinned original primitive, for the spec evaluation.
async function skinInfo(asset, nodeIndex, primitiveIndex) {
  const nodeDef = asset.json.nodes[nodeIndex];
  if (nodeDef.skin === undefined) return null;
  const skin = asset.json.skins[nodeDef.skin];
  const prim = asset.json.meshes[nodeDef.mesh].primitives[primitiveIndex];
  const joints = skin.joints.map((j) => {
    const o = asset.nodeObjects.get(j);
    if (!o) throw new Error(`joint node ${j} is not in the scene`);
    return o;
  });
  const ibm = skin.inverseBindMatrices === undefined ? null : await readAccessor(asset, skin.inverseBindMatrices);
  const inverseBind = joints.map((_, j) => (ibm ? new THREE.Matrix4().fromArray(ibm, j * 16) : new THREE.Matrix4()));
  const sets = [];
  for (let s = 0; prim.attributes[`JOINTS_${s}`] !== undefined && prim.attributes[`WEIGHTS_${s}`] !== undefined; s++) {
    sets.push({
      joints: await readAccessor(asset, prim.attributes[`JOINTS_${s}`]),
      weights: await readAccessor(asset, prim.attributes[`WEIGHTS_${s}`]),
    });
  }
  const count = asset.json.accessors[prim.attributes.POSITION].count;
  let nonNormalized = 0;
  let worstSum = 1;
  for (let v = 0; v < count; v++) {
    let sum = 0;
    for (const set of sets) for (let k = 0; k < 4; k++) sum += set.weights[v * 4 + k];
    if (Math.abs(sum - 1) > 2e-7 * 4 * sets.length) nonNormalized++;
    if (Math.abs(sum - 1) > Math.abs(worstSum - 1)) worstSum = sum;
  }
  return { skinIndex: nodeDef.skin, joints, inverseBind, sets, nonNormalized, worstSum };
}

// ---------------------------------------------------------------- posing

// Poses a loaded scene at time t of one of its clips, from the rest state:
// properties the clip does not animate keep their rest value, as glTF specifies
// (a long-lived mixer would keep values left there by an earlier clip).
//
// A fresh AnimationMixer per pose, on purpose: PropertyMixer.apply() only writes
// a property when its value differs from the one the mixer wrote at the previous
// update, so reusing a mixer after putting the scene back to rest leaves every
// property whose value did not change since the previous pose at its rest value.
// A new mixer takes the rest state as its reference (saveOriginalState) and
// writes everything that differs from it.
class Poser {
  constructor(asset) {
    this.asset = asset;
    this.mixer = null;
    this.rest = [];
    asset.scene.traverse((o) => {
      this.rest.push({
        o,
        position: o.position.clone(),
        quaternion: o.quaternion.clone(),
        scale: o.scale.clone(),
        morph: o.morphTargetInfluences ? o.morphTargetInfluences.slice() : null,
      });
    });
  }

  pose(clip, t) {
    const root = this.asset.scene;
    if (this.mixer) {
      this.mixer.stopAllAction();
      this.mixer.uncacheRoot(root);
    }
    for (const r of this.rest) {
      r.o.position.copy(r.position);
      r.o.quaternion.copy(r.quaternion);
      r.o.scale.copy(r.scale);
      if (r.morph) r.o.morphTargetInfluences.splice(0, r.morph.length, ...r.morph);
    }
    this.mixer = new THREE.AnimationMixer(root);
    const action = this.mixer.clipAction(clip);
    // LoopOnce + clampWhenFinished: t == duration gives the last key, not the first.
    action.setLoop(THREE.LoopOnce, 1);
    action.clampWhenFinished = true;
    action.play();
    this.mixer.setTime(t);
    // Updates every matrixWorld, and SkinnedMesh.bindMatrixInverse with it.
    // Skeleton.update() (bone matrices for the GPU) is not needed:
    // getVertexPosition reads the bones' matrixWorld directly.
    root.updateMatrixWorld(true);
  }
}


// ---------------------------------------------------------------- evaluation

const _v = new THREE.Vector3();
const _p = new THREE.Vector3();

// What three renders: morph, then skinning as SkinnedMesh.applyBoneTransform does
// (bindMatrixInverse * sum w * boneMatrixWorld * boneInverse * bindMatrix * p),
// then the object's matrixWorld, as the vertex shader's modelMatrix does.
function positionsThree(object, out) {
  const count = object.geometry.attributes.position.count;
  const m = object.matrixWorld;
  for (let i = 0; i < count; i++) {
    if (object.isMesh) object.getVertexPosition(i, _v);
    else THREE.Mesh.prototype.getVertexPosition.call(object, i, _v); // points, lines: morph only
    _v.applyMatrix4(m);
    out[3 * i] = _v.x;
    out[3 * i + 1] = _v.y;
    out[3 * i + 2] = _v.z;
  }
}

// glTF 2.0 skinning: world = sum_j w_j * (globalTransform(joint_j) * IBM_j) * p;
// the skinned node's own transform is ignored. p is the morphed local position
// (Mesh.getVertexPosition, without the SkinnedMesh override). `sets` are the
// raw file weights, or three's normalized skinIndex/skinWeight attributes.
function positionsSpec(object, skin, sets, out) {
  const matrices = skin.joints.map((joint, j) => new THREE.Matrix4().multiplyMatrices(joint.matrixWorld, skin.inverseBind[j]).elements);
  const count = object.geometry.attributes.position.count;
  for (let i = 0; i < count; i++) {
    THREE.Mesh.prototype.getVertexPosition.call(object, i, _p);
    let x = 0;
    let y = 0;
    let z = 0;
    for (const set of sets) {
      for (let k = 0; k < 4; k++) {
        const w = set.weights[4 * i + k];
        if (w === 0) continue;
        const e = matrices[set.joints[4 * i + k]];
        x += w * (e[0] * _p.x + e[4] * _p.y + e[8] * _p.z + e[12]);
        y += w * (e[1] * _p.x + e[5] * _p.y + e[9] * _p.z + e[13]);
        z += w * (e[2] * _p.x + e[6] * _p.y + e[10] * _p.z + e[14]);
      }
    }
    out[3 * i] = x;
    out[3 * i + 1] = y;
    out[3 * i + 2] = z;
  }
}

function threeWeightSets(object) {
  const { skinIndex, skinWeight } = object.geometry.attributes;
  const joints = new Float64Array(skinIndex.count * 4);
  const weights = new Float64Array(skinWeight.count * 4);
  for (let i = 0; i < skinIndex.count; i++) {
    for (let k = 0; k < 4; k++) {
      joints[4 * i + k] = skinIndex.getComponent(i, k);
      weights[4 * i + k] = skinWeight.getComponent(i, k);
    }
  }
  return [{ joints, weights }];
}

// Largest vertex distance between two position arrays, and the vertex where it is.
function maxDistance(a, b) {
  let max = 0;
  let vertex = -1;
  for (let i = 0; i < a.length; i += 3) {
    const d = Math.hypot(a[i] - b[i], a[i + 1] - b[i + 1], a[i + 2] - b[i + 2]);
    if (!(d <= max)) {
      max = d; // also catches NaN
      vertex = i / 3;
    }
  }
  return { max, vertex };
}

function diagonal(a) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < a.length; i += 3) {
    for (let c = 0; c < 3; c++) {
      lo[c] = Math.min(lo[c], a[i + c]);
      hi[c] = Math.max(hi[c], a[i + c]);
    }
  }
  return Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

// ---------------------------------------------------------------- what to compare

function trackTargets(asset, clip) {
  return clip.tracks.map((track) => {
    const parsed = THREE.PropertyBinding.parseTrackName(track.name);
    return { track, object: THREE.PropertyBinding.findNode(asset.scene, parsed.nodeName), property: parsed.propertyName };
  });
}

// Mesh nodes of ORIGINAL whose vertices the bake must cover for a clip: a
// weights track on the node, or a skinned node one of whose joints (or a joint's
// ancestor) the clip animates. With `rigid`, also nodes moved only through
// their own or an ancestor's transform (used by --self).
function movedMeshNodes(asset, clip, rigid) {
  const targets = trackTargets(asset, clip);
  const animated = new Set(targets.filter((t) => t.object && t.property !== 'morphTargetInfluences').map((t) => t.object));
  const morphed = new Set(targets.filter((t) => t.object && t.property === 'morphTargetInfluences').map((t) => t.object));
  const movedByAncestry = (object) => {
    for (let o = object; o; o = o.parent) if (animated.has(o)) return true;
    return false;
  };
  const result = new Set();
  asset.json.nodes.forEach((nodeDef, n) => {
    if (nodeDef.mesh === undefined || !asset.nodeObjects.has(n)) return;
    const prims = primitiveObjects(asset, n);
    if (prims.some((p) => morphed.has(p))) result.add(n);
    else if (nodeDef.skin !== undefined && asset.json.skins[nodeDef.skin].joints.some((j) => movedByAncestry(asset.nodeObjects.get(j)))) result.add(n);
    else if (rigid && movedByAncestry(asset.nodeObjects.get(n))) result.add(n);
  });
  return result;
}

// The (baked node, source node, primitive, times) to compare for one clip.
function comparisonsForClip(baked, clip, self, warnings, clipIndex) {
  const pairs = [];
  if (self) {
    const times = [...new Set(clip.tracks.flatMap((t) => Array.from(t.times)))].sort((a, b) => a - b);
    for (const n of movedMeshNodes(baked, clip, true)) {
      primitiveObjects(baked, n).forEach((object, p) => pairs.push({ bakedNode: n, sourceNode: n, primitive: p, object, times }));
    }
    return pairs;
  }
  for (const { track, object, property } of trackTargets(baked, clip)) {
    if (property !== 'morphTargetInfluences') continue;
    if (!object) {
      warnings.push(`clip ${clipIndex}: track ${track.name} targets no object`);
      continue;
    }
    const node = owningNode(baked, object);
    const assoc = baked.parser.associations.get(object);
    const source = node && node.object.userData.segmorph ? node.object.userData.segmorph.source_node : undefined;
    if (source === undefined) {
      warnings.push(`clip ${clipIndex}: weights track on node ${node ? node.index : '?'} without extras.segmorph.source_node, not compared`);
      continue;
    }
    pairs.push({ bakedNode: node.index, sourceNode: source, primitive: assoc.primitives, object, times: Array.from(track.times) });
  }
  return pairs;
}

// ---------------------------------------------------------------- main

function isIdentity(m) {
  return m.equals(new THREE.Matrix4());
}

async function compare(opts) {
  const [originalFile, bakedFile] = opts.files;
  const original = await loadGltf(originalFile);
  const baked = await loadGltf(bakedFile);
  if (opts.normalizeRotations) {
    normalizeRotations(original);
    normalizeRotations(baked);
  }

  const hasExtras = baked.json.nodes && baked.json.nodes.some((n) => n.extras && n.extras.segmorph && n.extras.segmorph.source_node !== undefined);
  if (!hasExtras && !opts.self) {
    throw new UsageError(`${bakedFile} has no extras.segmorph.source_node on any node (use --self to compare node i with node i)`);
  }
  const self = opts.self;

  const warnings = [];
  const rows = [];
  const uncovered = [];
  const skinCache = new Map();
  const originalPoser = new Poser(original);
  const bakedPoser = new Poser(baked);

  const originalClips = original.gltf.animations;
  const bakedClips = baked.gltf.animations;
  for (let c = 0; c < Math.max(originalClips.length, bakedClips.length); c++) {
    const oc = originalClips[c];
    const bc = bakedClips[c];
    if (!oc) {
      warnings.push(`clip ${c} (${bc.name}) of BAKED has no clip ${c} in ORIGINAL`);
      continue;
    }
    if (bc && bc.name !== oc.name) warnings.push(`clip ${c} is "${oc.name}" in ORIGINAL but "${bc.name}" in BAKED`);
    const pairs = bc ? comparisonsForClip(baked, bc, self, warnings, c) : [];

    // Coverage: every mesh node of ORIGINAL that this clip deforms has a baked node.
    const covered = new Set(pairs.map((p) => p.sourceNode));
    for (const n of movedMeshNodes(original, oc, false)) if (!covered.has(n)) uncovered.push({ clip: c, clipName: oc.name, sourceNode: n });
    if (pairs.length === 0) continue;

    const clipRows = [];
    for (const pair of pairs) {
      const originalObject = primitiveObjects(original, pair.sourceNode)[pair.primitive];
      const row = {
        clip: c,
        clipName: oc.name,
        bakedNode: pair.bakedNode,
        sourceNode: pair.sourceNode,
        primitive: pair.primitive,
        vertices: pair.object.geometry.attributes.position.count,
        frames: pair.times.length,
        skinned: false,
        error: null,
      };
      rows.push(row);
      if (!originalObject) {
        row.error = `ORIGINAL node ${pair.sourceNode} has no primitive ${pair.primitive}`;
        continue;
      }
      if (originalObject.geometry.attributes.position.count !== row.vertices) {
        row.error = `vertex count ${row.vertices} != ${originalObject.geometry.attributes.position.count} in ORIGINAL`;
        continue;
      }
      let skin = null;
      if (originalObject.isSkinnedMesh) {
        const key = `${pair.sourceNode}/${pair.primitive}`;
        if (!skinCache.has(key)) skinCache.set(key, await skinInfo(original, pair.sourceNode, pair.primitive));
        skin = skinCache.get(key);
      }
      row.skinned = skin !== null;
      const n3 = row.vertices * 3;
      clipRows.push({
        row,
        pair,
        originalObject,
        skin,
        threeSets: skin ? threeWeightSets(originalObject) : null,
        buf: { baked: new Float64Array(n3), three: new Float64Array(n3), spec: new Float64Array(n3), specNorm: new Float64Array(n3) },
        max: { three: 0, spec: 0, threeVsSpec: 0, convention: 0 },
        diag: null,
      });
    }

    // Pose each scene once per distinct time, then evaluate every pair keyed there.
    const byTime = new Map();
    for (const cr of clipRows) {
      for (const t of cr.pair.times) {
        if (!byTime.has(t)) byTime.set(t, []);
        byTime.get(t).push(cr);
      }
    }
    for (const t of [...byTime.keys()].sort((a, b) => a - b)) {
      originalPoser.pose(oc, t);
      bakedPoser.pose(bc, t);
      for (const cr of byTime.get(t)) {
        const { buf, max } = cr;
        positionsThree(cr.pair.object, buf.baked);
        positionsThree(cr.originalObject, buf.three);
        if (cr.skin) {
          positionsSpec(cr.originalObject, cr.skin, cr.skin.sets, buf.spec);
          positionsSpec(cr.originalObject, cr.skin, cr.threeSets, buf.specNorm);
        }
        const spec = cr.skin ? buf.spec : buf.three;
        if (cr.diag === null) cr.diag = { three: diagonal(buf.three), spec: diagonal(spec) };
        const d = maxDistance(buf.baked, buf.three);
        if (!(d.max <= max.three)) {
          max.three = d.max;
          cr.worst = { time: t, vertex: d.vertex }; // where the baked file is furthest from three
        }
        max.spec = Math.max(max.spec, maxDistance(buf.baked, spec).max);
        if (cr.skin) {
          max.threeVsSpec = Math.max(max.threeVsSpec, maxDistance(buf.three, buf.spec).max);
          max.convention = Math.max(max.convention, maxDistance(buf.three, buf.specNorm).max);
        }
      }
    }
    for (const cr of clipRows) {
      const { row, max, diag } = cr;
      const scale = (d) => (d > 0 ? d : 1); // a degenerate primitive: absolute distances
      row.diagonal = diag.three;
      row.maxDistance = max.three;
      row.worstTime = cr.worst ? cr.worst.time : null;
      row.worstVertex = cr.worst ? cr.worst.vertex : null;
      row.ratio = max.three / scale(diag.three);
      row.ratioSpec = max.spec / scale(diag.spec);
      if (cr.skin) {
        // three vs the spec formula, both on ORIGINAL: with the file's raw weights,
        // and with three's normalized weights (isolates the bind-matrix convention).
        row.originalThreeVsSpec = max.threeVsSpec / scale(diag.three);
        row.originalConvention = max.convention / scale(diag.three);
        row.skin = {
          skin: cr.skin.skinIndex,
          weightSets: cr.skin.sets.length,
          nonNormalizedVertices: cr.skin.nonNormalized,
          worstWeightSum: cr.skin.worstSum,
          bindMode: cr.originalObject.bindMode,
          bindMatrixIsIdentity: isIdentity(cr.originalObject.bindMatrix),
          nodeMatrixWorldIsIdentity: isIdentity(cr.originalObject.matrixWorld),
        };
      }
    }
  }

  const scoreOf = (row) => (row.error ? Infinity : opts.reference === 'spec' ? row.ratioSpec : row.ratio);
  let worst = null;
  for (const row of rows) {
    row.pass = scoreOf(row) <= opts.tolerance;
    if (!worst || !(scoreOf(row) <= scoreOf(worst))) worst = row;
  }
  const failures = [];
  if (rows.some((r) => !r.pass)) failures.push('a score exceeds the tolerance or a primitive could not be compared');
  if (rows.length === 0 && uncovered.length > 0) failures.push('nothing compared although ORIGINAL has animated primitives');
  if (opts.requireCoverage && uncovered.length > 0) failures.push('animated primitives of ORIGINAL have no baked counterpart');
  const maxOf = (key) => rows.reduce((m, r) => (r[key] !== undefined && !(r[key] <= m) ? r[key] : m), 0);
  return {
    original: originalFile,
    baked: bakedFile,
    mode: self ? 'self' : 'baked',
    reference: opts.reference,
    tolerance: opts.tolerance,
    pass: failures.length === 0,
    failures,
    maxRatio: rows.length ? scoreOf(worst) : 0,
    maxRatioThree: maxOf('ratio'),
    maxRatioSpec: maxOf('ratioSpec'),
    maxOriginalThreeVsSpec: maxOf('originalThreeVsSpec'),
    maxOriginalConvention: maxOf('originalConvention'),
    worst: worst && { clip: worst.clip, bakedNode: worst.bakedNode, sourceNode: worst.sourceNode, primitive: worst.primitive },
    rows,
    uncovered,
    warnings,
  };
}

function fmt(x) {
  if (x === undefined || x === null) return '-';
  if (!Number.isFinite(x)) return String(x);
  return x === 0 ? '0' : x.toExponential(2);
}

function printTable(result) {
  const anySkinned = result.rows.some((r) => r.skinned);
  const header = ['clip', 'name', 'node', 'prim', 'verts', 'frames', 'ratio'];
  if (anySkinned) header.push('ratio_spec', 'orig_three_vs_spec', 'orig_convention');
  header.push('');
  const lines = [header];
  for (const r of result.rows) {
    const line = [String(r.clip), r.clipName.slice(0, 16), `${r.bakedNode}<-${r.sourceNode}`, String(r.primitive), String(r.vertices), String(r.frames)];
    if (r.error) {
      line.push('-');
      if (anySkinned) line.push('-', '-', '-');
      line.push(`FAIL ${r.error}`);
    } else {
      line.push(fmt(r.ratio));
      if (anySkinned) line.push(fmt(r.skinned ? r.ratioSpec : undefined), fmt(r.originalThreeVsSpec), fmt(r.originalConvention));
      line.push(r.pass ? 'ok' : 'FAIL');
    }
    lines.push(line);
  }
  const widths = header.map((_, i) => Math.max(...lines.map((l) => l[i].length)));
  for (const l of lines) console.log(l.map((cell, i) => cell.padEnd(widths[i])).join('  ').trimEnd());
  for (const w of result.warnings) console.log(`warning: ${w}`);
  for (const u of result.uncovered) {
    console.log(`${result.mode === 'self' ? 'note' : 'uncovered'}: clip ${u.clip} (${u.clipName}) deforms ORIGINAL node ${u.sourceNode} but no baked node with that source_node is animated by it`);
  }
  const skinned = result.rows.filter((r) => r.skinned);
  if (skinned.length) {
    console.log(
      `skinning check on ORIGINAL: three vs glTF spec (raw weights) max ${fmt(result.maxOriginalThreeVsSpec)}, ` +
        `three vs spec formula with three's normalized weights max ${fmt(result.maxOriginalConvention)}`,
    );
  }
  const w = result.worst;
  console.log(
    `${result.pass ? 'PASS' : 'FAIL'}: ${result.rows.length} primitive(s) compared (${result.mode} mode), ` +
      `max ratio ${fmt(result.maxRatio)} (reference ${result.reference}` +
      (w ? `, clip ${w.clip} node ${w.bakedNode}<-${w.sourceNode} prim ${w.primitive}` : '') +
      `), tolerance ${result.tolerance}` +
      (result.failures.length ? `; ${result.failures.join('; ')}` : ''),
  );
}

// ---------------------------------------------------------------- entry

let opts;
try {
  opts = parseArgs(process.argv.slice(2));
} catch (err) {
  console.error(`compare_three.mjs: ${err.message}\n${USAGE}`);
  process.exit(2);
}
if (opts.json) {
  // Keep stdout for the one JSON object; three may log through console.log/info.
  console.log = console.info = (...args) => console.error(...args);
}
let result;
try {
  result = await compare(opts);
} catch (err) {
  const message = err instanceof UsageError ? err.message : `error: ${err && err.message ? err.message : err}`;
  console.error(`compare_three.mjs: ${message.split('\n')[0]}`);
  process.exit(2);
}
if (opts.json) process.stdout.write(JSON.stringify(result, (k, v) => (typeof v === 'number' && !Number.isFinite(v) ? String(v) : v)) + '\n');
else printTable(result);
process.exit(result.pass ? 0 : 1);
