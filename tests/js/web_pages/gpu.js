// In the browser (tests/js/web_gpu.mjs): the plugin's GPU playback (its default) against the file segmorph decode
// wrote, loaded by plain GLTFLoader. Per file:
// - the pictures: both scenes (one camera, one shadow-casting light, a ground) rendered at frame times and between
//   them, compared pixel by pixel; a control picture (the decoded file at another time) shows the comparison sees
//   the animation;
// - the positions: each GPU-played mesh's model evaluated by a ShaderMaterial of the same GLSL into a float render
//   target, read back at every frame time, against the float32 CPU reference (SegmorphDecoder's ModelDecoder at the
//   blended parameters) and against the decoded file's morph-target positions;
// - a cross-fade between two clips (when there are two), the same way;
// - the shadow alone (the meshes hidden from the camera, still casting): it matches the decoded file's and moves;
// - the GPU bytes of GPU playback, of { playback: 'morph' } and of the decoded file, and the bytes uploaded per frame.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';

import { SegmorphDecoder } from '/segmorph_decoder.js';
import { GLTFSegmorphExtension, SEGMORPH_MODEL_GLSL, SEGMORPH_NORMAL_GLSL } from '/three/GLTFSegmorphExtension.js';
import { gpuBytes, install } from '/gpu_bytes.js';
import { meshesOf, pairs } from './meshes.js';

install();
const draco = new DRACOLoader().setDecoderPath('/vendor/three/examples/jsm/libs/draco/');
const WIDTH = 160, HEIGHT = 120;
const renderer = new THREE.WebGLRenderer({ antialias: false });
renderer.setSize(WIDTH, HEIGHT);
renderer.shadowMap.enabled = true;
document.body.appendChild(renderer.domElement);
const picture = new THREE.WebGLRenderTarget(WIDTH, HEIGHT);

async function load(url, options) {
  const loader = new GLTFLoader().setDRACOLoader(draco);
  let plugin = null;
  if (options) loader.register((parser) => (plugin = new GLTFSegmorphExtension(parser, options)));
  const gltf = await loader.loadAsync(url);
  return { gltf, plugin };
}

// A scene around `root`: the camera frames `box`, a directional light casts shadows on a ground below it.
function stage(root, box, shadows = true) {
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x404860);
  const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(size.length() / 2, 1e-6);
  const camera = new THREE.PerspectiveCamera(40, WIDTH / HEIGHT, radius / 100, radius * 100);
  camera.position.copy(centre).add(new THREE.Vector3(0.9, 0.5, 1.6).normalize().multiplyScalar(radius * 3));
  camera.lookAt(centre);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 1.2));
  const light = new THREE.DirectionalLight(0xffffff, 2.5);
  light.position.copy(centre).add(new THREE.Vector3(0.4, 1, 0.3).normalize().multiplyScalar(radius * 4));
  light.target.position.copy(centre);
  light.castShadow = shadows;
  light.shadow.mapSize.set(512, 512);
  Object.assign(light.shadow.camera, { left: -radius * 2, right: radius * 2, top: radius * 2, bottom: -radius * 2,
                                       near: radius / 10, far: radius * 10 });
  light.shadow.camera.updateProjectionMatrix();
  scene.add(light, light.target);
  const ground = new THREE.Mesh(new THREE.PlaneGeometry(radius * 8, radius * 8),
                                new THREE.MeshStandardMaterial({ color: 0xd0d0d0 }));
  ground.rotation.x = -Math.PI / 2;
  ground.position.set(centre.x, box.min.y - radius * 0.05, centre.z);
  ground.receiveShadow = true;
  scene.add(ground, root);
  // Thin sheets (a flag) cast shadows from either side.
  for (const mesh of meshesOf(root)) {
    mesh.castShadow = true;
    for (const material of [mesh.material].flat()) material.shadowSide = THREE.DoubleSide;
  }
  return { scene, camera, ground };
}

function render(staged) {
  renderer.setRenderTarget(picture);
  renderer.render(staged.scene, staged.camera);
  const pixels = new Uint8Array(WIDTH * HEIGHT * 4);
  renderer.readRenderTargetPixels(picture, 0, 0, WIDTH, HEIGHT, pixels);
  renderer.setRenderTarget(null);
  return pixels;
}

// Pixels whose largest channel difference is above 24 (of 255), and the largest difference.
function difference(a, b) {
  let differing = 0, largest = 0;
  for (let i = 0; i < a.length; i += 4) {
    const d = Math.max(Math.abs(a[i] - b[i]), Math.abs(a[i + 1] - b[i + 1]), Math.abs(a[i + 2] - b[i + 2]));
    largest = Math.max(largest, d);
    if (d > 24) differing += 1;
  }
  return { differing: differing / (a.length / 4), largest };
}

// Reads a GPU-played mesh's positions back: its model evaluated per vertex (one point per pixel) into a float target.
class Readback {
  constructor(mesh, normals = false) {
    const count = mesh.geometry.getAttribute('position').count;
    this.width = Math.min(count, 1024);
    this.height = Math.ceil(count / this.width);
    this.count = count;
    this.target = new THREE.WebGLRenderTarget(this.width, this.height, { type: THREE.FloatType, format: THREE.RGBAFormat });
    const geometry = new THREE.BufferGeometry();
    for (const name of ['position', 'normal', 'segmorphCluster', 'segmorphWeight', 'segmorphCoefficient',
                        'segmorphSurface', 'segmorphRing'])
      if (mesh.geometry.getAttribute(name)) geometry.setAttribute(name, mesh.geometry.getAttribute(name));
    geometry.setDrawRange(0, count);
    const material = new THREE.ShaderMaterial({
      glslVersion: THREE.GLSL3,
      uniforms: mesh.segmorph.uniforms,
      vertexShader: `${SEGMORPH_MODEL_GLSL}${normals ? SEGMORPH_NORMAL_GLSL : ''}
        out vec3 evaluated;
        void main() {
          int width = ${this.width};
          vec2 pixel = vec2( float( gl_VertexID % width ) + 0.5, float( gl_VertexID / width ) + 0.5 );
          gl_Position = vec4( pixel / vec2( ${this.width}.0, ${this.height}.0 ) * 2.0 - 1.0, 0.0, 1.0 );
          gl_PointSize = 1.0;
          evaluated = ${normals ? 'normalize( segmorphNormal( normal ) )' : 'segmorphPosition( position )'};
        }`,
      fragmentShader: `
        in vec3 evaluated;
        out vec4 colour;
        void main() { colour = vec4( evaluated, 1.0 ); }`,
    });
    this.points = new THREE.Points(geometry, material);
    this.points.frustumCulled = false;
    this.scene = new THREE.Scene().add(this.points);
    this.camera = new THREE.Camera();
    this.mesh = mesh;
  }

  read() {
    this.mesh.segmorph.player.update(this.mesh);
    this.mesh.segmorph.player.shape(this.mesh, renderer);
    renderer.setRenderTarget(this.target);
    renderer.render(this.scene, this.camera);
    const rgba = new Float32Array(this.width * this.height * 4), out = new Float32Array(this.count * 3);
    renderer.readRenderTargetPixels(this.target, 0, 0, this.width, this.height, rgba);
    renderer.setRenderTarget(null);
    for (let v = 0; v < this.count; ++v) out.set(rgba.subarray(v * 4, v * 4 + 3), v * 3);
    return out;
  }
}

// The float32 CPU reference of a GPU-played mesh (the C API's evaluation, in WebAssembly) at the mesh's influences.
async function reference(gltf, mesh) {
  const { meshes, primitives } = gltf.parser.associations.get(mesh);
  const extension = gltf.parser.json.meshes[meshes].primitives[primitives].extensions.SEGMORPH_animation_compression;
  const stream = new Uint8Array(await gltf.parser.getDependency('bufferView', extension.bufferView));
  const decoder = SegmorphDecoder.createModelDecoder(stream, mesh.geometry.getAttribute('position').array,
                                                     mesh.geometry.index.array);
  const { clusterCount: K, basisCount: N } = decoder.model;
  const parameters = new Float32Array(K * 12 + N);
  return {
    decoder,
    evaluate: () => {
      mesh.segmorph.player.blend(mesh.morphTargetInfluences, parameters);
      return decoder.evaluate(parameters.subarray(0, K * 12), parameters.subarray(K * 12));
    },
  };
}

// The decoded file's morph-target positions (or normals) of `mesh` (object space) at its influences.
function morphed(mesh, attribute = 'position') {
  const geometry = mesh.geometry, base = geometry.getAttribute(attribute).array;
  const targets = geometry.morphAttributes[attribute] ?? [], w = mesh.morphTargetInfluences ?? [];
  const out = new Float64Array(base.length);
  let sum = 0;
  for (let t = 0; t < targets.length; ++t) sum += w[t];
  const baseWeight = geometry.morphTargetsRelative ? 1 : 1 - sum;
  for (let i = 0; i < base.length; ++i) out[i] = baseWeight * base[i];
  for (let t = 0; t < targets.length; ++t) {
    if (!w[t]) continue;
    const d = targets[t].array;
    for (let i = 0; i < base.length; ++i) out[i] += w[t] * d[i];
  }
  return out;
}

// Object space to world space, both through each mesh's matrixWorld.
function largestWorldDifference(a, meshA, b, meshB) {
  const p = new THREE.Vector3(), q = new THREE.Vector3();
  let largest = 0;
  for (let i = 0; i < a.length; i += 3) {
    p.set(a[i], a[i + 1], a[i + 2]).applyMatrix4(meshA.matrixWorld);
    q.set(b[i], b[i + 1], b[i + 2]).applyMatrix4(meshB.matrixWorld);
    largest = Math.max(largest, Math.abs(p.x - q.x), Math.abs(p.y - q.y), Math.abs(p.z - q.z));
  }
  return largest;
}

function largestDifference(a, b) {
  let largest = 0;
  for (let i = 0; i < a.length; ++i) largest = Math.max(largest, Math.abs(a[i] - b[i]));
  return largest;
}

// GPU bytes allocated by loading `url` with `options` (null: no plugin) and drawing it once, and the bytes uploaded
// by drawing it at a second time.
async function measureBytes(url, options) {
  const before = gpuBytes.allocated;
  const { gltf } = await load(url, options);
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const staged = stage(gltf.scene, box.isEmpty() ? new THREE.Box3(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1)) : box,
                       false);
  staged.scene.remove(staged.ground);
  const mixer = new THREE.AnimationMixer(gltf.scene);
  if (gltf.animations[0]) mixer.clipAction(gltf.animations[0]).play();
  mixer.setTime(0);
  render(staged);
  const allocated = gpuBytes.allocated - before;
  mixer.setTime((gltf.animations[0]?.duration ?? 0) * 0.37);
  const uploadedBefore = gpuBytes.uploaded;
  render(staged);
  const uploaded = gpuBytes.uploaded - uploadedBefore;
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    o.geometry.dispose();
    for (const m of [o.material].flat()) {
      for (const value of Object.values(m)) if (value?.isTexture) value.dispose();
      m.dispose();
    }
    o.segmorph?.player.dispose([o]);
  });
  return { allocated, uploaded };
}

window.gpuCase = async (encodedUrl, decodedUrl, { crossFade = true } = {}) => {
  // Everything the renderer allocates for itself first (shadow maps, the picture target), so that the bytes below
  // are the file's.
  const started = performance.now();
  const { gltf: a, plugin } = await load(encodedUrl, {});
  const loadMilliseconds = performance.now() - started;
  const { gltf: b } = await load(decodedUrl, null);
  const gpuMeshes = meshesOf(a.scene).filter((m) => m.segmorph);
  const meshPairs = pairs(meshesOf(a.scene), meshesOf(b.scene));
  const decodedOf = new Map(meshPairs), decodedOfMesh = (mesh) => decodedOf.get(mesh);
  if (a.animations.length !== b.animations.length)
    throw new Error(`${a.animations.length} clips with the plugin, ${b.animations.length} decoded`);
  a.scene.updateMatrixWorld(true);
  b.scene.updateMatrixWorld(true);
  // Frame with the model's bounds (every frame inside), the same box for both.
  const box = new THREE.Box3();
  for (const mesh of meshesOf(a.scene)) {
    if (!mesh.geometry.boundingBox) mesh.geometry.computeBoundingBox();
    box.union(mesh.geometry.boundingBox.clone().applyMatrix4(mesh.matrixWorld));
  }
  const stagedA = stage(a.scene, box), stagedB = stage(b.scene, box);
  const diagonal = box.getSize(new THREE.Vector3()).length();
  const readbacks = new Map(), references = new Map();
  const normalReadbacks = new Map();
  for (const mesh of gpuMeshes) {
    readbacks.set(mesh, new Readback(mesh));
    if (mesh.geometry.getAttribute('normal') && decodedOfMesh(mesh)?.geometry.morphAttributes.normal)
      normalReadbacks.set(mesh, new Readback(mesh, true));
    references.set(mesh, await reference(a, mesh));
  }
  const result = { playbacks: plugin.playbacks, gpuMeshes: gpuMeshes.length, meshes: meshPairs.length, frames: 0,
                   pictures: 0, loadMilliseconds, diagonal, gpuReference: 0, gpuDecoded: 0, worstPicture: 0,
                   worstPictureLargest: 0, control: 1, crossFade: null, shadow: null,
                   normals: { largestDegrees: 0, sumDegrees: 0, count: 0 } };

  // Positions at `mixer` times, and pictures at some of them.
  const compareNow = (takePicture) => {
    a.scene.updateMatrixWorld(true);
    b.scene.updateMatrixWorld(true);
    for (const mesh of gpuMeshes) {
      const gpu = readbacks.get(mesh).read(), cpu = references.get(mesh).evaluate();
      result.gpuReference = Math.max(result.gpuReference, largestDifference(gpu, cpu));
      const other = decodedOf.get(mesh);
      result.gpuDecoded = Math.max(result.gpuDecoded, largestWorldDifference(gpu, mesh, morphed(other), other));
      // The angle between the shader's normals (the cofactor of the blended A) and the decoded file's.
      if (!takePicture || !normalReadbacks.has(mesh)) continue;
      const n = normalReadbacks.get(mesh).read(), m = morphed(other, 'normal'), angles = result.normals;
      for (let i = 0; i < n.length; i += 3) {
        const length = Math.hypot(m[i], m[i + 1], m[i + 2]);
        if (!(length > 0)) continue;
        const cos = (n[i] * m[i] + n[i + 1] * m[i + 1] + n[i + 2] * m[i + 2]) / length;
        const degrees = (Math.acos(Math.min(1, Math.max(-1, cos))) * 180) / Math.PI;
        angles.largestDegrees = Math.max(angles.largestDegrees, degrees);
        angles.sumDegrees += degrees;
        angles.count += 1;
      }
    }
    if (takePicture) {
      const d = difference(render(stagedA), render(stagedB));
      result.worstPicture = Math.max(result.worstPicture, d.differing);
      result.worstPictureLargest = Math.max(result.worstPictureLargest, d.largest);
      result.pictures += 1;
    }
    result.frames += 1;
  };
  for (let c = 0; c < b.animations.length; ++c) {
    const mixerA = new THREE.AnimationMixer(a.scene), mixerB = new THREE.AnimationMixer(b.scene);
    mixerA.clipAction(a.animations[c]).play();
    mixerB.clipAction(b.animations[c]).play();
    const times = [...new Set(b.animations[c].tracks.flatMap((t) => Array.from(t.times)))].sort((x, y) => x - y);
    const shown = new Set([0, Math.floor(times.length / 3), Math.floor((2 * times.length) / 3), times.length - 1]);
    times.forEach((t, i) => {
      mixerA.setTime(t);
      mixerB.setTime(t);
      compareNow(shown.has(i));
      if (shown.has(i) && i + 1 < times.length) {  // between two frames: LINEAR blends them, STEP holds
        const between = t + (times[i + 1] - t) * 0.4;
        mixerA.setTime(between);
        mixerB.setTime(between);
        compareNow(true);
      }
    });
    // The control: the decoded file a third of the clip later differs from the GPU picture at the start.
    if (c === 0 && times.length > 2) {
      mixerA.setTime(times[0]);
      mixerB.setTime(times[Math.floor(times.length / 3)]);
      result.control = difference(render(stagedA), render(stagedB)).differing;
      // The shadow alone: the meshes hidden from the camera (colour and depth writes off), still casting.
      const hide = (root) => meshesOf(root).forEach((m) => [m.material].flat().forEach((x) => {
        x.colorWrite = false;
        x.depthWrite = false;
      }));
      hide(a.scene);
      hide(b.scene);
      const shadows = [];
      for (const t of [times[0], times[Math.floor(times.length / 2)]]) {
        mixerA.setTime(t);
        mixerB.setTime(t);
        shadows.push([render(stagedA), render(stagedB)]);
      }
      for (const m of meshesOf(a.scene)) m.castShadow = false;
      mixerA.setTime(times[0]);
      const noShadow = render(stagedA);
      for (const m of meshesOf(a.scene)) m.castShadow = true;
      result.shadow = {
        matches: Math.max(difference(...shadows[0]).differing, difference(...shadows[1]).differing),
        moves: difference(shadows[0][0], shadows[1][0]).differing,
        present: Math.max(difference(shadows[0][0], noShadow).differing, difference(shadows[1][0], noShadow).differing),
      };
      const show = (root) => meshesOf(root).forEach((m) => [m.material].flat().forEach((x) => {
        x.colorWrite = true;
        x.depthWrite = true;
      }));
      show(a.scene);
      show(b.scene);
    }
    mixerA.stopAllAction();
    mixerB.stopAllAction();
    mixerA.uncacheRoot(a.scene);
    mixerB.uncacheRoot(b.scene);
  }

  // A cross-fade from clip 0 to clip 1 over half of clip 0, sampled as the mixer advances.
  if (crossFade && a.animations.length >= 2 && gpuMeshes.length) {
    const fade = { gpuDecoded: 0, gpuReference: 0, frames: 0, worstPicture: 0 };
    const mixers = [[a, new THREE.AnimationMixer(a.scene)], [b, new THREE.AnimationMixer(b.scene)]].map(([gltf, mixer]) => {
      const first = mixer.clipAction(gltf.animations[0]).play(), second = mixer.clipAction(gltf.animations[1]);
      second.play();
      first.crossFadeTo(second, Math.max(gltf.animations[0].duration * 0.5, 0.05), false);
      return mixer;
    });
    const steps = 12, step = Math.max(a.animations[0].duration * 0.5, 0.05) / (steps - 2);
    const keep = [result.gpuDecoded, result.gpuReference, result.worstPicture];
    result.gpuDecoded = result.gpuReference = result.worstPicture = 0;
    for (let s = 0; s < steps; ++s) {
      for (const mixer of mixers) mixer.update(s === 0 ? 0 : step);
      compareNow(s % 3 === 1);
      fade.frames += 1;
    }
    Object.assign(fade, { gpuDecoded: result.gpuDecoded, gpuReference: result.gpuReference, worstPicture: result.worstPicture });
    [result.gpuDecoded, result.gpuReference, result.worstPicture] = [Math.max(keep[0], fade.gpuDecoded),
      Math.max(keep[1], fade.gpuReference), Math.max(keep[2], fade.worstPicture)];
    result.crossFade = fade;
  }
  for (const { decoder } of references.values()) decoder.dispose();

  // GPU bytes: GPU playback, morph targets, the decoded file.
  result.bytes = {
    gpu: await measureBytes(encodedUrl, {}),
    morph: await measureBytes(encodedUrl, { playback: 'morph' }),
    decoded: await measureBytes(decodedUrl, null),
  };
  return result;
};

// The load of a file that must fail: its error message (null when it loaded), and the GPU bytes allocated meanwhile.
window.loadError = async (url) => {
  const before = gpuBytes.allocated;
  try {
    const { gltf } = await load(url, {});
    renderer.render(gltf.scene, new THREE.PerspectiveCamera());
    return { message: null, allocated: gpuBytes.allocated - before };
  } catch (error) {
    renderer.render(new THREE.Scene(), new THREE.PerspectiveCamera());
    return { message: String(error?.message ?? error), allocated: gpuBytes.allocated - before };
  }
};

// The renderer's own allocations (its shadow maps and targets) before any file.
{
  const warm = stage(new THREE.Group(), new THREE.Box3(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1)));
  render(warm);
}
window.ready = true;
