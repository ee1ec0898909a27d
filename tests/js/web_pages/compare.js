// In the browser (tests/js/web_browser.mjs): a file written by segmorph encode, loaded by GLTFLoader with the plugin,
// against the same file decoded by segmorph decode and loaded without it. Each clip is played with AnimationMixer and
// the positions three.js computes (Mesh.getVertexPosition: morph targets and skinning applied, then the world matrix)
// are compared at every key time of the decoded clip.
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
  let maxError = 0, frames = 0;
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
      }
      frames += 1;
    }
    mixerA.stopAllAction();
    mixerB.stopAllAction();
    clips.push({ name: b.name, times: times.length, maxError: clipError });
    maxError = Math.max(maxError, clipError);
  }
  if (options.workers) SegmorphDecoder.useWorkers(0);
  return { meshes: meshPairs.length, clips, frames, maxError, diagonal, loadMilliseconds };
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
