// In Chromium (bench/lib/browser.mjs): how long GLTFLoader takes from a file's bytes to a scene ready to play, for a
// segmorph file (with the plugin: the Draco base meshes and the streams) and for gltfpack's file of the same sequence
// (MeshoptDecoder). window.measure(url, kind, repeats) → { first, median, decode: { first, median } } in
// milliseconds: `first` the first load in the page (the decoder's WebAssembly compiled on demand), `median` of the
// repeats after it; `decode` the time inside the decoder alone (the plugin's, or MeshoptDecoder.decodeGltfBuffer's).
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';

import { GLTFSegmorphExtension } from '/three/GLTFSegmorphExtension.js';

const draco = new DRACOLoader().setDecoderPath('/vendor/three/examples/jsm/libs/draco/');
// MeshoptDecoder's time: GLTFLoader calls decodeGltfBufferAsync when there is one, which without workers runs the
// same decode on this thread; removing it makes GLTFLoader call decodeGltfBuffer, timed here.
let meshoptMilliseconds = 0;
const decodeGltfBuffer = MeshoptDecoder.decodeGltfBuffer;
MeshoptDecoder.decodeGltfBufferAsync = undefined;
MeshoptDecoder.decodeGltfBuffer = (...args) => {
  const started = performance.now();
  decodeGltfBuffer(...args);
  meshoptMilliseconds += performance.now() - started;
};

async function loadOnce(bytes, kind) {
  const loader = new GLTFLoader();
  let plugin = null;
  if (kind === 'segmorph') {
    loader.setDRACOLoader(draco);
    loader.register((parser) => (plugin = new GLTFSegmorphExtension(parser)));
  } else {
    loader.setMeshoptDecoder(MeshoptDecoder);
  }
  meshoptMilliseconds = 0;
  const started = performance.now();
  await loader.parseAsync(bytes.slice(0), '');
  return { load: performance.now() - started, decode: kind === 'segmorph' ? plugin.decodeMilliseconds : meshoptMilliseconds };
}

const median = (values) => {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted.length % 2 ? sorted[(sorted.length - 1) / 2] : (sorted[sorted.length / 2 - 1] + sorted[sorted.length / 2]) / 2;
};

window.measure = async (url, kind, repeats) => {
  await MeshoptDecoder.ready;
  const bytes = await (await fetch(url)).arrayBuffer();
  const first = await loadOnce(bytes, kind);
  const rest = [];
  for (let i = 0; i < repeats; ++i) rest.push(await loadOnce(bytes, kind));
  return { first: first.load, median: median(rest.map((r) => r.load)),
           decode: { first: first.decode, median: median(rest.map((r) => r.decode)) } };
};

window.ready = true;
