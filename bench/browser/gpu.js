// In Chromium (bench/lib/gpu.mjs): what playing a file costs. window.measurePlayback(url, mode, repeats, frames) with
// mode 'gpu' (segmorph's file, the plugin's default playback), 'morph' (the same file, { playback: 'morph' }) or
// 'gltfpack' (gltfpack's file, MeshoptDecoder) → { allocated, first, cpu, frame, uploaded }: the GPU bytes the load
// and first frame allocate, the milliseconds from the bytes to the first drawn frame (median of `repeats` loads after
// a first that warms the page), and per frame over `frames` times of the first clip (median): the CPU time of
// mixer.setTime and renderer.render, the whole frame's time with the drawing waited for (a 1-pixel readPixels), and
// the bytes uploaded.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';

import { GLTFSegmorphExtension } from '/three/GLTFSegmorphExtension.js';
import { gpuBytes, install, release } from '/gpu_bytes.js';

install();
const draco = new DRACOLoader().setDecoderPath('/vendor/three/examples/jsm/libs/draco/');
const renderer = new THREE.WebGLRenderer({ antialias: false });
renderer.setSize(480, 360);
document.body.appendChild(renderer.domElement);
const gl = renderer.getContext();
const pixel = new Uint8Array(4);
const finish = () => gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);

const median = (values) => {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted.length % 2 ? sorted[(sorted.length - 1) / 2] : (sorted[sorted.length / 2 - 1] + sorted[sorted.length / 2]) / 2;
};

async function once(bytes, mode, frames) {
  const loader = new GLTFLoader();
  if (mode === 'gltfpack') loader.setMeshoptDecoder(MeshoptDecoder);
  else {
    loader.setDRACOLoader(draco);
    loader.register((parser) => new GLTFSegmorphExtension(parser, { playback: mode }));
  }
  const before = gpuBytes.allocated, started = performance.now();
  const gltf = await loader.parseAsync(bytes.slice(0), '');
  const scene = new THREE.Scene().add(new THREE.HemisphereLight(0xffffff, 0x404040, 2), gltf.scene);
  const box = new THREE.Box3().setFromObject(gltf.scene), size = box.getSize(new THREE.Vector3()).length() || 1;
  const camera = new THREE.PerspectiveCamera(40, 4 / 3, size / 100, size * 100);
  camera.position.copy(box.getCenter(new THREE.Vector3())).add(new THREE.Vector3(0.6, 0.4, 1).normalize().multiplyScalar(size * 1.3));
  camera.lookAt(box.getCenter(new THREE.Vector3()));
  const mixer = new THREE.AnimationMixer(gltf.scene), clip = gltf.animations[0];
  if (clip) mixer.clipAction(clip).play();
  mixer.setTime(0);
  renderer.render(scene, camera);
  finish();
  const first = performance.now() - started, allocated = gpuBytes.allocated - before;
  const cpu = [], frame = [], uploadedBefore = gpuBytes.uploaded;
  for (let i = 1; i <= frames; ++i) {
    const begin = performance.now();
    mixer.setTime(((clip?.duration ?? 0) * i) / (frames + 1));
    renderer.render(scene, camera);
    cpu.push(performance.now() - begin);
    finish();
    frame.push(performance.now() - begin);
  }
  const uploaded = (gpuBytes.uploaded - uploadedBefore) / Math.max(frames, 1);
  release(gltf.scene);
  return { allocated, first, cpu: median(cpu), frame: median(frame), uploaded };
}

window.measurePlayback = async (url, mode, repeats, frames) => {
  await MeshoptDecoder.ready;
  const bytes = await (await fetch(url)).arrayBuffer();
  const warm = await once(bytes, mode, frames);
  const runs = [];
  for (let i = 0; i < repeats; ++i) runs.push(await once(bytes, mode, frames));
  return { allocated: warm.allocated, uploaded: warm.uploaded, firstLoad: warm.first,
           first: median(runs.map((r) => r.first)), cpu: median(runs.map((r) => r.cpu)),
           frame: median(runs.map((r) => r.frame)) };
};

window.ready = true;
