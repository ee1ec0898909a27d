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
//   { pluginOptions: { gltf: { extensionOptions: { SEGMORPH_animation_compression: { playback: 'gpu' } } } } }
// playback (default 'gpu'): 'gpu' plays a version-4 stream of clips from its model on the GPU (other versions play as
// 'morph'), 'morph' makes every frame a morph target; normals (default true): turn the normals with the surface in
// every frame or target, as segmorph decode does.
//
// What it does with each part of the extension (docs/web.md, "Babylon.js"):
// - coded tracks (an animation's translation, rotation and scale samplers in a track stream): decoded when the loader
//   starts, and served as the data of their accessors, so that the loader builds ordinary Animations from them;
// - a primitive that keeps its morph targets: the targets' positions (and normals) are filled in from the stream;
//   the node's weights animation plays them as usual;
// - a primitive that plays clips, on the GPU (the default, for version-4 streams): the stream's model is uploaded as
//   float textures and evaluated per vertex into a shape texture whenever the shown parameters change; the mesh's
//   cloned materials take positions and turned normals from it (GpuPlayback below); the AnimationGroups animate one
//   influence per frame as with morph targets, and the parameters are blended by them;
// - a primitive that plays clips as morph targets: its stream is decoded against the Draco base mesh; every frame of every clip becomes
//   a MorphTarget of a MorphTargetManager (Babylon's targets hold absolute positions, so at influence 1 on one target
//   the mesh shows that frame exactly), the mesh's POSITION becomes frame 0 of clip 0 (what it shows when no clip
//   plays), and the AnimationGroup of the glTF animation each clip names gets an Animation of every target's influence,
//   as a glTF weights channel would: a frame of the clip is 1 at its time and 0 at its neighbours' (LINEAR or STEP as
//   the clip says), the other clips' frames stay 0;
// - placeholder channels play a constant; they stay.
// Each clip primitive's mesh says how it plays in mesh.metadata.segmorph ({ mode: 'gpu' | 'morph', version }, and the
// GpuPlayback as player on the GPU).
// A damaged or mismatched stream makes the load fail with an Error that names the mesh, primitive or animation.
import { Animation } from '@babylonjs/core/Animations/animation.js';
import { VertexBuffer } from '@babylonjs/core/Buffers/buffer.js';
import { BoundingInfo } from '@babylonjs/core/Culling/boundingInfo.js';
import { Constants } from '@babylonjs/core/Engines/constants.js';
import { EffectRenderer, EffectWrapper } from '@babylonjs/core/Materials/effectRenderer.js';
import { MaterialPluginBase } from '@babylonjs/core/Materials/materialPluginBase.js';
import { ShadowDepthWrapper } from '@babylonjs/core/Materials/shadowDepthWrapper.js';
import { RawTexture } from '@babylonjs/core/Materials/Textures/rawTexture.js';
import { RenderTargetTexture } from '@babylonjs/core/Materials/Textures/renderTargetTexture.js';
import { Vector3 } from '@babylonjs/core/Maths/math.vector.js';
import { MorphTarget } from '@babylonjs/core/Morph/morphTarget.js';
import { MorphTargetManager } from '@babylonjs/core/Morph/morphTargetManager.js';
import { registerGLTFExtension, unregisterGLTFExtension } from '@babylonjs/loaders/glTF/2.0/glTFLoaderExtensionRegistry.js';

import { NAME, checkClips, trackLayout } from '../gltf_extension.js';
import { SegmorphDecoder } from '../segmorph_decoder.js';
import { MODEL_GLSL, TEXEL_GLSL, TURN_GLSL, blendParameters, surfaceRings, textureWidth } from '../model_playback.js';

export { SegmorphDecoder };

const STEP = 1;  // AnimationKeyInterpolation.STEP

export class SegmorphExtension {
  // Made by the factory below, once per load, after the coded tracks are decoded.
  constructor(loader, options) {
    this.name = NAME;
    this.enabled = true;
    this.order = 50;  // before the loader's own handling of anything it serves
    this._loader = loader;
    this.options = { normals: true, playback: 'gpu', ...options };
    if (!['gpu', 'morph'].includes(this.options.playback))
      throw new Error(`${NAME}: playback must be 'gpu' or 'morph', not '${this.options.playback}'`);
    this.views = new Map();  // synthetic bufferView → its decoded bytes (coded tracks)
  }

  dispose() {
    this._loader = null;
    this.views.clear();
  }

  // `decode()`'s result, its errors prefixed with `what` (and still saying whether the stream is of an earlier version).
  async _named(what, decode) {
    try {
      return await decode();
    } catch (error) {
      throw Object.assign(new Error(`${what}: ${error.message}`), { unsupported: error.unsupported === true });
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
      const stream = await this._named(what, () => this._bytes(coded.bufferView));
      const counts = timeAccessors.map((i) => gltf.accessors[i].count);
      const decoded = await this._named(what, () => SegmorphDecoder.decodeTracks(stream, counts, samplers));
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
    const gltf = this._loader.gltf, work = [], scene = this._loader.babylonScene;
    // What the work below makes (materials, textures, morph target managers) goes where the loader's own objects went:
    // into the asset container of LoadAssetContainerAsync (so that addAllToScene, removeAllFromScene and dispose handle
    // it), else the scene.
    const container = this._loader._assetContainer, lists = ['materials', 'textures', 'morphTargetManagers'];
    const before = lists.map((list) => new Set(scene[list]));
    this.ownsEntities = !container;
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
    try {
      await Promise.all(work);
    } finally {
      if (container) {
        const remove = { materials: 'removeMaterial', textures: 'removeTexture', morphTargetManagers: 'removeMorphTargetManager' };
        lists.forEach((list, i) => {
          for (const made of scene[list].filter((o) => !before[i].has(o))) {
            scene[remove[list]](made);
            container[list].push(made);
            made._parentContainer = container;
          }
        });
      }
    }
  }

  async _inputs(mesh, extension, what) {
    const positions = mesh.getVerticesData(VertexBuffer.PositionKind, false, true);
    if (!(positions instanceof Float32Array) || positions.length === 0) throw new Error(`${what}: its base mesh has no float POSITION`);
    const indices = mesh.getIndices(false, true);
    if (!indices || indices.length === 0) throw new Error(`${what}: its base mesh has no triangles`);
    const stream = await this._named(what, () => this._bytes(extension.bufferView));
    return { stream, positions, indices: Uint32Array.from(indices) };
  }

  // Every node that uses the mesh has a Mesh and a MorphTargetManager of its own (the loader instances no mesh with
  // targets): each gets the shapes.
  async _keptTargets(meshes, extension, what) {
    const mesh = meshes[0];
    const { stream, positions, indices } = await this._inputs(mesh, extension, what);
    const baseNormals = this.options.normals ? floatsOf(mesh.getVerticesData(VertexBuffer.NormalKind, false, true)) : null;
    const decoded = await this._named(what, () =>
      SegmorphDecoder.decodeTargetsAsync(stream, positions, indices, baseNormals ?? undefined));
    const count = mesh.morphTargetManager?.numTargets ?? 0;
    if (decoded.targetCount !== count) throw new Error(`${what}: the stream holds ${decoded.targetCount} targets, the primitive has ${count}`);
    const floats = positions.length, shapes = [], turned = [];
    for (let t = 0; t < count; ++t) {
      const shape = new Float32Array(floats);
      for (let i = 0; i < floats; ++i) shape[i] = positions[i] + decoded.deltas[t * floats + i];
      shapes.push(shape);
      turned.push(decoded.normals ? decoded.normals.subarray(t * floats, (t + 1) * floats) : null);
    }
    for (const m of meshes) {
      const manager = m.morphTargetManager;
      if (manager?.numTargets !== count) throw new Error(`${what}: a node's mesh has ${manager?.numTargets ?? 0} targets, the stream ${count}`);
      for (let t = 0; t < count; ++t) {
        const target = manager.getTarget(t);
        target.setPositions(shapes[t]);
        if (turned[t] && target.hasNormals) target.setNormals(turned[t]);
      }
      manager.synchronize();  // the targets' texture made again from the filled-in shapes
      m.refreshBoundingInfo({ applyMorph: true });
    }
  }

  async _clips(meshes, extension, what) {
    const gltf = this._loader.gltf, mesh = meshes[0], scene = mesh.getScene();
    const { stream, positions, indices } = await this._inputs(mesh, extension, what);
    const times = await Promise.all(extension.clips.map((clip, c) => {
      const accessor = gltf.accessors?.[clip.times];
      if (!accessor) throw new Error(`${what}: clip ${c} names accessor ${clip.times}, which does not exist`);
      return this._loader._loadFloatAccessorAsync(`/accessors/${clip.times}`, accessor);
    }));
    let fallback = null;  // why a version-4 stream plays as morph targets under 'gpu'
    if (this.options.playback === 'gpu') {
      let model = null;
      try {
        model = await this._named(what, () => SegmorphDecoder.decodeModelAsync(stream, positions, indices));
      } catch (error) {
        if (!error.unsupported) throw error;  // damaged: reject; versions 1-3: morph targets below
      }
      const unplayable = model && gpuUnplayable(scene, model, indices);
      if (unplayable) fallback = unplayable;
      if (model && !unplayable) {
        checkClips(model.clipFrames, extension, times.map((t) => t.length), what);
        const normals = this.options.normals && mesh.getVerticesData(VertexBuffer.NormalKind) !== null;
        let player = null;
        try {
          player = new GpuPlayback(model, meshes, positions, indices, normals, this.ownsEntities);
          await player.ready();
          this._animate(player.targets, extension, times, `${mesh.name}`, what);
        } catch (error) {
          player?.dispose();
          throw new Error(`${what}: ${error.message}`);
        }
        return;
      }
    }
    const baseNormals = this.options.normals ? floatsOf(mesh.getVerticesData(VertexBuffer.NormalKind, false, true)) : null;
    const decoded = await this._named(what, () =>
      SegmorphDecoder.decodeStreamAsync(stream, positions, indices, baseNormals ?? undefined));
    checkClips(decoded.clips.map((c) => c.frameCount), extension, times.map((t) => t.length), what);
    const floats = positions.length, normals = baseNormals !== null;
    // Every frame a target: at influence 1 on one target the position is that frame exactly.
    const manager = new MorphTargetManager(scene), targets = [];
    manager.areUpdatesFrozen = true;  // its texture made once, below
    let shown = null;
    decoded.clips.forEach((clip, c) => {
      for (let f = 0; f < clip.frameCount; ++f) {
        const frame = clip.frames.slice(f * floats, (f + 1) * floats);
        const target = new MorphTarget(`${mesh.name} clip ${c} frame ${f}`, 0, scene);
        target.setPositions(frame);
        if (normals) target.setNormals(clip.normals.slice(f * floats, (f + 1) * floats));
        manager.addTarget(target);
        targets.push(target);
        shown ??= { positions: frame, normals: normals ? target.getNormals() : null };
      }
    });
    manager.areUpdatesFrozen = false;
    const playback = { mode: 'morph', version: decoded.version, ...(fallback ? { reason: fallback } : {}) };
    for (const m of meshes) {
      m.setVerticesData(VertexBuffer.PositionKind, shown.positions, false);
      if (shown.normals) m.setVerticesData(VertexBuffer.NormalKind, shown.normals, false);
      m.morphTargetManager = manager;
      m.metadata = { ...m.metadata, segmorph: playback };
    }
    this._animate(targets, extension, times, mesh.name, what);
    for (const m of meshes) m.refreshBoundingInfo({ applyMorph: false });
  }

  // Each clip: its animation's group animates every target (an object with an influence per frame of the stream), as
  // a glTF weights channel does: its own frames one-hot at their times, the other clips' frames held at 0.
  _animate(targets, extension, times, name, what) {
    const gltf = this._loader.gltf, fps = this._loader.parent.targetFps;
    let first = 0;
    extension.clips.forEach((clip, c) => {
      const group = gltf.animations?.[clip.animation]?._babylonAnimationGroup;
      if (!group) throw new Error(`${what}: a clip names animation ${clip.animation}, which does not exist`);
      const keys = times[c], step = clip.interpolation === 'STEP', last = keys.length - 1;
      const zero = [{ frame: keys[0] * fps, value: 0 }, { frame: keys[last] * fps, value: 0 }];
      targets.forEach((target, t) => {
        const f = t - first;
        const animation = new Animation(`${name} clip ${c} target ${t}`, 'influence', fps, Animation.ANIMATIONTYPE_FLOAT);
        animation.setKeys(f >= 0 && f <= last ? oneHotKeys(keys, f, fps, step) : zero);
        group.addTargetedAnimation(animation, target);
      });
      first += keys.length;
    });
  }
}

// The model's evaluation per vertex (docs/runtime.md, "Playing the model"; MODEL_GLSL's segmorphEvaluate, the C API's
// float32 arithmetic and order), in a fragment shader: texel v of the shape texture is vertex v's position at the shown parameters. Per vertex
// (textures of the shape's size): its base position and first coefficient vector, its 4 clusters and 4 weights;
// segmorphParameters holds cluster k's [A | t] rows at texels 3k .. 3k + 2, then the basis values 4 to a texel;
// segmorphClusters row k its centroid and (first basis value, m_k); segmorphCoefficients the coefficient vectors.
const SHAPE_GLSL = `
precision highp float;
precision highp int;
uniform highp sampler2D segmorphVertices;
uniform highp sampler2D segmorphVertexClusters;
uniform highp sampler2D segmorphVertexWeights;
uniform highp sampler2D segmorphParameters;
uniform highp sampler2D segmorphClusters;
uniform highp sampler2D segmorphCoefficients;
uniform int segmorphCount;
${TEXEL_GLSL}${MODEL_GLSL}
void main(void) {
  ivec2 at = ivec2(gl_FragCoord.xy);
  int v = at.y * textureSize(segmorphVertices, 0).x + at.x;
  if (v >= segmorphCount) { gl_FragColor = vec4(0.0); return; }
  vec4 vertex = texelFetch(segmorphVertices, at, 0);
  ivec4 clusters = ivec4(texelFetch(segmorphVertexClusters, at, 0));
  gl_FragColor = vec4(segmorphEvaluate(vertex.xyz, clusters, texelFetch(segmorphVertexWeights, at, 0), int(vertex.w)), 1.0);
}
`;

// What the mesh's material does with the shape texture (SegmorphPlugin): the vertex's position is texel gl_VertexID;
// with normals, the base normal turned by the smallest rotation taking the base surface normal around the vertex's
// point (segmorphSurface) to today's, summed over the same triangles (segmorphRing: the first and the count of its
// entries in segmorphTriangles, each a triangle's three vertices), as segmorph decode turns them.
const VERTEX_DEFINITIONS = `
uniform highp sampler2D segmorphShape;
uniform highp sampler2D segmorphTriangles;
#ifdef SEGMORPH_NORMALS
attribute vec3 segmorphSurface;
attribute vec2 segmorphRing;
#endif
${TEXEL_GLSL}
#ifdef SEGMORPH_NORMALS
${TURN_GLSL}
vec3 segmorphNormal(vec3 n) {
  return segmorphTurn(n, segmorphSurface, int(segmorphRing.x), int(segmorphRing.y));
}
#endif
`;

// A material evaluating a GpuPlayback's shape: the plugin of each clone of the meshes' materials.
class SegmorphPlugin extends MaterialPluginBase {
  constructor(material, player, normals) {
    super(material, 'Segmorph', 300, { SEGMORPH: false, SEGMORPH_NORMALS: false });
    this._player = player;
    this._normals = normals;
    this._enable(true);
  }

  getClassName() {
    return 'SegmorphPlugin';
  }

  isCompatible(shaderLanguage) {
    return shaderLanguage === 0;  // GLSL (WebGL 2)
  }

  prepareDefines(defines) {
    defines.SEGMORPH = true;
    defines.SEGMORPH_NORMALS = this._normals;
  }

  getSamplers(samplers) {
    samplers.push('segmorphShape', 'segmorphTriangles');
  }

  getAttributes(attributes) {
    if (this._normals) attributes.push('segmorphSurface', 'segmorphRing');
  }

  getUniforms() {
    return { ubo: [] };
  }

  bindForSubMesh(uniformBuffer) {
    uniformBuffer.setTexture('segmorphShape', this._player.shape);
    uniformBuffer.setTexture('segmorphTriangles', this._player.triangleTexture ?? this._player.shape);
  }

  getCustomCode(shaderType) {
    if (shaderType !== 'vertex') return null;
    return {
      CUSTOM_VERTEX_DEFINITIONS: VERTEX_DEFINITIONS,
      CUSTOM_VERTEX_UPDATE_POSITION: 'positionUpdated = segmorphTexel(segmorphShape, gl_VertexID).xyz;',
      CUSTOM_VERTEX_UPDATE_NORMAL: '#if defined(NORMAL) && defined(SEGMORPH_NORMALS)\nnormalUpdated = segmorphNormal(normalUpdated);\n#endif',
    };
  }
}

// A float RGBA texture of `count` texels from `values` (4 floats a texel, padded with zeros), read by texelFetch.
function floatTexture(scene, values, count, width = textureWidth(Math.max(count, 1))) {
  const height = Math.max(1, Math.ceil(Math.max(count, 1) / width)), data = new Float32Array(width * height * 4);
  data.set(values.subarray(0, Math.min(values.length, data.length)));
  const texture = new RawTexture(data, width, height, Constants.TEXTUREFORMAT_RGBA, scene, false, false,
                                 Constants.TEXTURE_NEAREST_SAMPLINGMODE, Constants.TEXTURETYPE_FLOAT);
  texture.wrapU = texture.wrapV = Constants.TEXTURE_CLAMP_ADDRESSMODE;
  texture.name = 'segmorph model';
  return texture;
}

// GPU playback of a clip primitive (the default for version-4 streams): the model's per-vertex data (gathered through
// its welded map), clusters and coefficients become float textures; `targets` (one { influence } a frame of the
// stream) are what the animation groups animate. Before the scene is drawn, when their influences changed, the
// parameters are blended by them (frame f by weight w_f and frame 0 of clip 0 by 1 − Σ w_f, exact because positions
// are linear in the parameters), uploaded (K × 12 + N floats), and a pass evaluates every vertex into the shape
// texture (SHAPE_GLSL), from which the meshes' cloned materials (SegmorphPlugin) take positions and turn normals.
// Their shadows follow through a ShadowDepthWrapper of each material. The bounds are the model's box.
export class GpuPlayback {
  // ownsTextures: this player disposes its textures (false when an asset container holds them).
  constructor(model, meshes, positions, indices, normals, ownsTextures = true) {
    this.model = model;
    this.meshes = meshes;
    this.normals = normals;
    this.ownsTextures = ownsTextures;
    const scene = meshes[0].getScene(), engine = scene.getEngine();
    const { vertexCount: V, clusterCount: K, coefficientCount: C, basisCount: N, frameCount: F } = model;
    if (V >= 1 << 24 || C >= 1 << 24) throw new Error(`${V} vertices and ${C} coefficient vectors: more than a float indexes exactly`);
    const width = textureWidth(V), vertices = new Float32Array(V * 4), clusters = new Float32Array(V * 4), weights = new Float32Array(V * 4);
    for (let v = 0; v < V; ++v) {
      const w = model.welded[v];
      vertices.set(positions.subarray(v * 3, v * 3 + 3), v * 4);
      vertices[v * 4 + 3] = model.coefficientOffsets[w];
      for (let j = 0; j < 4; ++j) {
        clusters[v * 4 + j] = model.clusters[w * 4 + j];
        weights[v * 4 + j] = model.weights[w * 4 + j];
      }
    }
    this.textures = [floatTexture(scene, vertices, V, width), floatTexture(scene, clusters, V, width), floatTexture(scene, weights, V, width)];
    const clusterData = new Float32Array(K * 8);
    for (let k = 0; k < K; ++k) {
      clusterData.set(model.centroids.subarray(k * 3, k * 3 + 3), k * 8);
      clusterData[k * 8 + 4] = model.bases[k * 2];
      clusterData[k * 8 + 5] = model.bases[k * 2 + 1];
    }
    this.clusterTexture = floatTexture(scene, clusterData, K * 2, 2);
    const coefficients = new Float32Array(C * 4);
    for (let i = 0; i < C; ++i) coefficients.set(model.coefficients.subarray(i * 3, i * 3 + 3), i * 4);
    this.coefficientTexture = floatTexture(scene, coefficients, C);
    this.parameterCount = K * 3 + Math.ceil(N / 4);
    this.parameters = new Float32Array(textureWidth(this.parameterCount) ** 2 * 4);
    this.parameterTexture = floatTexture(scene, this.parameters, this.parameterCount);
    this.shape = new RenderTargetTexture('segmorph shape', { width, height: Math.ceil(V / width) }, scene, {
      type: Constants.TEXTURETYPE_FLOAT, format: Constants.TEXTUREFORMAT_RGBA, generateMipMaps: false,
      generateDepthBuffer: false, samplingMode: Constants.TEXTURE_NEAREST_SAMPLINGMODE });
    this.renderer = new EffectRenderer(engine);
    this.pass = new EffectWrapper({
      engine, name: 'segmorph shape', fragmentShader: SHAPE_GLSL, uniformNames: ['segmorphCount'],
      samplerNames: ['segmorphVertices', 'segmorphVertexClusters', 'segmorphVertexWeights', 'segmorphParameters',
                     'segmorphClusters', 'segmorphCoefficients'],
    });
    this.pass.onApplyObservable.add(() => {
      const effect = this.pass.effect;
      effect.setTexture('segmorphVertices', this.textures[0]);
      effect.setTexture('segmorphVertexClusters', this.textures[1]);
      effect.setTexture('segmorphVertexWeights', this.textures[2]);
      effect.setTexture('segmorphParameters', this.parameterTexture);
      effect.setTexture('segmorphClusters', this.clusterTexture);
      effect.setTexture('segmorphCoefficients', this.coefficientTexture);
      effect.setInt('segmorphCount', V);
    });
    // One animated influence per frame of the stream, as the morph targets' would be.
    this.targets = Array.from({ length: F }, () => ({ influence: 0 }));
    this.shown = new Float64Array(F).fill(NaN);
    if (normals) {
      const rings = surfaceRings(model, indices, 4), ring = Float32Array.from(rings.ring);
      this.triangleTexture = floatTexture(scene, rings.list, rings.entries);
      for (const mesh of meshes) {
        mesh.setVerticesData('segmorphSurface', rings.surface, false, 3);
        mesh.setVerticesData('segmorphRing', ring, false, 2);
      }
    }
    const b = model.bounds;
    for (const mesh of meshes) {
      mesh.morphTargetManager = null;
      if (mesh.material) mesh.material = this.material(mesh.material);
      mesh.setBoundingInfo(new BoundingInfo(new Vector3(b[0], b[1], b[2]), new Vector3(b[3], b[4], b[5])));
      mesh.getBoundingInfo().isLocked = true;  // the model's box (every frame), which follows the node's world matrix
      mesh.metadata = { ...mesh.metadata, segmorph: { mode: 'gpu', version: model.version, player: this } };
    }
    this._observer = scene.onBeforeRenderObservable.add(() => this.update());
    this._sceneObserver = scene.onDisposeObservable.addOnce(() => this.dispose());
    meshes[0].onDisposeObservable.addOnce(() => this.dispose());
  }

  // A clone of `material` that draws this player's shape and casts its shadow: each mesh's material gets one at the
  // load; a material given to a mesh later needs one too (mesh.material = player.material(new StandardMaterial(...))).
  material(material) {
    const copy = material.clone(`${material.name} (segmorph)`);
    copy.segmorph = new SegmorphPlugin(copy, this, this.normals);
    copy.shadowDepthWrapper = new ShadowDepthWrapper(copy, this.meshes[0].getScene());
    return copy;
  }

  // Resolves once the pass's shader is compiled; the first shape is then evaluated.
  async ready() {
    const started = performance.now();
    while (!this.pass.isReady()) {
      const error = this.pass.effect?.getCompilationError?.();
      if (error) throw new Error(`the GPU playback shader does not compile: ${error}`);
      if (performance.now() - started > 60000) throw new Error('the GPU playback shader did not compile in 60 s');
      await new Promise((resolve) => setTimeout(resolve, 10));
    }
    this.update();
  }

  // The parameters at `influences` (one weight per frame), into `out` (blendParameters).
  blend(influences, out) {
    return blendParameters(this.model, influences, out);
  }

  // When the influences changed: the parameters blended and uploaded, the shape evaluated.
  update() {
    if (!this.pass.isReady()) return;
    let changed = false;
    for (let f = 0; f < this.targets.length; ++f) {
      const w = this.targets[f].influence;
      if (this.shown[f] !== w) changed = true, this.shown[f] = w;
    }
    if (!changed) return;
    this.blend(this.shown, this.parameters);
    this.parameterTexture.update(this.parameters);
    this.renderer.render(this.pass, this.shape);
  }

  // Frees what the player holds: its observers, the pass, and its textures where it owns them. Once.
  dispose() {
    if (this.disposed) return;
    this.disposed = true;
    const scene = this.meshes[0]?.getScene();
    scene?.onBeforeRenderObservable.remove(this._observer);
    scene?.onDisposeObservable.remove(this._sceneObserver);
    if (this.ownsTextures)
      for (const texture of [...this.textures, this.clusterTexture, this.coefficientTexture, this.parameterTexture, this.shape,
                             this.triangleTexture]) texture?.dispose();
    this.pass.dispose();
    this.renderer.dispose();
  }
}

// Why `scene`'s engine cannot play `model` on the GPU (null: it can): GPU playback needs WebGL 2 (GLSL ES 3.0:
// texelFetch, gl_VertexID), float render targets, textures wide enough, and indices that floats hold exactly.
function gpuUnplayable(scene, model, indices) {
  const engine = scene.getEngine(), caps = engine.getCaps();
  if (engine.isWebGPU || !(engine.webGLVersion >= 2)) return 'GPU playback needs WebGL 2';
  if (!caps.textureFloatRender) return 'GPU playback needs float render targets';
  const widest = Math.max(model.vertexCount, model.coefficientCount, indices.length, model.clusterCount * 3);
  if (Math.ceil(Math.sqrt(widest)) * 2 > caps.maxTextureSize || model.clusterCount > caps.maxTextureSize)
    return `its textures would be wider than ${caps.maxTextureSize} texels`;
  if (indices.length >= 1 << 24) return 'more triangle corners than a float indexes exactly';
  return null;
}

// Keys of the influence of frame f of a clip whose frames are at `times`: 1 at its time, 0 at its neighbours' and
// at the clip's ends (held between them), in frames at `fps`.
// A vertex buffer's data (Babylon's FloatArray, or null) as a Float32Array, as the decoder takes it.
function floatsOf(data) {
  if (!data) return null;
  return data instanceof Float32Array ? data : Float32Array.from(data);
}

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
