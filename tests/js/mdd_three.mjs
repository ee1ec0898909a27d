#!/usr/bin/env node
// Cross-checks segmorph's MDD reading with three.js's MDDLoader.
//
//   node mdd_three.mjs CACHE.mdd BAKED.glb [--tolerance 1e-6]
//
// BAKED is `segmorph bake MESH.obj --cache CACHE.mdd -o BAKED.glb` (no --z-up: the coordinates as stored). three's
// MDDLoader reads the cache (frames, points, times, big-endian positions) into one absolute morph target per frame
// and a one-hot clip; GLTFLoader reads BAKED, an AnimationMixer plays its clip at each of the MDD's times, and
// Mesh.getVertexPosition gives each vertex as three renders it. A glTF vertex is paired with the MDD point at its
// position in the first frame (the baked base is the first frame, copied). Checked: the clip's key times equal the
// MDD's, and every vertex of every frame lies within TOLERANCE x the first frame's bounding-box diagonal of its point.
//
// Exit status: 0 when everything agrees, 1 when not, 2 on usage or load errors.

import { readFile } from 'node:fs/promises';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MDDLoader } from 'three/examples/jsm/loaders/MDDLoader.js';

function fail(message, status) {
  console.error(`mdd_three: ${message}`);
  process.exit(status);
}

const args = process.argv.slice(2);
let tolerance = 1e-6;
const files = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--tolerance') tolerance = Number(args[++i]);
  else files.push(args[i]);
}
if (files.length !== 2 || !(tolerance >= 0)) fail('usage: node mdd_three.mjs CACHE.mdd BAKED.glb [--tolerance X]', 2);

const arrayBuffer = (bytes) => bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
let mdd, gltf;
try {
  mdd = new MDDLoader().parse(arrayBuffer(await readFile(files[0])));
  gltf = await new GLTFLoader().parseAsync(arrayBuffer(await readFile(files[1])), '');
} catch (error) {
  fail(`cannot load: ${error.message}`, 2);
}

let mesh = null;
gltf.scene.traverse((object) => {
  if (!mesh && object.isMesh && object.morphTargetInfluences) mesh = object;
});
if (!mesh || gltf.animations.length !== 1) fail('BAKED has no morphed mesh or not exactly one clip', 2);

const mddTimes = mdd.clip.tracks[0].times;
const frames = mdd.morphTargets;
const gltfTimes = gltf.animations[0].tracks[0].times;
if (gltfTimes.length !== mddTimes.length || gltfTimes.some((t, k) => t !== mddTimes[k])) {
  fail(`key times differ: glTF [${gltfTimes.slice(0, 3).join(', ')}, ...], MDD [${mddTimes.slice(0, 3).join(', ')}, ...]`, 1);
}

// Pair vertices with points by their first-frame position.
const pointAt = new Map();
const first = frames[0].array;
for (let p = 0; p < frames[0].count; p++) {
  const key = `${first[3 * p]},${first[3 * p + 1]},${first[3 * p + 2]}`;
  if (pointAt.has(key)) fail(`points ${pointAt.get(key)} and ${p} share their first position: cannot pair`, 2);
  pointAt.set(key, p);
}
const base = mesh.geometry.attributes.position;
const pointOf = new Int32Array(base.count);
for (let v = 0; v < base.count; v++) {
  const key = `${base.getX(v)},${base.getY(v)},${base.getZ(v)}`;
  if (!pointAt.has(key)) fail(`glTF vertex ${v} is at no point of the MDD's first frame`, 1);
  pointOf[v] = pointAt.get(key);
}
const box = new THREE.Box3().setFromBufferAttribute(frames[0]);
const diagonal = box.max.distanceTo(box.min);

const mixer = new THREE.AnimationMixer(gltf.scene);
// Played once and held at its end: a looping action wraps its last key time to its first.
const action = mixer.clipAction(gltf.animations[0]);
action.setLoop(THREE.LoopOnce, 1);
action.clampWhenFinished = true;
action.play();
const position = new THREE.Vector3();
let worst = 0;
let worstAt = '';
for (let k = 0; k < frames.length; k++) {
  mixer.setTime(mddTimes[k]);
  const frame = frames[k].array;
  for (let v = 0; v < base.count; v++) {
    mesh.getVertexPosition(v, position);
    const p = pointOf[v];
    const distance = Math.hypot(position.x - frame[3 * p], position.y - frame[3 * p + 1], position.z - frame[3 * p + 2]);
    if (distance > worst) {
      worst = distance;
      worstAt = `frame ${k}, vertex ${v} (point ${p})`;
    }
  }
}
const score = worst / diagonal;
console.log(`mdd_three: ${frames.length} frames of ${frames[0].count} points, ${base.count} glTF vertices: ` +
            `largest distance ${score.toExponential(3)} of the diagonal${worstAt ? ` (${worstAt})` : ''}`);
process.exit(score <= tolerance ? 0 : 1);
