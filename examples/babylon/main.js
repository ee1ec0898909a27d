// A Babylon.js page that plays a glTF file, plain or compressed by segmorph: `import 'segmorph/babylon'` (here the
// package's file, served at /babylon/) is all a Babylon page needs besides a Draco decoder for the base meshes.
// Open ?file=URL or drop a .glb; it frames the scene, plays the first animation group and shows the file's bytes,
// the WebGL bytes its load and first frame allocated and how its compressed primitives play (docs/web.md,
// "Babylon.js"). Served by web/serve.mjs:
//   node web/serve.mjs --root /example/=examples/babylon --root /files/=samples    then open /example/?file=/files/Fox/Fox.glb
import { Engine } from '@babylonjs/core/Engines/engine.js';
import { Scene } from '@babylonjs/core/scene.js';
import { Vector3 } from '@babylonjs/core/Maths/math.vector.js';
import { ArcRotateCamera } from '@babylonjs/core/Cameras/arcRotateCamera.js';
import { HemisphericLight } from '@babylonjs/core/Lights/hemisphericLight.js';
import { LoadAssetContainerAsync } from '@babylonjs/core/Loading/sceneLoader.js';
import { DracoDecoder } from '@babylonjs/core/Meshes/Compression/dracoDecoder.js';
import '@babylonjs/loaders/glTF/index.js';

import { SegmorphDecoder } from '/babylon/SegmorphExtension.js';
import { gpuBytes, install } from '/gpu_bytes.js';

install();  // before the engine makes its context
const draco = '/vendor/three/examples/jsm/libs/draco/gltf/';  // any copy of Google's glTF Draco decoder
DracoDecoder.DefaultConfiguration = { wasmUrl: `${draco}draco_wasm_wrapper.js`, wasmBinaryUrl: `${draco}draco_decoder.wasm`,
                                      fallbackUrl: `${draco}draco_decoder.js` };
const canvas = document.getElementById('view');
const engine = new Engine(canvas, true, { preserveDrawingBuffer: true, stencil: true });
let scene = null;
engine.runRenderLoop(() => scene?.render());
window.addEventListener('resize', () => engine.resize());

// Loads `source` (a URL, or a File with its name) into a new scene; resolves with what the page shows.
async function open(source, name) {
  await SegmorphDecoder.ready;
  scene?.dispose();
  scene = new Scene(engine);
  const camera = new ArcRotateCamera('camera', 0.8, 1.2, 3, Vector3.Zero(), scene);
  camera.attachControl(canvas, true);
  new HemisphericLight('light', new Vector3(0.3, 1, 0.2), scene);
  const before = gpuBytes.allocated, started = performance.now();
  const container = await LoadAssetContainerAsync(source, scene, name ? { pluginExtension: '.glb', name } : undefined);
  container.addAllToScene();
  await scene.whenReadyAsync();
  scene.render();
  const milliseconds = performance.now() - started, allocated = gpuBytes.allocated - before;
  const { min, max } = scene.getWorldExtends((mesh) => mesh.isVisible && mesh.getTotalVertices() > 0);
  camera.setTarget(min.add(max).scale(0.5));  // (recomputes the radius: set it after)
  camera.radius = max.subtract(min).length() * 1.2;
  camera.minZ = camera.radius / 100;
  container.animationGroups[0]?.start(true);
  const modes = container.meshes.map((m) => m.metadata?.segmorph?.mode).filter((m) => m);
  const plays = modes.length === 0 ? '' : `, ${modes.filter((m) => m === 'gpu').length} of ${modes.length} compressed ` +
    `primitives on the GPU`;
  const bytes = typeof source === 'string' ? (await (await fetch(source)).arrayBuffer()).byteLength : source.size;
  const text = `${name ?? source}: ${bytes.toLocaleString('en')} bytes, GPU ${(allocated / 1e6).toFixed(2)} MB${plays}, ` +
    `loaded in ${milliseconds.toFixed(0)} ms, ${container.animationGroups.length} animation groups`;
  document.getElementById('facts').textContent = text;
  return { text, allocated, groups: container.animationGroups.length, modes };
}

window.addEventListener('dragover', (event) => event.preventDefault());
window.addEventListener('drop', (event) => {
  event.preventDefault();
  const file = event.dataTransfer.files[0];
  if (file) open(file, file.name).catch((error) => { document.getElementById('facts').textContent = error.message; });
});

// For tests: the result of the first load (the ?file= one), and open() itself.
const file = new URLSearchParams(location.search).get('file');
window.example = { open, loaded: file ? open(file).catch((error) => ({ error: error.message })) : null };
