// In the browser (tests/js/web_babylon.mjs): segmorph/babylon (the extension registered by importing it) against the
// file segmorph decode wrote, loaded by Babylon's glTF loader alone. Per file:
// - the pictures: each file in a scene of its own (one camera, a hemispheric light and a shadow-casting directional
//   light, a ground), every animation group at frame times and between them, compared pixel by pixel; a control
//   picture (the decoded file a third of a group later, in the group that moves most) shows that the comparison sees
//   the animation;
// - the positions Babylon computes on the CPU (AbstractMesh.getPositionData: morph targets and skinning applied), in
//   world space, at the same times, within the tolerance of the test's caller;
// - a cross-fade between two groups (when there are two), weights 0.5 each;
// - the GPU bytes each file's load and first frame allocate.
import { Engine } from '@babylonjs/core/Engines/engine.js';
import { Scene } from '@babylonjs/core/scene.js';
import { Color3, Color4 } from '@babylonjs/core/Maths/math.color.js';
import { Vector3 } from '@babylonjs/core/Maths/math.vector.js';
import { ArcRotateCamera } from '@babylonjs/core/Cameras/arcRotateCamera.js';
import { HemisphericLight } from '@babylonjs/core/Lights/hemisphericLight.js';
import { DirectionalLight } from '@babylonjs/core/Lights/directionalLight.js';
import { ShadowGenerator } from '@babylonjs/core/Lights/Shadows/shadowGenerator.js';
import '@babylonjs/core/Lights/Shadows/shadowGeneratorSceneComponent.js';
import { CreateGround } from '@babylonjs/core/Meshes/Builders/groundBuilder.js';
import { StandardMaterial } from '@babylonjs/core/Materials/standardMaterial.js';
import { LoadAssetContainerAsync } from '@babylonjs/core/Loading/sceneLoader.js';
import { DracoDecoder } from '@babylonjs/core/Meshes/Compression/dracoDecoder.js';
import '@babylonjs/loaders/glTF/index.js';

import { SegmorphDecoder } from '/babylon/SegmorphExtension.js';
import { gpuBytes, install } from '/gpu_bytes.js';

install();
const draco = '/vendor/three/examples/jsm/libs/draco/gltf/';
DracoDecoder.DefaultConfiguration = { wasmUrl: `${draco}draco_wasm_wrapper.js`, wasmBinaryUrl: `${draco}draco_decoder.wasm`,
                                      fallbackUrl: `${draco}draco_decoder.js` };
const canvas = document.getElementById('view');
const engine = new Engine(canvas, false, { preserveDrawingBuffer: true, stencil: true });
const WIDTH = canvas.width, HEIGHT = canvas.height;

// A scene with `url` loaded into it, staged: camera framing the decoded file's
// bounds `box` (or its own), lights, a shadow-casting light and a ground.
async function staged(url, box = null, options = null) {
  const scene = new Scene(engine);
  scene.clearColor = new Color4(0.25, 0.28, 0.38, 1);
  const camera = new ArcRotateCamera('camera', 0.6, 1.1, 3, Vector3.Zero(), scene);
  // What the file takes on the GPU: its load and its first frame, before the stage's lights, shadows and ground.
  const before = gpuBytes.allocated;
  const container = await LoadAssetContainerAsync(url, scene, options ? {
    pluginOptions: { gltf: { extensionOptions: { SEGMORPH_animation_compression: options } } } } : undefined);
  container.addAllToScene();
  for (const group of container.animationGroups) group.stop();
  await scene.whenReadyAsync();  // textures decoded, shaders compiled
  scene.render();
  const allocated = gpuBytes.allocated - before;
  const meshes = container.meshes.filter((m) => m.getTotalVertices() > 0);
  if (!box) {
    let min = new Vector3(Infinity, Infinity, Infinity), max = new Vector3(-Infinity, -Infinity, -Infinity);
    for (const mesh of meshes) {
      mesh.refreshBoundingInfo({ applySkeleton: true, applyMorph: true });
      mesh.computeWorldMatrix(true);  // the box in world space
      const b = mesh.getBoundingInfo().boundingBox;
      min = Vector3.Minimize(min, b.minimumWorld);
      max = Vector3.Maximize(max, b.maximumWorld);
    }
    box = { min, max };
  }
  const centre = box.min.add(box.max).scale(0.5), radius = Math.max(box.max.subtract(box.min).length() / 2, 1e-6);
  camera.setTarget(centre);  // (recomputes the radius from the camera's position: set it after)
  camera.radius = radius * 3;
  camera.minZ = radius / 100;
  camera.maxZ = radius * 100;
  new HemisphericLight('sky', new Vector3(0, 1, 0), scene).intensity = 0.6;
  const light = new DirectionalLight('sun', new Vector3(-0.4, -1, -0.3), scene);
  light.position = centre.subtract(light.direction.scale(radius * 4));
  light.intensity = 1.5;
  // The shadow's projection from the decoded file's box, not fitted to the casters' bounds (a GPU-played mesh's are
  // its model's box over every frame, the decoded file's its first frame's).
  light.autoUpdateExtends = false;
  light.autoCalcShadowZBounds = false;
  Object.assign(light, { orthoLeft: -radius * 2, orthoRight: radius * 2, orthoTop: radius * 2, orthoBottom: -radius * 2,
                         shadowMinZ: radius / 10, shadowMaxZ: radius * 10 });
  const shadows = new ShadowGenerator(512, light);
  for (const mesh of meshes) shadows.addShadowCaster(mesh);
  const ground = CreateGround('ground', { width: radius * 8, height: radius * 8 }, scene);
  ground.position = new Vector3(centre.x, box.min.y - radius * 0.05, centre.z);
  ground.material = new StandardMaterial('ground', scene);
  ground.material.diffuseColor = new Color3(0.8, 0.8, 0.8);
  ground.receiveShadows = true;
  scene.render();
  return { scene, container, meshes, box, allocated };
}

// The view drawn, once every shader its pose needs is compiled (a pose that changes the active morph targets' count
// asks for another variant of the material).
async function picture(view) {
  view.scene.render();
  await view.scene.whenReadyAsync();
  view.scene.render();
  const gl = engine._gl, pixels = new Uint8Array(WIDTH * HEIGHT * 4);
  gl.readPixels(0, 0, WIDTH, HEIGHT, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
  return pixels;
}

// The share of pixels whose largest channel difference is above 24 (of 255).
function difference(a, b) {
  let differing = 0;
  for (let i = 0; i < a.length; i += 4)
    if (Math.max(Math.abs(a[i] - b[i]), Math.abs(a[i + 1] - b[i + 1]), Math.abs(a[i + 2] - b[i + 2])) > 24) differing += 1;
  return differing / (a.length / 4);
}

// Pairs each mesh of `a` with one of `b`: the same vertex count, the same name first.
function pairs(a, b) {
  const used = new Set(), out = [];
  for (const mesh of a) {
    const count = mesh.getTotalVertices();
    const candidates = b.filter((m) => !used.has(m) && m.getTotalVertices() === count);
    const match = candidates.find((m) => m.name === mesh.name) ?? candidates[0];
    if (!match) throw new Error(`no mesh of the decoded file has ${count} vertices like ${mesh.name}`);
    used.add(match);
    out.push([mesh, match]);
  }
  return out;
}

// World-space positions: as Babylon computes them on the CPU (morph targets and skinning applied), or for a mesh that
// plays on the GPU, its shape texture read back (the positions its material draws).
async function worldPositions(mesh) {
  mesh.computeWorldMatrix(true);
  mesh.skeleton?.prepare(true);
  let local;
  const player = mesh.metadata?.segmorph?.player;
  if (player) {
    const texels = await player.shape.readPixels(), count = mesh.getTotalVertices();
    local = new Float32Array(count * 3);
    for (let v = 0; v < count; ++v) local.set(texels.subarray(v * 4, v * 4 + 3), v * 3);
  } else {
    local = mesh.getPositionData(true, true);
  }
  const world = mesh.getWorldMatrix(), out = new Float64Array(local.length);
  const p = new Vector3();
  for (let i = 0; i < local.length; i += 3) {
    Vector3.TransformCoordinatesFromFloatsToRef(local[i], local[i + 1], local[i + 2], world, p);
    out[i] = p.x, out[i + 1] = p.y, out[i + 2] = p.z;
  }
  return out;
}

function largestDifference(a, b) {
  let largest = 0;
  for (let i = 0; i < a.length; ++i) largest = Math.max(largest, Math.abs(a[i] - b[i]));
  return largest;
}

// Shows group g of each view at frame `frame` (the others stopped), or, with `weights`, every group at that frame
// with its weight.
function show(view, frame, g, weights = null) {
  view.container.animationGroups.forEach((group, i) => {
    const weight = weights ? weights[i] : i === g ? 1 : 0;
    if (weight === 0) { group.stop(); return; }
    if (!group.isStarted) group.start(true, 1, group.from, group.to);
    group.pause();
    group.setWeightForAllAnimatables(weight);
    group.goToFrame(frame);
  });
}

// options: the extension's (null: its defaults), and standardMaterial: both files drawn with a StandardMaterial.
window.babylonCase = async (compressedUrl, decodedUrl, options = null) => {
  const started = performance.now();
  const decoded = await staged(decodedUrl);
  const { standardMaterial, ...extension } = options ?? {};
  const compressed = await staged(compressedUrl, decoded.box, Object.keys(extension).length ? extension : null);
  const loadMilliseconds = performance.now() - started;
  const result = { pictures: 0, worstPicture: 0, control: 0, positions: 0, worstPosition: 0, frames: 0,
                   diagonal: decoded.box.max.subtract(decoded.box.min).length(), loadMilliseconds,
                   playbacks: compressed.meshes.map((m) => m.metadata?.segmorph).filter((p) => p).map(({ mode, version }) => ({ mode, version })), bytes: { compressed: compressed.allocated, decoded: decoded.allocated },
                   groups: compressed.container.animationGroups.length };
  if (compressed.container.animationGroups.length !== decoded.container.animationGroups.length)
    throw new Error(`${compressed.container.animationGroups.length} animation groups, the decoded file has ${decoded.container.animationGroups.length}`);
  const meshPairs = pairs(compressed.meshes, decoded.meshes);
  if (options?.standardMaterial) {
    // Both files' meshes drawn with a StandardMaterial given after the load (a GPU-played mesh's through its player).
    for (const [x, y] of meshPairs) {
      const material = (scene) => Object.assign(new StandardMaterial('standard', scene), { diffuseColor: new Color3(0.9, 0.6, 0.3) });
      const player = x.metadata?.segmorph?.player;
      x.material = player ? player.material(material(compressed.scene)) : material(compressed.scene);
      y.material = material(decoded.scene);
    }
    await compressed.scene.whenReadyAsync();
    await decoded.scene.whenReadyAsync();
  }
  const compare = async (frame, g, weights) => {
    show(compressed, frame, g, weights);
    show(decoded, frame, g, weights);
    const a = await picture(compressed), b = await picture(decoded), d = difference(a, b);
    if (d >= result.worstPicture) window.worstPictures = [a, b];
    result.worstPicture = Math.max(result.worstPicture, d);
    result.pictures += 1;
    for (const [x, y] of meshPairs) {
      const d = largestDifference(await worldPositions(x), await worldPositions(y));
      if (d > result.worstPosition) result.worstAt = { frame, group: g, weights, mesh: x.name };
      result.worstPosition = Math.max(result.worstPosition, d);
      result.positions += 1;
    }
    return b;
  };
  for (const [g, group] of decoded.container.animationGroups.entries()) {
    const samples = 6, from = group.from, to = group.to;
    let first = null, control = null;
    for (let k = 0; k <= samples; ++k) {
      const frame = from + ((to - from) * k) / samples;
      const b = await compare(frame, g);
      if (k === 0) first = b;
      if (k === 2) control = b;
      result.frames += 1;
    }
    if (first && control) result.control = Math.max(result.control, difference(first, control));
  }
  if (decoded.container.animationGroups.length >= 2) {
    const groups = decoded.container.animationGroups, frame = Math.min(groups[0].to, groups[1].to) / 3;
    const weights = groups.map((_, i) => (i < 2 ? 0.5 : 0));
    await compare(frame, 0, weights);
    result.crossFade = true;
  }
  // The compressed file's container taken out of its scene takes everything the extension made with it (but the
  // materials given after the load).
  compressed.container.removeAllFromScene();
  compressed.scene.render();
  result.leftInScene = standardMaterial ? [] : [...compressed.scene.materials.filter((m) => m.name.endsWith('(segmorph)')).map((m) => m.name),
                        ...compressed.scene.textures.filter((t) => t.name.startsWith('segmorph')).map((t) => t.name),
                        ...compressed.scene.morphTargetManagers.map(() => 'a morph target manager')];
  for (const view of [compressed, decoded]) {
    view.container.dispose();
    view.scene.dispose();
  }
  return result;
};

// The error a load of `url` rejects with (null if it loads).
window.loadError = async (url) => {
  const scene = new Scene(engine);
  try {
    await LoadAssetContainerAsync(url, scene);
    return null;
  } catch (error) {
    return String(error?.message ?? error);
  } finally {
    scene.dispose();
  }
};

await SegmorphDecoder.ready;
window.ready = true;
