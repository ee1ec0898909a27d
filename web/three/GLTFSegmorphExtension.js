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
// - a primitive that plays clips: its stream is decoded against the Draco base mesh; every frame of every clip
//   becomes an absolute morph target (geometry.morphTargetsRelative = false), the geometry's POSITION becomes frame 0
//   of clip 0 (what the primitive shows when no clip plays), and each clip's AnimationClip (the glTF animation the
//   clip names, with its name and times) gets a morphTargetInfluences track that is 1 on the frame's target at the
//   frame's time (LINEAR or STEP as the clip says). With { streaming: true } it keeps the stream instead and decodes
//   the shown frame into POSITION (see StreamingPlayback below). Normals turn with the surface unless
//   { normals: false };
// - a primitive that keeps its morph targets: the targets' POSITION (and NORMAL) displacements are filled in; the
//   node's weights animation plays them as usual;
// - an animation with coded tracks: its samplers' times and values are decoded and given to GLTFLoader as the data
//   of their accessors, so they become ordinary KeyframeTracks;
// - placeholder channels play a constant; they stay.
// A damaged or mismatched stream makes the load fail with an Error that names the mesh, primitive or animation.
import { BufferAttribute, InterpolateDiscrete, InterpolateLinear, NumberKeyframeTrack } from 'three';

import { SegmorphDecoder } from '../segmorph_decoder.js';

const NAME = 'SEGMORPH_animation_compression';
const PATHS = { translation: 0, rotation: 1, scale: 2 };

export class GLTFSegmorphExtension {
  // options: normals (default true): turn the normals with the surface in every frame or target; streaming (default
  // false): decode the shown frame of a clip primitive on demand instead of making every frame a morph target.
  constructor(parser, options = {}) {
    this.name = NAME;
    this.parser = parser;
    this.options = { normals: true, streaming: false, ...options };
    this.views = new Map();  // synthetic bufferView index → the decoded bytes (coded tracks)
    this.decodeMilliseconds = 0;  // time spent in the decoder (for viewers and benchmarks)
  }

  // `decode()`'s result, its time added to decodeMilliseconds, its errors prefixed with `what`.
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
    const decoded = await this._timed(what, () => SegmorphDecoder.decodeTargetsAsync(stream, positions, indices));
    const targets = geometry.morphAttributes.position ?? [];
    if (decoded.targetCount !== targets.length)
      throw new Error(`${what}: the stream holds ${decoded.targetCount} targets, the primitive has ${targets.length}`);
    const floats = positions.length;
    const normals = this.options.normals && geometry.morphAttributes.normal && geometry.getAttribute('normal') &&
                    new SurfaceNormals(positions, indices, geometry.getAttribute('normal').array);
    for (let t = 0; t < targets.length; ++t) {
      const deltas = decoded.deltas.slice(t * floats, (t + 1) * floats);
      geometry.morphAttributes.position[t] = new BufferAttribute(deltas, 3);
      if (!normals) continue;
      const shape = new Float32Array(floats);
      for (let i = 0; i < floats; ++i) shape[i] = positions[i] + deltas[i];
      const turned = normals.turned(shape), base = geometry.getAttribute('normal').array;
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
    if (this.options.streaming) return this._streaming(meshes, extension, animations, stream, positions, indices, times, what);
    const decoded = await this._timed(what, () => SegmorphDecoder.decodeStreamAsync(stream, positions, indices));
    checkClips(decoded.clips.map((c) => c.frameCount), extension, times, what);
    // Every frame an absolute target: at weight 1 on one target the position is that frame exactly.
    const floats = positions.length, targets = [], normalTargets = [];
    const normal = geometry.getAttribute('normal');
    const normals = this.options.normals && normal && new SurfaceNormals(positions, indices, normal.array);
    for (const clip of decoded.clips)
      for (let f = 0; f < clip.frameCount; ++f) {
        const frame = clip.frames.subarray(f * floats, (f + 1) * floats);
        targets.push(new BufferAttribute(frame, 3));
        if (normals) normalTargets.push(new BufferAttribute(normals.turned(frame), 3));
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
    checkClips(player.frameCounts, extension, times, what);
    extension.clips.forEach((clip, c) => {
      for (const mesh of meshes) for (const track of player.tracks(mesh, c)) addTrack(animations, clip.animation, track, what);
    });
  }
}

// The layout of an animation's track stream (spec/README.md, "Coded tracks"): the distinct input accessors of its coded
// samplers in first-named order, and per sampler its time array, path and component count.
function trackLayout(json, animation, coded, what) {
  const timeAccessors = [], samplers = [];
  for (const s of coded.samplers) {
    const sampler = animation.samplers[s];
    if (!sampler) throw new Error(`${what}: coded sampler ${s} does not exist`);
    const paths = new Set(animation.channels.filter((c) => c.sampler === s).map((c) => c.target.path));
    const path = paths.size === 1 ? PATHS[[...paths][0]] : undefined;
    if (path === undefined) throw new Error(`${what}: coded sampler ${s} must move translations, rotations or scales alone`);
    const input = json.accessors[sampler.input], output = json.accessors[sampler.output];
    const components = path === 1 ? 4 : 3;
    if (!input || !output || input.bufferView !== undefined || output.bufferView !== undefined ||
        output.count !== input.count || output.type !== (components === 4 ? 'VEC4' : 'VEC3'))
      throw new Error(`${what}: coded sampler ${s} needs FLOAT accessors without data that agree with its path`);
    let times = timeAccessors.indexOf(sampler.input);
    if (times < 0) times = timeAccessors.push(sampler.input) - 1;
    samplers.push({ times, path, components });
  }
  return { timeAccessors, samplers };
}

function checkClips(frameCounts, extension, times, what) {
  if (frameCounts.length !== extension.clips.length)
    throw new Error(`${what}: the stream has ${frameCounts.length} clips, the extension names ${extension.clips.length}`);
  frameCounts.forEach((count, c) => {
    if (times[c].count !== count)
      throw new Error(`${what}: clip ${c} has ${count} frames in the stream and ${times[c].count} times`);
  });
}

function addTrack(animations, index, track, what) {
  const clip = animations[index];
  if (!clip) throw new Error(`${what}: a clip names animation ${index}, which does not exist`);
  clip.tracks.push(track);
  clip.resetDuration();
}

// Normals that turn with the surface (spec/README.md, "Normals and tangents", as segmorph decode does): each vertex's
// normal in the base mesh is turned by the smallest rotation taking the area-weighted normal of the surface around it
// in the base to the one in the frame; vertices at the same base position (seams) share that surface.
class SurfaceNormals {
  constructor(positions, indices, normals) {
    const count = positions.length / 3, keys = new Map();
    this.point = new Uint32Array(count);  // the surface point (welded vertex) of each vertex
    for (let v = 0; v < count; ++v) {
      const key = `${positions[v * 3]},${positions[v * 3 + 1]},${positions[v * 3 + 2]}`;
      if (!keys.has(key)) keys.set(key, keys.size);
      this.point[v] = keys.get(key);
    }
    this.points = keys.size;
    this.indices = indices;
    this.normals = normals;
    this.base = this._surface(positions);
  }

  _surface(positions) {
    const sum = new Float64Array(this.points * 3), index = this.indices;
    for (let t = 0; t + 2 < index.length; t += 3) {
      const a = index[t] * 3, b = index[t + 1] * 3, c = index[t + 2] * 3;
      const ux = positions[b] - positions[a], uy = positions[b + 1] - positions[a + 1], uz = positions[b + 2] - positions[a + 2];
      const vx = positions[c] - positions[a], vy = positions[c + 1] - positions[a + 1], vz = positions[c + 2] - positions[a + 2];
      const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;  // twice the area, outward
      for (const corner of [index[t], index[t + 1], index[t + 2]]) {
        const p = this.point[corner] * 3;
        sum[p] += nx, sum[p + 1] += ny, sum[p + 2] += nz;
      }
    }
    for (let p = 0; p < sum.length; p += 3) {
      const length = Math.hypot(sum[p], sum[p + 1], sum[p + 2]);
      if (length > 0) sum[p] /= length, sum[p + 1] /= length, sum[p + 2] /= length;
    }
    return sum;
  }

  // The base normals turned to `frame` (V × 3 positions): a new Float32Array.
  turned(frame) {
    const now = this._surface(frame), out = new Float32Array(this.normals.length);
    for (let v = 0; v < this.point.length; ++v) {
      const p = this.point[v] * 3;
      const ax = this.base[p], ay = this.base[p + 1], az = this.base[p + 2];
      const bx = now[p], by = now[p + 1], bz = now[p + 2];
      let nx = this.normals[v * 3], ny = this.normals[v * 3 + 1], nz = this.normals[v * 3 + 2];
      // Rodrigues: the rotation taking a to b, about a × b by the angle between them.
      const cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx, cos = ax * bx + ay * by + az * bz;
      if (cos > -0.999999) {
        const k = 1 / (1 + cos), dot = cx * nx + cy * ny + cz * nz;
        const wx = cy * nz - cz * ny, wy = cz * nx - cx * nz, wz = cx * ny - cy * nx;
        nx = nx * cos + wx + cx * dot * k, ny = ny * cos + wy + cy * dot * k, nz = nz * cos + wz + cz * dot * k;
      }
      out[v * 3] = nx, out[v * 3 + 1] = ny, out[v * 3 + 2] = nz;
    }
    return out;
  }
}

// Streaming playback of a clip primitive: the stream stays compressed in the decoder's memory and only the shown frame
// is decoded, into the geometry's POSITION (and NORMAL). Each clip's AnimationClip drives two numbers on the mesh:
// segmorphClip (the clip, held) and segmorphFrame (the frame position in it, interpolated between frames for LINEAR);
// onBeforeRender decodes the frames around it (seeking when it moved backwards or to another clip) and writes the
// interpolated positions. Memory: the stream and three frames of V × 3 floats, whatever the frame count. One clip
// plays at a time (no cross-fades: the numbers would blend).
export class StreamingPlayback {
  constructor(stream, positions, indices, extension, times, meshes, normals) {
    this.decoder = SegmorphDecoder.createStreamDecoder(stream, positions, indices);
    this.frameCounts = Array.from({ length: this.decoder.clipCount }, (_, c) => this.decoder.frameCount(c));
    this.extension = extension;
    this.times = times;
    this.frames = [new Float32Array(positions.length), new Float32Array(positions.length)];
    this.clip = -1;
    this.decoded = -1;  // the last frame of this.clip decoded (frames[1]); frames[0] holds the one before it
    const geometry = meshes[0].geometry, normal = geometry.getAttribute('normal');
    this.geometry = geometry;
    this.normals = normals && normal && new SurfaceNormals(positions, indices, normal.array);
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
      this.geometry.getAttribute('normal').array.set(this.normals.turned(out));
      this.geometry.getAttribute('normal').needsUpdate = true;
    }
  }
}
