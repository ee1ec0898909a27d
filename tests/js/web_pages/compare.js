// In the browser (tests/js/web_browser.mjs): a file written by segmorph encode, loaded by GLTFLoader with the plugin,
// against the same file decoded by segmorph decode and loaded without it. Each clip is played with AnimationMixer and
// the positions three.js computes (Mesh.getVertexPosition: morph targets and skinning applied, then the world matrix)
// are compared at every key time of the decoded clip, and so are the normals it shades with (morph targets applied on
// the CPU as its vertex shader applies them, object space, each normalized) where the plugin's are on the CPU (morph
// targets and streaming playback): the plugin turns them through the decoder (turn_normals) as segmorph decode does.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';

import { SegmorphDecoder } from '/segmorph_decoder.js';
import { GLTFSegmorphExtension } from '/three/GLTFSegmorphExtension.js';
import { meshesOf, pairs } from './meshes.js';

const draco = new DRACOLoader().setDecoderPath('/vendor/three/examples/jsm/libs/draco/');

async function load(url, plugin, options) {
  const loader = new GLTFLoader().setDRACOLoader(draco);
  if (plugin) loader.register((parser) => new GLTFSegmorphExtension(parser, options));
  return loader.loadAsync(url);
}

function positions(mesh, streaming) {
  if (streaming) mesh.onBeforeRender();  // streaming playback decodes the shown frame when the mesh is drawn
  const count = mesh.geometry.getAttribute('position').count, out = new Float64Array(count * 3), p = new THREE.Vector3();
  for (let v = 0; v < count; ++v) {
    mesh.getVertexPosition(v, p).applyMatrix4(mesh.matrixWorld);
    out[v * 3] = p.x, out[v * 3 + 1] = p.y, out[v * 3 + 2] = p.z;
  }
  return out;
}

// The normals three.js shades `mesh` with at its influences: its morph targets applied as its vertex shader applies
// them (relative: base + Σ w·delta; absolute: base·(1 − Σ w) + Σ w·target), in object space, each normalized.
function normals(mesh) {
  const geometry = mesh.geometry, base = geometry.getAttribute('normal');
  if (!base) return null;
  const targets = geometry.morphAttributes.normal ?? [], weights = mesh.morphTargetInfluences ?? [];
  const sum = weights.reduce((a, w) => a + w, 0), baseWeight = geometry.morphTargetsRelative ? 1 : 1 - sum;
  const out = new Float64Array(base.count * 3);
  for (let v = 0; v < base.count; ++v) {
    let x = base.getX(v) * baseWeight, y = base.getY(v) * baseWeight, z = base.getZ(v) * baseWeight;
    targets.forEach((target, t) => {
      const w = weights[t] ?? 0;
      if (w !== 0) x += w * target.getX(v), y += w * target.getY(v), z += w * target.getZ(v);
    });
    const length = Math.hypot(x, y, z) || 1;
    out[v * 3] = x / length, out[v * 3 + 1] = y / length, out[v * 3 + 2] = z / length;
  }
  return out;
}

// The largest angle in degrees between two meshes' normals (vertices whose normals vanish left out).
function largestAngle(a, b) {
  let largest = 0;
  for (let i = 0; i < a.length; i += 3) {
    const cos = a[i] * b[i] + a[i + 1] * b[i + 1] + a[i + 2] * b[i + 2];
    if (Math.hypot(a[i], a[i + 1], a[i + 2]) > 0.5 && Math.hypot(b[i], b[i + 1], b[i + 2]) > 0.5)
      largest = Math.max(largest, Math.acos(Math.min(1, Math.max(-1, cos))) * 180 / Math.PI);
  }
  return largest;
}

window.compare = async (compressedUrl, decodedUrl, options = {}) => {
  if (options.workers) SegmorphDecoder.useWorkers(options.workers);
  const started = performance.now();
  const compressed = await load(compressedUrl, true, options);
  const loadMilliseconds = performance.now() - started;
  const decoded = await load(decodedUrl, false);
  const meshPairs = pairs(meshesOf(compressed.scene), meshesOf(decoded.scene));
  const box = new THREE.Box3().setFromObject(decoded.scene, true);
  const diagonal = box.getSize(new THREE.Vector3()).length();
  if (compressed.animations.length !== decoded.animations.length)
    throw new Error(`${compressed.animations.length} clips with the plugin, ${decoded.animations.length} decoded`);
  // The plugin's normals are on the CPU unless it plays the model on the GPU (its default for version-4 streams).
  const cpuNormals = options.streaming || options.playback === 'morph';
  let maxError = 0, frames = 0, maxNormalDegrees = 0, normalsCompared = 0;
  const clips = [];
  for (let c = 0; c < decoded.animations.length; ++c) {
    const a = compressed.animations[c], b = decoded.animations[c];
    if (a.name !== b.name) throw new Error(`clip ${c} is ${a.name} with the plugin, ${b.name} decoded`);
    const mixerA = new THREE.AnimationMixer(compressed.scene), mixerB = new THREE.AnimationMixer(decoded.scene);
    mixerA.clipAction(a).play();
    mixerB.clipAction(b).play();
    const times = [...new Set(b.tracks.flatMap((track) => Array.from(track.times)))].sort((x, y) => x - y);
    let clipError = 0;
    for (const t of times) {
      mixerA.setTime(t);
      mixerB.setTime(t);
      compressed.scene.updateMatrixWorld(true);
      decoded.scene.updateMatrixWorld(true);
      for (const [meshA, meshB] of meshPairs) {
        const pa = positions(meshA, options.streaming), pb = positions(meshB, false);
        for (let i = 0; i < pa.length; ++i) clipError = Math.max(clipError, Math.abs(pa[i] - pb[i]));
        const na = cpuNormals && normals(meshA), nb = na && normals(meshB);
        if (nb && (meshA.geometry.morphAttributes.normal || options.streaming)) {
          maxNormalDegrees = Math.max(maxNormalDegrees, largestAngle(na, nb));
          normalsCompared += 1;
        }
      }
      frames += 1;
    }
    mixerA.stopAllAction();
    mixerB.stopAllAction();
    clips.push({ name: b.name, times: times.length, maxError: clipError });
    maxError = Math.max(maxError, clipError);
  }
  if (options.workers) SegmorphDecoder.useWorkers(0);
  return { meshes: meshPairs.length, clips, frames, maxError, diagonal, loadMilliseconds, maxNormalDegrees,
           normalsCompared };
};

// The load of a file that must fail: its error message, or null when it loaded.
window.loadError = async (url) => {
  try {
    await load(url, true);
    return null;
  } catch (error) {
    return String(error?.message ?? error);
  }
};

window.ready = true;
