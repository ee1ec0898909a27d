// The segmorph viewer (web/viewer/index.html): open or drop a .glb, plain or compressed by segmorph, and it plays,
// with play/pause, a clip list and a time slider; it shows the file's bytes, the GPU bytes its first frame allocated
// (WebGL's allocation calls counted, web/gpu_bytes.js) and how its primitives play (the plugin's default: on the GPU
// from their model where the stream is version 4), the load and decode times, and the vertices, frames and clips.
// The page exposes window.viewer for tests (tests/js/web_browser.mjs).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

import { GLTFSegmorphExtension } from '../three/GLTFSegmorphExtension.js';
import { gpuBytes, install, release } from '../gpu_bytes.js';

install();  // before the renderer makes its context

const element = (id) => document.getElementById(id);
const view = element('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20242a);
scene.add(new THREE.HemisphereLight(0xffffff, 0x444455, 2.5));
const light = new THREE.DirectionalLight(0xffffff, 2);
light.position.set(1, 2, 1.5);
scene.add(light);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
const timer = new THREE.Timer();

const draco = new DRACOLoader().setDecoderPath('/vendor/three/examples/jsm/libs/draco/');
const state = { root: null, mixer: null, action: null, clips: [], playing: true, facts: null };

function resize() {
  const { clientWidth: width, clientHeight: height } = view;
  renderer.setSize(width, height, false);
  camera.aspect = width / Math.max(height, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

function frame() {
  timer.update();
  const delta = timer.getDelta();
  if (state.mixer && state.playing) {
    state.mixer.update(delta);
    if (state.action) element('time').value = String(state.action.time / Math.max(state.action.getClip().duration, 1e-9));
  }
  controls.update();
  renderer.render(scene, camera);
  requestAnimationFrame(frame);
}
requestAnimationFrame(frame);

function frameTheCamera(object) {
  // The geometries' bounds, which include every morph target: a vertex cache may travel far from its first frame.
  const box = new THREE.Box3().setFromObject(object);
  const size = box.getSize(new THREE.Vector3()).length() || 1, center = box.getCenter(new THREE.Vector3());
  camera.near = size / 100;
  camera.far = size * 100;
  camera.position.copy(center).add(new THREE.Vector3(0.6, 0.4, 1).normalize().multiplyScalar(size * 1.2));
  camera.updateProjectionMatrix();
  controls.target.copy(center);
}

function playClip(index) {
  if (!state.mixer) return;
  state.mixer.stopAllAction();
  state.action = state.clips[index] ? state.mixer.clipAction(state.clips[index]).play() : null;
  element('clips').value = String(index);
}

// What the file holds: vertices, frames and clips of its compressed primitives (or of all its meshes).
function describe(gltf, bytes, milliseconds, decodeMilliseconds) {
  let vertices = 0, frames = 0;
  gltf.scene.traverse((object) => {
    if (!object.isMesh) return;
    vertices += object.geometry.getAttribute('position').count;
    frames = Math.max(frames, object.morphTargetInfluences?.length ?? 0);
  });
  return { bytes, milliseconds, decodeMilliseconds, vertices, frames, clips: gltf.animations.length };
}

// How the file's compressed primitives play: "on the GPU", "as morph targets" or both with counts.
function playbackText(plugin) {
  const names = { gpu: 'on the GPU', morph: 'as morph targets', stream: 'streamed' }, counts = new Map();
  for (const p of plugin?.playbacks ?? []) counts.set(p.mode, (counts.get(p.mode) ?? 0) + 1);
  if (counts.size === 0) return '';
  const total = [...counts.values()].reduce((a, b) => a + b, 0);
  return `, ${[...counts].map(([mode, n]) => (counts.size > 1 || total > 1 ? `${n} ` : '') + names[mode]).join(', ')}`;
}

export async function open(buffer, name) {
  const started = performance.now();
  const before = gpuBytes.allocated;
  const loader = new GLTFLoader().setDRACOLoader(draco);
  let plugin = null;
  loader.register((parser) => (plugin = new GLTFSegmorphExtension(parser)));
  const gltf = await loader.parseAsync(buffer, '');
  const milliseconds = performance.now() - started;
  if (state.root) {
    scene.remove(state.root);
    release(state.root);
  }
  state.root = gltf.scene;
  scene.add(gltf.scene);
  state.clips = gltf.animations;
  state.mixer = new THREE.AnimationMixer(gltf.scene);
  state.facts = describe(gltf, buffer.byteLength, milliseconds, plugin?.decodeMilliseconds ?? 0);
  const clips = element('clips');
  clips.replaceChildren(...state.clips.map((clip, i) => new Option(`${clip.name} (${clip.duration.toFixed(2)} s)`, String(i))));
  for (const id of ['clips', 'time', 'play']) element(id).disabled = state.clips.length === 0;
  frameTheCamera(gltf.scene);
  playClip(0);
  state.mixer.update(0);
  renderer.render(scene, camera);  // the first frame: what the file takes on the GPU
  state.facts.gpuBytes = gpuBytes.allocated - before;
  state.facts.playback = playbackText(plugin);
  const f = state.facts;
  element('facts').textContent = `${name}: ${f.bytes.toLocaleString()} bytes, ` +
    `GPU ${(f.gpuBytes / 1e6).toFixed(2)} MB${f.playback}, loaded in ${f.milliseconds.toFixed(1)} ms ` +
    `(segmorph decode ${f.decodeMilliseconds.toFixed(1)} ms), ${f.vertices.toLocaleString()} vertices, ` +
    `${f.frames} frames, ${f.clips} clip${f.clips === 1 ? '' : 's'}`;
  element('drop').classList.add('hidden');
  return { gltf, facts: state.facts };
}

async function openFile(file) {
  try {
    await open(await file.arrayBuffer(), file.name);
  } catch (error) {
    element('facts').innerHTML = '';
    const span = document.createElement('span');
    span.id = 'error';
    span.textContent = `${file.name}: ${error.message}`;
    element('facts').appendChild(span);
  }
}

element('file').addEventListener('change', (event) => event.target.files[0] && openFile(event.target.files[0]));
window.addEventListener('dragover', (event) => event.preventDefault());
window.addEventListener('drop', (event) => {
  event.preventDefault();
  if (event.dataTransfer.files[0]) openFile(event.dataTransfer.files[0]);
});
element('clips').addEventListener('change', (event) => playClip(Number(event.target.value)));
element('play').addEventListener('click', () => {
  state.playing = !state.playing;
  element('play').textContent = state.playing ? 'Pause' : 'Play';
});
element('time').addEventListener('input', (event) => {
  if (!state.action) return;
  state.playing = false;
  element('play').textContent = 'Play';
  state.action.time = Number(event.target.value) * state.action.getClip().duration;
  state.mixer.update(0);
});

window.viewer = { open, state, renderer, setTime(t) { if (state.action) { state.action.time = t; state.mixer.update(0); } } };
