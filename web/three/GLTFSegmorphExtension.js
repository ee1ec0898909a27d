// A three.js GLTFLoader plugin for SEGMORPH_animation_compression (spec/README.md): with it, GLTFLoader plays a file
// written by `segmorph encode` as it plays the `segmorph decode` output.
//
//   import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
//   import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
//   import { GLTFSegmorphExtension } from 'segmorph/three';
//   const loader = new GLTFLoader();
//   loader.setDRACOLoader(new DRACOLoader().setDecoderPath('/draco/'));
//   loader.register((parser) => new GLTFSegmorphExtension(parser));
//
// What it does with each part of the extension (docs/web.md):
// - a primitive that plays clips, with { playback: 'gpu' } (the default) and a version-4 stream: the stream's model
//   (docs/runtime.md, "Playing the model") is uploaded once and the mesh's material evaluates it in the vertex shader
//   (see GpuPlayback below); the AnimationClips drive morphTargetInfluences over the frames as with morph targets;
// - a primitive that plays clips with { playback: 'morph' } (or a version 1-3 stream under 'gpu'): its stream is
//   decoded against the Draco base mesh; every frame of every clip becomes an absolute morph target (geometry.morphTargetsRelative = false), the geometry's POSITION becomes frame 0
//   of clip 0 (what the primitive shows when no clip plays), and each clip's AnimationClip (the glTF animation the
//   clip names, with its name and times) gets a morphTargetInfluences track that is 1 on the frame's target at the
//   frame's time (LINEAR or STEP as the clip says). With { playback: 'stream' } it keeps the stream instead and
//   decodes the shown frame into POSITION (see StreamingPlayback below). Normals turn with the surface unless
//   { normals: false };
// - a primitive that keeps its morph targets: the targets' POSITION (and NORMAL) displacements are filled in; the
//   node's weights animation plays them as usual;
// - an animation with coded tracks: its samplers' times and values are decoded and given to GLTFLoader as the data
//   of their accessors, so they become ordinary KeyframeTracks;
// - placeholder channels play a constant; they stay.
// A damaged or mismatched stream makes the load fail with an Error that names the mesh, primitive or animation.
import {
  Box3, BufferAttribute, BufferGeometry, Camera, DataTexture, FloatType, GLSL3, IntType, InterpolateDiscrete,
  InterpolateLinear, MeshDepthMaterial, MeshDistanceMaterial, NearestFilter, NumberKeyframeTrack, Points, RGBAFormat,
  RGBFormat, Scene, ShaderMaterial, Sphere, Vector3, WebGLRenderTarget,
} from 'three';

import { NAME, checkClips, trackLayout } from '../gltf_extension.js';
import { SegmorphDecoder } from '../segmorph_decoder.js';
import { MODEL_GLSL, TEXEL_GLSL, TURN_GLSL, blendParameters, surfaceRings, textureWidth } from '../model_playback.js';


export class GLTFSegmorphExtension {
  // options: playback (default 'gpu'): how a clip primitive plays: 'gpu' evaluates a version-4 stream's model in the
  // vertex shader (other versions play as 'morph'), 'morph' makes every frame a morph target, 'stream' decodes the
  // shown frame on demand ({ streaming: true } is the same as 'stream'); normals (default true): turn the normals with
  // the surface in every frame or target.
  constructor(parser, options = {}) {
    this.name = NAME;
    this.parser = parser;
    this.options = { normals: true, playback: options.streaming ? 'stream' : 'gpu', ...options };
    if (!['gpu', 'morph', 'stream'].includes(this.options.playback))
      throw new Error(`${NAME}: playback must be 'gpu', 'morph' or 'stream', not '${this.options.playback}'`);
    this.playbacks = [];  // per clip primitive: { what, mode: 'gpu' | 'morph' | 'stream', version }
    this.views = new Map();  // synthetic bufferView index → the decoded bytes (coded tracks)
    this.decodeMilliseconds = 0;  // time spent in the decoder (for viewers and benchmarks)
  }

  // `decode()`'s result, its time added to decodeMilliseconds, its errors prefixed with `what`.
  async _timed(what, decode) {
    const started = performance.now();
    try {
      return await decode();
    } catch (error) {
      throw Object.assign(new Error(`${what}: ${error.message}`), { unsupported: error.unsupported === true });
    } finally {
      this.decodeMilliseconds += performance.now() - started;
    }
  }

  // Coded tracks, before GLTFLoader reads any animation: each coded sampler's accessors get a bufferView of their own
  // that loadBufferView() serves from the decoded stream.
  async beforeRoot() {
    const json = this.parser.json;
    if (!(json.extensionsUsed ?? []).includes(NAME)) return;
    await SegmorphDecoder.ready;
    const animations = json.animations ?? [];
    for (let a = 0; a < animations.length; ++a) {
      const coded = animations[a].extensions?.[NAME];
      if (!coded) continue;
      const what = `${NAME}: animation ${a}`;
      const { timeAccessors, samplers } = trackLayout(json, animations[a], coded, what);
      const stream = new Uint8Array(await this.parser.getDependency('bufferView', coded.bufferView));
      const counts = timeAccessors.map((i) => json.accessors[i].count);
      const decoded = await this._timed(what, () => SegmorphDecoder.decodeTracks(stream, counts, samplers));
      timeAccessors.forEach((accessor, i) => this._serve(json, accessor, decoded.times[i]));
      coded.samplers.forEach((s, i) => this._serve(json, animations[a].samplers[s].output, decoded.values[i]));
    }
  }

  _serve(json, accessor, floats) {
    json.bufferViews.push({ buffer: 0, byteLength: floats.byteLength, extras: { segmorph: 'decoded' } });
    const view = json.bufferViews.length - 1;
    json.accessors[accessor].bufferView = view;
    json.accessors[accessor].byteOffset = 0;
    this.views.set(view, floats.slice().buffer);
  }

  loadBufferView(index) {
    const bytes = this.views.get(index);
    return bytes ? Promise.resolve(bytes) : null;
  }

  // Compressed primitives, once GLTFLoader has built the meshes (their Draco base meshes decoded) and the clips.
  async afterRoot(result) {
    const json = this.parser.json;
    if (!(json.extensionsUsed ?? []).includes(NAME)) return;
    await SegmorphDecoder.ready;
    const objects = new Map();  // "mesh/primitive" → the three.js meshes GLTFLoader made of it
    for (const scene of result.scenes)
      scene.traverse((object) => {
        const association = this.parser.associations.get(object);
        if (!object.isMesh || association?.primitives === undefined) return;
        const key = `${association.meshes}/${association.primitives}`;
        if (!objects.has(key)) objects.set(key, []);
        objects.get(key).push(object);
      });
    const work = [];
    (json.meshes ?? []).forEach((mesh, m) =>
      mesh.primitives.forEach((primitive, p) => {
        const extension = primitive.extensions?.[NAME];
        const meshes = objects.get(`${m}/${p}`) ?? [];
        if (!extension || meshes.length === 0) return;
        const what = `${NAME}: mesh ${m} primitive ${p}`;
        work.push(extension.morphTargets
          ? this._keptTargets(meshes, extension, what)
          : this._clips(meshes, extension, result.animations, what));
      }));
    await Promise.all(work);
  }

  async _inputs(geometry, extension, what) {
    const position = geometry.getAttribute('position');
    if (!position || !(position.array instanceof Float32Array) || position.itemSize !== 3 || position.isInterleavedBufferAttribute)
      throw new Error(`${what}: its base mesh has no float POSITION`);
    if (!geometry.index) throw new Error(`${what}: its base mesh has no triangles`);
    const stream = new Uint8Array(await this.parser.getDependency('bufferView', extension.bufferView));
    return { stream, positions: position.array, indices: geometry.index.array };
  }

  async _keptTargets(meshes, extension, what) {
    const geometry = meshes[0].geometry;
    const { stream, positions, indices } = await this._inputs(geometry, extension, what);
    const base = this.options.normals && geometry.morphAttributes.normal && geometry.getAttribute('normal')?.array;
    const decoded = await this._timed(what, () =>
      SegmorphDecoder.decodeTargetsAsync(stream, positions, indices, base || undefined));
    const targets = geometry.morphAttributes.position ?? [];
    if (decoded.targetCount !== targets.length)
      throw new Error(`${what}: the stream holds ${decoded.targetCount} targets, the primitive has ${targets.length}`);
    const floats = positions.length;
    for (let t = 0; t < targets.length; ++t) {
      geometry.morphAttributes.position[t] = new BufferAttribute(decoded.deltas.slice(t * floats, (t + 1) * floats), 3);
      if (!decoded.normals) continue;
      // Relative, as segmorph decode writes them: the turned normal minus the base's.
      const turned = decoded.normals.slice(t * floats, (t + 1) * floats);
      for (let i = 0; i < floats; ++i) turned[i] -= base[i];
      geometry.morphAttributes.normal[t] = new BufferAttribute(turned, 3);
    }
    geometry.computeBoundingBox();
    geometry.computeBoundingSphere();
  }

  async _clips(meshes, extension, animations, what) {
    const geometry = meshes[0].geometry;
    const { stream, positions, indices } = await this._inputs(geometry, extension, what);
    const times = await Promise.all(extension.clips.map((clip) => this.parser.getDependency('accessor', clip.times)));
    if (this.options.playback === 'stream') {
      this.playbacks.push({ what, mode: 'stream' });
      return this._streaming(meshes, extension, animations, stream, positions, indices, times, what);
    }
    if (this.options.playback === 'gpu') {
      let model = null;
      try {
        model = await this._timed(what, () => SegmorphDecoder.decodeModelAsync(stream, positions, indices));
      } catch (error) {
        if (!error.unsupported) throw error;  // damaged: reject; versions 1-3: morph targets below
      }
      if (model) {
        checkClips(model.clipFrames, extension, times.map((t) => t.count), what);
        this.playbacks.push({ what, mode: 'gpu', version: model.version });
        const player = new GpuPlayback(model, geometry, meshes, this.options.normals);
        extension.clips.forEach((clip, c) => {
          for (const mesh of meshes) addTrack(animations, clip.animation, player.track(mesh, c, times[c].array, clip.interpolation), what);
        });
        return;
      }
    }
    const normal = geometry.getAttribute('normal');
    const normals = Boolean(this.options.normals && normal);
    const decoded = await this._timed(what, () =>
      SegmorphDecoder.decodeStreamAsync(stream, positions, indices, normals ? normal.array : undefined));
    checkClips(decoded.clips.map((c) => c.frameCount), extension, times.map((t) => t.count), what);
    this.playbacks.push({ what, mode: 'morph', version: decoded.version });
    // Every frame an absolute target: at weight 1 on one target the position is that frame exactly.
    const floats = positions.length, targets = [], normalTargets = [];
    for (const clip of decoded.clips)
      for (let f = 0; f < clip.frameCount; ++f) {
        targets.push(new BufferAttribute(clip.frames.subarray(f * floats, (f + 1) * floats), 3));
        if (normals) normalTargets.push(new BufferAttribute(clip.normals.subarray(f * floats, (f + 1) * floats), 3));
      }
    geometry.setAttribute('position', new BufferAttribute(decoded.clips[0].frames.slice(0, floats), 3));
    if (normals) geometry.setAttribute('normal', normalTargets[0].clone());
    geometry.morphAttributes = normals ? { position: targets, normal: normalTargets } : { position: targets };
    geometry.morphTargetsRelative = false;
    geometry.computeBoundingBox();
    geometry.computeBoundingSphere();
    for (const mesh of meshes) mesh.updateMorphTargets();

    // Each clip: its animation's AnimationClip gets one-hot weights on this mesh's targets at the clip's times.
    let first = 0;
    extension.clips.forEach((clip, c) => {
      const count = decoded.clips[c].frameCount, keys = times[c].array;
      const values = new Float32Array(count * targets.length);
      for (let f = 0; f < count; ++f) values[f * targets.length + first + f] = 1;
      for (const mesh of meshes) {
        const track = new NumberKeyframeTrack(`${mesh.uuid}.morphTargetInfluences`, Array.from(keys), values,
                                              clip.interpolation === 'STEP' ? InterpolateDiscrete : InterpolateLinear);
        addTrack(animations, clip.animation, track, what);
      }
      first += count;
    });
  }

  async _streaming(meshes, extension, animations, stream, positions, indices, times, what) {
    const player = await this._timed(what, () =>
      new StreamingPlayback(stream, positions, indices, extension, times, meshes, this.options.normals));
    checkClips(player.frameCounts, extension, times.map((t) => t.count), what);
    extension.clips.forEach((clip, c) => {
      for (const mesh of meshes) for (const track of player.tracks(mesh, c)) addTrack(animations, clip.animation, track, what);
    });
  }
}

function addTrack(animations, index, track, what) {
  const clip = animations[index];
  if (!clip) throw new Error(`${what}: a clip names animation ${index}, which does not exist`);
  clip.tracks.push(track);
  clip.resetDuration();
}

// Streaming playback of a clip primitive: the stream stays compressed in the decoder's memory and only the shown frame
// is decoded, into the geometry's POSITION (and NORMAL). Each clip's AnimationClip drives two numbers on the mesh:
// segmorphClip (the clip, held) and segmorphFrame (the frame position in it, interpolated between frames for LINEAR);
// onBeforeRender decodes the frames around it (seeking when it moved backwards or to another clip) and writes the
// interpolated positions. Memory: the stream and three frames of V × 3 floats, whatever the frame count. One clip
// plays at a time (no cross-fades: the numbers would blend).
export class StreamingPlayback {
  constructor(stream, positions, indices, extension, times, meshes, normals) {
    const normal = meshes[0].geometry.getAttribute('normal');
    this.normals = Boolean(normals && normal);
    this.decoder = SegmorphDecoder.createStreamDecoder(stream, positions, indices, this.normals ? normal.array : undefined);
    this.frameCounts = Array.from({ length: this.decoder.clipCount }, (_, c) => this.decoder.frameCount(c));
    this.extension = extension;
    this.times = times;
    this.frames = [new Float32Array(positions.length), new Float32Array(positions.length)];
    this.clip = -1;
    this.decoded = -1;  // the last frame of this.clip decoded (frames[1]); frames[0] holds the one before it
    const geometry = meshes[0].geometry;
    this.geometry = geometry;
    geometry.setAttribute('position', new BufferAttribute(new Float32Array(positions.length), 3));
    if (this.normals) geometry.setAttribute('normal', new BufferAttribute(new Float32Array(positions.length), 3));
    this.shown = null;
    this.show(0, 0);  // frame 0 of clip 0 until a clip plays
    for (const mesh of meshes) {
      mesh.segmorphClip = 0;
      mesh.segmorphFrame = 0;
      mesh.frustumCulled = false;  // the bounds are the first frame's, not every frame's
      const previous = mesh.onBeforeRender;
      mesh.onBeforeRender = (...args) => {
        this.show(mesh.segmorphClip, mesh.segmorphFrame);
        previous.apply(mesh, args);
      };
    }
  }

  // The tracks that play clip c on `mesh`.
  tracks(mesh, c) {
    const keys = Array.from(this.times[c].array);
    const step = this.extension.clips[c].interpolation === 'STEP';
    return [new NumberKeyframeTrack(`${mesh.uuid}.segmorphClip`, [keys[0]], [c], InterpolateDiscrete),
            new NumberKeyframeTrack(`${mesh.uuid}.segmorphFrame`, keys, keys.map((_, f) => f),
                                    step ? InterpolateDiscrete : InterpolateLinear)];
  }

  // The frames around frame position `frame` of `clip`: [frame j, frame j + 1] (the same frame twice at the end).
  _around(clip, frame) {
    const last = this.frameCounts[clip] - 1, j = Math.min(Math.max(Math.floor(frame), 0), last);
    const target = Math.min(j + 1, last);
    if (clip !== this.clip || this.decoded > target) {
      this.decoder.seek(clip);
      this.clip = clip;
      this.decoded = -1;
    }
    while (this.decoded < target) {
      this.frames.reverse();
      this.decoder.decodeFrame(this.frames[1]);
      this.decoded += 1;
    }
    return { j, pair: target === j ? [this.frames[1], this.frames[1]] : [this.frames[0], this.frames[1]] };
  }

  // Shows frame position `frame` of `clip` (clip and frame as the mixer left them on the mesh).
  show(clip, frame) {
    const key = `${clip}:${frame}`;
    if (key === this.shown) return;
    this.shown = key;
    const c = Math.min(Math.max(Math.round(clip), 0), this.frameCounts.length - 1);
    const { j, pair: [a, b] } = this._around(c, frame);
    const u = Math.min(Math.max(frame - j, 0), 1);
    const position = this.geometry.getAttribute('position'), out = position.array;
    if (u === 0 || a === b) out.set(a);
    else for (let i = 0; i < out.length; ++i) out[i] = a[i] + u * (b[i] - a[i]);
    position.needsUpdate = true;
    if (this.normals) {
      this.decoder.turnNormals(out, this.geometry.getAttribute('normal').array);
      this.geometry.getAttribute('normal').needsUpdate = true;
    }
  }
}

// The vertex shader's evaluation of a version-4 model (docs/runtime.md, "Playing the model"): MODEL_GLSL's
// segmorphEvaluate (the arithmetic of the C API's segmorph_decoder_model_evaluate, in its order) on attributes. segmorphParameters holds the shown parameters (cluster k's
// [A | t] rows at texels 3k, 3k + 1, 3k + 2, then the basis values, 4 per texel, from texel 3K); segmorphClusters
// row k its centroid and (first basis value, m_k); segmorphCoefficients the coefficient vectors. Per vertex:
// segmorphCluster and segmorphWeight its (cluster, weight) pairs, the own cluster first, and segmorphCoefficient the
// texel of its first coefficient vector. segmorphPosition(x) is the position at base position x.
export const SEGMORPH_MODEL_GLSL = /* glsl */`
uniform highp sampler2D segmorphParameters;
uniform highp sampler2D segmorphClusters;
uniform highp sampler2D segmorphCoefficients;
in uvec4 segmorphCluster;
in vec4 segmorphWeight;
in uint segmorphCoefficient;

${TEXEL_GLSL}${MODEL_GLSL}
vec3 segmorphPosition( vec3 x ) {
	return segmorphEvaluate( x, ivec4( segmorphCluster ), segmorphWeight, int( segmorphCoefficient ) );
}
`;

// Normals that turn with the surface, as segmorph decode and the 'morph' playback turn them (turn_normals): the
// base normal turned by the smallest rotation taking the base surface normal around the vertex's point (segmorphSurface,
// the normalized sum of its triangles' cross products) to today's, summed over the same triangles (segmorphRing: the
// first and the count of its entries in segmorphTriangles, each a triangle's three vertices) from segmorphShape, every
// vertex's position at the shown parameters (a pass of its own before the mesh is drawn).
export const SEGMORPH_NORMAL_GLSL = /* glsl */`
uniform highp sampler2D segmorphShape;
uniform highp sampler2D segmorphTriangles;
in vec3 segmorphSurface;
in uvec2 segmorphRing;
${TURN_GLSL}
vec3 segmorphNormal( vec3 n ) {
	return segmorphTurn( n, segmorphSurface, int( segmorphRing.x ), int( segmorphRing.y ) );
}
`;

// A float texture of `count` texels of `channels` floats from `values` (padded with zeros), read by texelFetch.
function dataTexture(values, count, channels) {
  const width = textureWidth(Math.max(count, 1)), height = Math.max(1, Math.ceil(count / width));
  const data = new Float32Array(width * height * channels);
  data.set(values.subarray(0, Math.min(values.length, data.length)));
  const texture = new DataTexture(data, width, height, channels === 4 ? RGBAFormat : RGBFormat, FloatType);
  if (channels === 3) texture.internalFormat = 'RGB32F';
  texture.minFilter = texture.magFilter = NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}

// GPU playback of a clip primitive (the plugin's default for version-4 streams): the model's per-vertex data become
// attributes of the geometry (per vertex its 4 clusters, 4 weights and first coefficient texel, gathered from its
// welded vertex), its coefficients and clusters two float textures, and each mesh gets a texture of the shown
// parameters (K × 12 floats and the N basis values) and its own clone of its materials, patched to evaluate the model
// (SEGMORPH_MODEL_GLSL), as are its customDepthMaterial and customDistanceMaterial so that shadows follow. POSITION
// and NORMAL stay the base mesh's. The AnimationClips drive mesh.morphTargetInfluences over the frames (one per frame,
// one-hot at the frame times, as with morph targets); before the mesh is drawn (onBeforeRender, onBeforeShadow) the
// parameters are blended by its influences, frame f by weight w_f and frame 0 of clip 0 by 1 − Σ w_f, which is exact
// because positions are linear in the parameters: LINEAR and STEP clips, cross-fades, several actions and seeking
// show what the absolute morph targets would. They are uploaded only when the influences change. With normals, a
// pass before the mesh is drawn (in onBeforeRender) evaluates every vertex into a float texture (segmorphShape) from
// which the material turns the normals with the surface (SEGMORPH_NORMAL_GLSL). The bounds are the model's (every
// frame inside).
export class GpuPlayback {
  constructor(model, geometry, meshes, normals) {
    this.model = model;
    const { vertexCount: V, clusterCount: K, frameCount: F, coefficientCount: C } = model;
    this.frameCounts = model.clipFrames;
    const wide = K > 65535;
    const clusters = wide ? new Uint32Array(V * 4) : new Uint16Array(V * 4), weights = new Float32Array(V * 4);
    const first = new Uint32Array(V);
    for (let v = 0; v < V; ++v) {
      const w = model.welded[v];
      for (let j = 0; j < 4; ++j) {
        clusters[v * 4 + j] = model.clusters[w * 4 + j];
        weights[v * 4 + j] = model.weights[w * 4 + j];
      }
      first[v] = model.coefficientOffsets[w];
    }
    const clusterAttribute = new BufferAttribute(clusters, 4);
    clusterAttribute.gpuType = IntType;  // an integer attribute (uvec4), Uint16 or Uint32
    geometry.setAttribute('segmorphCluster', clusterAttribute);
    geometry.setAttribute('segmorphWeight', new BufferAttribute(weights, 4));
    geometry.setAttribute('segmorphCoefficient', new BufferAttribute(first, 1));  // Uint32: uint
    const clusterData = new Float32Array(K * 8);
    for (let k = 0; k < K; ++k) {
      clusterData.set(model.centroids.subarray(k * 3, k * 3 + 3), k * 8);
      clusterData[k * 8 + 4] = model.bases[k * 2];
      clusterData[k * 8 + 5] = model.bases[k * 2 + 1];
    }
    this.clusterTexture = new DataTexture(clusterData, 2, K, RGBAFormat, FloatType);
    this.clusterTexture.minFilter = this.clusterTexture.magFilter = NearestFilter;
    this.clusterTexture.needsUpdate = true;
    this.coefficientTexture = dataTexture(model.coefficients, C, 3);
    const b = model.bounds;
    geometry.boundingBox = new Box3(new Vector3(b[0], b[1], b[2]), new Vector3(b[3], b[4], b[5]));
    geometry.boundingSphere = geometry.boundingBox.getBoundingSphere(new Sphere());
    // Vertex indices are read from float textures: exact below 2^24.
    this.normals = normals && geometry.getAttribute('normal') !== undefined && V < 1 << 24;
    if (this.normals) {
      const rings = surfaceRings(model, geometry.index.array, 3);
      geometry.setAttribute('segmorphSurface', new BufferAttribute(rings.surface, 3));
      geometry.setAttribute('segmorphRing', new BufferAttribute(rings.ring, 2));  // Uint32: uvec2
      this.triangleTexture = dataTexture(rings.list, rings.entries, 3);
    }
    for (const mesh of meshes) this._attach(mesh, F);
  }

  _attach(mesh, frameCount) {
    const { clusterCount: K, basisCount: N, vertexCount: V } = this.model;
    const parameters = dataTexture(new Float32Array(0), K * 3 + Math.ceil(N / 4), 4);
    const uniforms = {
      segmorphParameters: { value: parameters },
      segmorphClusters: { value: this.clusterTexture },
      segmorphCoefficients: { value: this.coefficientTexture },
    };
    // mesh.segmorph: this player, the mesh's parameter texture and its uniforms (for a ShaderMaterial of its own that
    // evaluates the model, e.g. to read positions back), the influences last uploaded and the parameters' version.
    const state = { player: this, texture: parameters, uniforms, shown: new Float64Array(frameCount).fill(NaN),
                    version: 0, shapeVersion: -1, shape: null };
    mesh.segmorph = state;
    if (this.normals) {
      const width = textureWidth(V), height = Math.ceil(V / width);
      state.shape = new WebGLRenderTarget(width, height, { type: FloatType, format: RGBAFormat, minFilter: NearestFilter,
                                                           magFilter: NearestFilter, depthBuffer: false });
      uniforms.segmorphShape = { value: state.shape.texture };
      uniforms.segmorphTriangles = { value: this.triangleTexture };
      const points = new BufferGeometry();
      for (const name of ['position', 'segmorphCluster', 'segmorphWeight', 'segmorphCoefficient'])
        points.setAttribute(name, mesh.geometry.getAttribute(name));
      const pass = new Points(points, new ShaderMaterial({
        glslVersion: GLSL3,
        uniforms,
        vertexShader: `${SEGMORPH_MODEL_GLSL}
out vec3 segmorphShapePosition;
void main() {
	vec2 pixel = vec2( float( gl_VertexID % ${width} ) + 0.5, float( gl_VertexID / ${width} ) + 0.5 );
	gl_Position = vec4( pixel / vec2( ${width}.0, ${height}.0 ) * 2.0 - 1.0, 0.0, 1.0 );
	gl_PointSize = 1.0;
	segmorphShapePosition = segmorphPosition( position );
}`,
        fragmentShader: `in vec3 segmorphShapePosition;
out vec4 segmorphShapeColour;
void main() { segmorphShapeColour = vec4( segmorphShapePosition, 1.0 ); }`,
        depthTest: false,
        depthWrite: false,
      }));
      pass.frustumCulled = false;
      state.shapePass = { scene: new Scene().add(pass), camera: new Camera() };
    }
    mesh.morphTargetInfluences = new Array(frameCount).fill(0);
    mesh.morphTargetDictionary = {};
    const patch = (material) => patchMaterial(material, uniforms, this.normals);
    mesh.material = Array.isArray(mesh.material) ? mesh.material.map(patch) : patch(mesh.material);
    mesh.customDepthMaterial = patchMaterial(mesh.customDepthMaterial ?? new MeshDepthMaterial(), uniforms, false);
    mesh.customDistanceMaterial = patchMaterial(mesh.customDistanceMaterial ?? new MeshDistanceMaterial(), uniforms, false);
    const beforeShadow = mesh.onBeforeShadow, beforeRender = mesh.onBeforeRender;
    mesh.onBeforeShadow = (...args) => {
      this.update(mesh);
      beforeShadow.apply(mesh, args);
    };
    mesh.onBeforeRender = (renderer, ...rest) => {
      this.update(mesh);
      this.shape(mesh, renderer);
      beforeRender.call(mesh, renderer, ...rest);
    };
    this.update(mesh);
  }

  // The track that plays clip c on `mesh`: one-hot influences on the clip's frames at its times.
  track(mesh, c, keys, interpolation) {
    let first = 0;
    for (let i = 0; i < c; ++i) first += this.frameCounts[i];
    const count = this.frameCounts[c], total = mesh.morphTargetInfluences.length;
    const values = new Float32Array(count * total);
    for (let f = 0; f < count; ++f) values[f * total + first + f] = 1;
    return new NumberKeyframeTrack(`${mesh.uuid}.morphTargetInfluences`, Array.from(keys), values,
                                   interpolation === 'STEP' ? InterpolateDiscrete : InterpolateLinear);
  }

  // The parameters at `influences` (one weight per frame), into `out` (blendParameters).
  blend(influences, out) {
    return blendParameters(this.model, influences, out);
  }

  // Uploads the mesh's parameters when its influences changed since the last draw.
  update(mesh) {
    const state = mesh.segmorph, influences = mesh.morphTargetInfluences;
    let changed = false;
    for (let f = 0; f < influences.length; ++f)
      if (state.shown[f] !== influences[f]) { changed = true; state.shown[f] = influences[f]; }
    if (!changed) return;
    this.blend(influences, state.texture.image.data);
    state.texture.needsUpdate = true;
    state.version += 1;
  }

  // With normals: every vertex's position at the mesh's parameters into its shape texture, when they changed (a
  // render of its own, as three.js's Reflector renders in onBeforeRender).
  shape(mesh, renderer) {
    const state = mesh.segmorph;
    if (!state.shape || state.shapeVersion === state.version) return;
    state.shapeVersion = state.version;
    const target = renderer.getRenderTarget(), face = renderer.getActiveCubeFace(), level = renderer.getActiveMipmapLevel();
    const xr = renderer.xr.enabled, shadows = renderer.shadowMap.autoUpdate;
    renderer.xr.enabled = false;
    renderer.shadowMap.autoUpdate = false;
    renderer.setRenderTarget(state.shape);
    renderer.render(state.shapePass.scene, state.shapePass.camera);
    renderer.setRenderTarget(target, face, level);
    renderer.xr.enabled = xr;
    renderer.shadowMap.autoUpdate = shadows;
  }

  // Frees what this player and `meshes` (its meshes) hold on the GPU beyond their geometry and materials.
  dispose(meshes = []) {
    this.clusterTexture.dispose();
    this.coefficientTexture.dispose();
    this.triangleTexture?.dispose();
    for (const mesh of meshes) {
      mesh.segmorph?.texture.dispose();
      mesh.segmorph?.shape?.dispose();
    }
  }
}

// `material` cloned and patched to evaluate the model with `uniforms` (its program shared by every such material).
function patchMaterial(material, uniforms, normals) {
  const patched = material.clone();
  const previous = material.onBeforeCompile, previousKey = material.customProgramCacheKey;
  patched.onBeforeCompile = (shader, renderer) => {
    previous.call(patched, shader, renderer);
    Object.assign(shader.uniforms, uniforms);
    shader.vertexShader = shader.vertexShader
      .replace('#include <common>', `#include <common>\n${SEGMORPH_MODEL_GLSL}${normals ? SEGMORPH_NORMAL_GLSL : ''}`)
      .replace('#include <begin_vertex>', '#include <begin_vertex>\n\ttransformed = segmorphPosition( transformed );');
    if (normals)
      shader.vertexShader = shader.vertexShader.replace('#include <beginnormal_vertex>', `#include <beginnormal_vertex>
	objectNormal = segmorphNormal( objectNormal );
	#ifdef USE_TANGENT
		objectTangent = segmorphNormal( objectTangent );
	#endif`);
  };
  patched.customProgramCacheKey = () => `segmorph-model:${normals ? 1 : 0}:${previousKey.call(material)}`;
  return patched;
}
