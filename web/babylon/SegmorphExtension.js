// SEGMORPH_animation_compression for Babylon.js's glTF 2.0 loader (@babylonjs/loaders 9). Importing this module
// registers the extension (registerGLTFExtension); a page then loads compressed files as any glTF file:
//
//   import '@babylonjs/loaders/glTF/index.js';
//   import { SegmorphDecoder } from 'segmorph/babylon';
//   await SegmorphDecoder.ready;
//   const container = await LoadAssetContainerAsync('walk.glb', scene);
//
// The base meshes are KHR_draco_mesh_compression: point Babylon's DracoDecoder.DefaultConfiguration at local copies
// of the Draco decoder (docs/web.md). Options, per load, through the loader's extension options:
//   { pluginOptions: { gltf: { extensionOptions: { SEGMORPH_animation_compression: { normals: true } } } } }
// normals (default true): turn the normals with the surface in every frame or target, as segmorph decode does.
//
// What it does with each part of the extension (docs/web.md, "Babylon.js"):
// - coded tracks (an animation's translation, rotation and scale samplers in a track stream): decoded when the loader
//   starts, and served as the data of their accessors, so that the loader builds ordinary Animations from them;
// - a primitive that keeps its morph targets: the targets' positions (and normals) are filled in from the stream;
//   the node's weights animation plays them as usual;
// - a primitive that plays clips: its stream is decoded against the Draco base mesh; every frame of every clip becomes
//   a MorphTarget of a MorphTargetManager (Babylon's targets hold absolute positions, so at influence 1 on one target
//   the mesh shows that frame exactly), the mesh's POSITION becomes frame 0 of clip 0 (what it shows when no clip
//   plays), and the AnimationGroup of the glTF animation each clip names gets an Animation of every target's influence,
//   as a glTF weights channel would: a frame of the clip is 1 at its time and 0 at its neighbours' (LINEAR or STEP as
//   the clip says), the other clips' frames stay 0;
// - placeholder channels play a constant; they stay.
// Each clip primitive's mesh says how it plays in mesh.metadata.segmorph ({ mode: 'morph', version }).
// A damaged or mismatched stream makes the load fail with an Error that names the mesh, primitive or animation.
import { Animation } from '@babylonjs/core/Animations/animation.js';
import { VertexBuffer } from '@babylonjs/core/Buffers/buffer.js';
import { MorphTarget } from '@babylonjs/core/Morph/morphTarget.js';
import { MorphTargetManager } from '@babylonjs/core/Morph/morphTargetManager.js';
import { registerGLTFExtension, unregisterGLTFExtension } from '@babylonjs/loaders/glTF/2.0/glTFLoaderExtensionRegistry.js';

import { NAME, checkClips, trackLayout } from '../gltf_extension.js';
import { SegmorphDecoder } from '../segmorph_decoder.js';
import { SurfaceNormals } from '../surface_normals.js';

export { SegmorphDecoder };

const STEP = 1;  // AnimationKeyInterpolation.STEP

export class SegmorphExtension {
  // Made by the factory below, once per load, after the coded tracks are decoded.
  constructor(loader, options) {
    this.name = NAME;
    this.enabled = true;
    this.order = 50;  // before the loader's own handling of anything it serves
    this._loader = loader;
    this.options = { normals: true, ...options };
    this.playbacks = [];  // per clip primitive: { what, mode: 'morph', version }
    this.views = new Map();  // synthetic bufferView → its decoded bytes (coded tracks)
    this.decodeMilliseconds = 0;  // time spent in the decoder
  }

  dispose() {
    this._loader = null;
    this.views.clear();
  }

  async _timed(what, decode) {
    const started = performance.now();
    try {
      return await decode();
    } catch (error) {
      throw new Error(`${what}: ${error.message}`);
    } finally {
      this.decodeMilliseconds += performance.now() - started;
    }
  }

  async _bytes(index) {
    const gltf = this._loader.gltf, view = gltf.bufferViews?.[index];
    if (!view) throw new Error(`bufferView ${index} does not exist`);
    const data = await this._loader.loadBufferViewAsync(`/bufferViews/${index}`, view);
    return new Uint8Array(data.buffer, data.byteOffset, data.byteLength).slice();
  }

  // Coded tracks: each coded sampler's accessors get a bufferView of their own, served by loadBufferViewAsync from
  // the decoded stream, before the loader reads any animation.
  async _decodeTracks() {
    const gltf = this._loader.gltf, animations = gltf.animations ?? [];
    for (let a = 0; a < animations.length; ++a) {
      const coded = animations[a].extensions?.[NAME];
      if (!coded) continue;
      const what = `${NAME}: animation ${a}`;
      const { timeAccessors, samplers } = trackLayout(gltf, animations[a], coded, what);
      const stream = await this._timed(what, () => this._bytes(coded.bufferView));
      const counts = timeAccessors.map((i) => gltf.accessors[i].count);
      const decoded = await this._timed(what, () => SegmorphDecoder.decodeTracks(stream, counts, samplers));
      timeAccessors.forEach((accessor, i) => this._serve(gltf, accessor, decoded.times[i]));
      coded.samplers.forEach((s, i) => this._serve(gltf, animations[a].samplers[s].output, decoded.values[i]));
    }
  }

  _serve(gltf, accessor, floats) {
    const index = gltf.bufferViews.length;
    gltf.bufferViews.push({ buffer: 0, byteLength: floats.byteLength, index, extras: { segmorph: 'decoded' } });
    gltf.accessors[accessor].bufferView = index;
    gltf.accessors[accessor].byteOffset = 0;
    this.views.set(index, new Uint8Array(floats.buffer, floats.byteOffset, floats.byteLength));
  }

  loadBufferViewAsync(context, bufferView) {
    const bytes = this.views.get(bufferView.index);
    return bytes ? Promise.resolve(bytes) : null;
  }

  // The compressed primitives, once the loader has built the meshes (their Draco base meshes decoded) and the
  // animation groups, before it starts any animation.
  async onReady() {
    const gltf = this._loader.gltf, work = [];
    (gltf.meshes ?? []).forEach((mesh, m) =>
      mesh.primitives.forEach((primitive, p) => {
        const extension = primitive.extensions?.[NAME];
        if (!extension) return;
        const meshes = primitiveMeshes(gltf, m, p);
        if (meshes.length === 0) return;
        const what = `${NAME}: mesh ${m} primitive ${p}`;
        work.push(extension.morphTargets ? this._keptTargets(meshes, extension, what)
                                         : this._clips(meshes, extension, what));
      }));
    await Promise.all(work);
  }

  async _inputs(mesh, extension, what) {
    const positions = mesh.getVerticesData(VertexBuffer.PositionKind, false, true);
    if (!(positions instanceof Float32Array) || positions.length === 0) throw new Error(`${what}: its base mesh has no float POSITION`);
    const indices = mesh.getIndices(false, true);
    if (!indices || indices.length === 0) throw new Error(`${what}: its base mesh has no triangles`);
    const stream = await this._timed(what, () => this._bytes(extension.bufferView));
    return { stream, positions, indices: Uint32Array.from(indices) };
  }

  async _keptTargets(meshes, extension, what) {
    const mesh = meshes[0], manager = mesh.morphTargetManager;
    const { stream, positions, indices } = await this._inputs(mesh, extension, what);
    const decoded = await this._timed(what, () => SegmorphDecoder.decodeTargetsAsync(stream, positions, indices));
    const count = manager?.numTargets ?? 0;
    if (decoded.targetCount !== count) throw new Error(`${what}: the stream holds ${decoded.targetCount} targets, the primitive has ${count}`);
    const floats = positions.length, baseNormals = mesh.getVerticesData(VertexBuffer.NormalKind, false, true);
    const normals = this.options.normals && baseNormals && new SurfaceNormals(positions, indices, baseNormals);
    for (let t = 0; t < count; ++t) {
      const target = manager.getTarget(t), shape = new Float32Array(floats);
      for (let i = 0; i < floats; ++i) shape[i] = positions[i] + decoded.deltas[t * floats + i];
      target.setPositions(shape);
      if (normals && target.hasNormals) target.setNormals(normals.turned(shape));
    }
    manager.synchronize();  // the targets' texture made again from the filled-in shapes
    mesh.refreshBoundingInfo({ applyMorph: true });
  }

  async _clips(meshes, extension, what) {
    const gltf = this._loader.gltf, mesh = meshes[0], scene = mesh.getScene();
    const { stream, positions, indices } = await this._inputs(mesh, extension, what);
    const times = await Promise.all(extension.clips.map((clip, c) => {
      const accessor = gltf.accessors?.[clip.times];
      if (!accessor) throw new Error(`${what}: clip ${c} names accessor ${clip.times}, which does not exist`);
      return this._loader._loadFloatAccessorAsync(`/accessors/${clip.times}`, accessor);
    }));
    const decoded = await this._timed(what, () => SegmorphDecoder.decodeStreamAsync(stream, positions, indices));
    checkClips(decoded.clips.map((c) => c.frameCount), extension, times.map((t) => t.length), what);
    this.playbacks.push({ what, mode: 'morph', version: decoded.version });
    const floats = positions.length, baseNormals = mesh.getVerticesData(VertexBuffer.NormalKind, false, true);
    const normals = this.options.normals && baseNormals && new SurfaceNormals(positions, indices, baseNormals);
    // Every frame a target: at influence 1 on one target the position is that frame exactly.
    const manager = new MorphTargetManager(scene), targets = [];
    manager.areUpdatesFrozen = true;  // its texture made once, below
    let shown = null;
    decoded.clips.forEach((clip, c) => {
      for (let f = 0; f < clip.frameCount; ++f) {
        const frame = clip.frames.slice(f * floats, (f + 1) * floats);
        const target = new MorphTarget(`${mesh.name} clip ${c} frame ${f}`, 0, scene);
        target.setPositions(frame);
        if (normals) target.setNormals(normals.turned(frame));
        manager.addTarget(target);
        targets.push(target);
        shown ??= { positions: frame, normals: normals ? target.getNormals() : null };
      }
    });
    manager.areUpdatesFrozen = false;
    const playback = { mode: 'morph', version: decoded.version };
    for (const m of meshes) {
      m.setVerticesData(VertexBuffer.PositionKind, shown.positions, false);
      if (shown.normals) m.setVerticesData(VertexBuffer.NormalKind, shown.normals, false);
      m.morphTargetManager = manager;
      m.metadata = { ...m.metadata, segmorph: playback };
    }
    // Each clip: its animation's group animates every target, as a glTF weights channel does: its own frames' one
    // hot at their times, the other clips' frames held at 0.
    const fps = this._loader.parent.targetFps;
    let first = 0;
    extension.clips.forEach((clip, c) => {
      const group = gltf.animations?.[clip.animation]?._babylonAnimationGroup;
      if (!group) throw new Error(`${what}: a clip names animation ${clip.animation}, which does not exist`);
      const keys = times[c], step = clip.interpolation === 'STEP', last = keys.length - 1;
      const zero = [{ frame: keys[0] * fps, value: 0 }, { frame: keys[last] * fps, value: 0 }];
      targets.forEach((target, t) => {
        const f = t - first;
        const animation = new Animation(`${mesh.name} clip ${c} target ${t}`, 'influence', fps, Animation.ANIMATIONTYPE_FLOAT);
        animation.setKeys(f >= 0 && f <= last ? oneHotKeys(keys, f, fps, step) : zero);
        group.addTargetedAnimation(animation, target);
      });
      first += keys.length;
    });
    for (const m of meshes) m.refreshBoundingInfo({ applyMorph: false });
  }
}

// Keys of the influence of frame f of a clip whose frames are at `times`: 1 at its time, 0 at its neighbours' and
// at the clip's ends (held between them), in frames at `fps`.
function oneHotKeys(times, f, fps, step) {
  const keys = [], last = times.length - 1;
  const key = (i, value) => keys.push(step ? { frame: times[i] * fps, value, interpolation: STEP } : { frame: times[i] * fps, value });
  if (f - 1 > 0) key(0, 0);
  if (f > 0) key(f - 1, 0);
  key(f, 1);
  if (f < last) key(f + 1, 0);
  if (f + 1 < last) key(last, 0);
  return keys;
}

// The Babylon meshes the loader made of mesh m's primitive p: every node's that uses the mesh.
function primitiveMeshes(gltf, m, p) {
  const meshes = [];
  for (const node of gltf.nodes ?? []) {
    if (node.mesh !== m) continue;
    const babylon = node._primitiveBabylonMeshes?.[p];
    if (babylon) meshes.push(babylon.sourceMesh ?? babylon);
  }
  return [...new Set(meshes)];
}

// The extension for every load from now on (importing this module calls it; again after unregisterSegmorph()).
export function registerSegmorph() {
  unregisterGLTFExtension(NAME);
  registerGLTFExtension(NAME, true, async (loader) => {
    await SegmorphDecoder.ready;
    const extension = new SegmorphExtension(loader, loader.parent.extensionOptions?.[NAME]);
    await extension._decodeTracks();
    return extension;
  });
}

export function unregisterSegmorph() {
  return unregisterGLTFExtension(NAME);
}

registerSegmorph();
