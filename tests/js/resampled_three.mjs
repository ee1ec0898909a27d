#!/usr/bin/env node
// Measures, with three.js alone, how well OTHER plays ORIGINAL's vertex animation: the KG error that
// `segmorph verify ORIGINAL OTHER` reports, computed independently of segmorph's code.
//
//   node resampled_three.mjs ORIGINAL OTHER [--json] [--times keys|fps:N] [--pairing nearest|trajectory]
//                            [--normalize-rotations]
//
// OTHER is any glTF that plays the same clips (e.g. gltfpack's output, which may have resampled every
// track at 30 Hz, renamed or dropped node and mesh names, reordered nodes, welded vertices and quantized
// positions). Both files are loaded with three's GLTFLoader in plain Node (textures stripped, buffers
// packed into one in-memory GLB; EXT_meshopt_compression is decoded by three's MeshoptDecoder).
//
// For every clip of ORIGINAL and every mesh node that clip deforms (a skinned node one of whose joints,
// or a joint's ancestor, has a TRS track in the clip; a morphed node with a weights track in the clip),
// and every primitive of that node:
//   times   --times keys (default): the union of the key times of the clip's tracks that move the node,
//           or, when there are more than 60 keys per second over their span, a 30 fps grid from the first
//           key to the last (the last key added when it is not on the grid), as verify samples;
//           --times fps:N: an N fps grid over the same span (verify --fps N).
//   posing  each scene by its own AnimationMixer playing the clip of the same name (else the same index),
//           LoopOnce + clampWhenFinished, a fresh mixer per pose from the rest state.
//   vertex  Mesh/SkinnedMesh.getVertexPosition (morph, then skin), then matrixWorld: world space.
//   pairing OTHER's primitive and vertex for each ORIGINAL vertex: nearest in world space at the node's
//           first frame of its first clip (a uniform grid over every vertex of every OTHER mesh), ties within
//           1e-3 of the primitive's diagonal broken by the distance summed over 5 frames of that clip. The
//           OTHER primitive is the one that receives most of the vertices (restricted to the OTHER node of
//           the same name when there is exactly one); the vertices are then paired within it alone.
//           --pairing trajectory keeps that primitive but pairs each vertex with the one of its vertices
//           nearest over every sampled frame (sum of squared distances), as verify does: an optimistic
//           pairing (it may pick a neighbour that the error brought nearer), for telling pairing apart
//           from sampling when the two disagree.
//   KG      100 * ||A - Ã||_F / ||A - E(A)||_F over the frames of every clip of the primitive, E(A) each
//           frame's centroid, in two spaces:
//             kg_percent:       verify's space: skinned primitives in world (model) space, morph-only
//                               primitives in mesh space carried by the node's REST world matrix (the node's
//                               own animated motion is not part of the measure), as verify does;
//             kg_percent_world: what is seen: world space for every primitive (includes, for a morphed
//                               mesh under animated joints, the error of its rigid motion).
//
// --normalize-rotations normalizes the rotation keys and node rotations of both files first: three
// uses them as stored, and a quaternion that is not of unit length (a quantized one, as gltfpack
// writes) makes a slightly scaled bone matrix; verify normalizes them.
//
// Prints a table per primitive and the worst; --json prints one JSON object instead (per primitive
// also per clip, the pairing and its distances, and timings).
//
// Exit status: 0 when every animated primitive of ORIGINAL was measured, 1 when one could not be (no
// counterpart clip or primitive) or ORIGINAL has nothing deforming, 2 on usage or load errors.

import * as THREE from 'three';
import { loadGltf, normalizeRotations, owningNode, primitiveObjects } from './three_scene.mjs';

const USAGE = 'usage: node resampled_three.mjs ORIGINAL OTHER [--json] [--times keys|fps:N] [--pairing nearest|trajectory] [--normalize-rotations]';
const MAX_KEY_RATE = 60; // keys per second above which verify samples a grid
const DEFAULT_FPS = 30; // that grid
const TIE_SLACK = 1e-3; // of the primitive's diagonal: OTHER vertices this close to the nearest are candidates
const CHECK_FRAMES = 5; // frames of the pairing clip that break ties
const PAIRING_WARNING = 0.01; // of the primitive's diagonal: a first-frame pair this far apart is reported

class UsageError extends Error {}

// ---------------------------------------------------------------- arguments

function parseArgs(argv) {
  const opts = { json: false, fps: 0, pairing: 'nearest', normalizeRotations: false, files: [] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--json') opts.json = true;
    else if (a === '--normalize-rotations') opts.normalizeRotations = true;
    else if (a === '--times') {
      if (i + 1 >= argv.length) throw new UsageError('--times needs a value');
      const v = argv[++i];
      const m = /^fps:([0-9.]+)$/.exec(v);
      if (v === 'keys') opts.fps = 0;
      else if (m && Number(m[1]) > 0 && Number(m[1]) <= 1000) opts.fps = Number(m[1]);
      else throw new UsageError('--times is keys or fps:N (0 < N <= 1000)');
    } else if (a === '--pairing') {
      if (i + 1 >= argv.length) throw new UsageError('--pairing needs a value');
      opts.pairing = argv[++i];
      if (opts.pairing !== 'nearest' && opts.pairing !== 'trajectory') throw new UsageError('--pairing is nearest or trajectory');
    } else if (a === '--help' || a === '-h') {
      console.log(USAGE);
      process.exit(0);
    } else if (a.startsWith('--')) throw new UsageError(`unknown option ${a}`);
    else opts.files.push(a);
  }
  if (opts.files.length !== 2) throw new UsageError('need ORIGINAL and OTHER');
  return opts;
}

// Every drawable primitive of a file: { node, mesh, primitive, object }.
function allPrimitives(asset) {
  const list = [];
  asset.json.nodes.forEach((nodeDef, n) => {
    primitiveObjects(asset, n).forEach((object, p) => {
      if (object && object.geometry && object.geometry.attributes.position) list.push({ node: n, mesh: nodeDef.mesh, primitive: p, object });
    });
  });
  return list;
}

// ---------------------------------------------------------------- what moves, and when

function parentsOf(json) {
  const parent = new Array(json.nodes.length).fill(-1);
  json.nodes.forEach((n, i) => (n.children || []).forEach((c) => (parent[c] = i)));
  return parent;
}

// The clip's tracks as { node, property, times }.
function clipTracks(asset, clip) {
  return clip.tracks.map((track) => {
    const parsed = THREE.PropertyBinding.parseTrackName(track.name);
    const object = THREE.PropertyBinding.findNode(asset.scene, parsed.nodeName);
    return { node: object ? (owningNode(asset, object)?.index ?? -1) : -1, property: parsed.propertyName, times: track.times };
  });
}

// The tracks of `tracks` that move node n's vertices: weights on n (morphed), TRS on its skin's joints
// and their ancestors (skinned).
function movingTracks(asset, parent, n, tracks) {
  const nodeDef = asset.json.nodes[n];
  const morphed = (asset.json.meshes[nodeDef.mesh].primitives[0].targets || []).length > 0;
  const relevant = new Set();
  if (nodeDef.skin !== undefined) {
    for (const joint of asset.json.skins[nodeDef.skin].joints) for (let j = joint; j >= 0 && !relevant.has(j); j = parent[j]) relevant.add(j);
  }
  return tracks.filter((t) => (t.property === 'morphTargetInfluences' ? morphed && t.node === n : relevant.has(t.node)));
}

// A grid of `fps` frames per second from start to end, in float32 as verify writes it.
function regularGrid(start, end, fps) {
  const duration = end - start;
  const steps = Math.floor(duration * fps + 1e-9);
  const times = [];
  for (let k = 0; k <= steps; k++) times.push(Math.fround(start + k / fps));
  if (end - times[times.length - 1] > 1e-6 * Math.max(1, duration)) times.push(Math.fround(end));
  return times.filter((t, i) => i === 0 || t > times[i - 1]);
}

// The frame times of a node in a clip (see the header).
function frameTimes(tracks, fps) {
  const keys = [...new Set(tracks.flatMap((t) => Array.from(t.times)))].sort((a, b) => a - b);
  if (keys.length === 0) return keys;
  const start = keys[0];
  const end = keys[keys.length - 1];
  if (fps > 0) return regularGrid(start, end, fps);
  if (keys.length - 1 <= MAX_KEY_RATE * (end - start) + 1e-9) return keys;
  return regularGrid(start, end, DEFAULT_FPS);
}

// OTHER's clip for ORIGINAL's clip c: the one of the same name when exactly one has it, else index c.
function counterpartClip(original, other, c) {
  const name = original.clips[c].name;
  const same = other.clips.filter((clip) => clip.name === name);
  if (same.length === 1) return same[0];
  return other.clips[c] || null;
}

// ---------------------------------------------------------------- posing


// Poses a scene at time t of a clip from its rest state, with a fresh mixer each time (a reused mixer
// skips writing values it wrote before, which a reset to rest would leave wrong).
class Poser {
  constructor(asset) {
    this.scene = asset.scene;
    this.mixer = null;
    this.scene.updateMatrixWorld(true);
    this.rest = [];
    this.restWorld = new Map();
    this.scene.traverse((o) => {
      this.rest.push({ o, position: o.position.clone(), quaternion: o.quaternion.clone(), scale: o.scale.clone(), morph: o.morphTargetInfluences ? o.morphTargetInfluences.slice() : null });
      this.restWorld.set(o, o.matrixWorld.clone());
    });
  }

  pose(clip, t) {
    if (this.mixer) {
      this.mixer.stopAllAction();
      this.mixer.uncacheRoot(this.scene);
    }
    for (const r of this.rest) {
      r.o.position.copy(r.position);
      r.o.quaternion.copy(r.quaternion);
      r.o.scale.copy(r.scale);
      if (r.morph) r.o.morphTargetInfluences.splice(0, r.morph.length, ...r.morph);
    }
    this.mixer = new THREE.AnimationMixer(this.scene);
    const action = this.mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce, 1);
    action.clampWhenFinished = true; // t == duration is the last key, not the first
    action.play();
    this.mixer.setTime(t);
    this.scene.updateMatrixWorld(true);
  }
}

const _v = new THREE.Vector3();
const _m = new THREE.Vector3();

// An object's vertices at the current pose: world (what is drawn) and verify's space (skinned: world;
// morph only: the morphed mesh-space position carried by the object's rest world matrix).
function positions(poser, object) {
  const count = object.geometry.attributes.position.count;
  const world = new Float64Array(3 * count);
  const model = object.isSkinnedMesh ? world : new Float64Array(3 * count);
  const rest = poser.restWorld.get(object);
  for (let i = 0; i < count; i++) {
    if (object.isMesh) object.getVertexPosition(i, _v); // morph, then skin
    else THREE.Mesh.prototype.getVertexPosition.call(object, i, _v); // points, lines: morph only
    if (!object.isSkinnedMesh) {
      _m.copy(_v).applyMatrix4(rest);
      model[3 * i] = _m.x;
      model[3 * i + 1] = _m.y;
      model[3 * i + 2] = _m.z;
    }
    _v.applyMatrix4(object.matrixWorld);
    world[3 * i] = _v.x;
    world[3 * i + 1] = _v.y;
    world[3 * i + 2] = _v.z;
  }
  return { world, model };
}

// ---------------------------------------------------------------- pairing

function diagonal(a) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < a.length; i += 3) {
    for (let c = 0; c < 3; c++) {
      lo[c] = Math.min(lo[c], a[i + c]);
      hi[c] = Math.max(hi[c], a[i + c]);
    }
  }
  return Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

// A uniform grid over points tagged (set, index): nearest neighbours by growing shells of cells.
class PointGrid {
  constructor(sets) {
    this.sets = sets; // arrays of xyz
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    let count = 0;
    for (const s of sets) {
      count += s.length / 3;
      for (let i = 0; i < s.length; i += 3) for (let c = 0; c < 3; c++) (lo[c] = Math.min(lo[c], s[i + c])), (hi[c] = Math.max(hi[c], s[i + c]));
    }
    const d = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    this.cell = Math.max(d / Math.max(1, Math.cbrt(count)), 1e-12);
    this.lo = lo;
    this.span = Math.ceil(d / this.cell) + 1; // shells beyond this hold nothing
    this.cells = new Map();
    sets.forEach((s, set) => {
      for (let i = 0; i < s.length / 3; i++) {
        const key = this.key(this.coord(s, i));
        if (!this.cells.has(key)) this.cells.set(key, []);
        this.cells.get(key).push(set, i);
      }
    });
  }

  coord(s, i) {
    return [0, 1, 2].map((c) => Math.floor((s[3 * i + c] - this.lo[c]) / this.cell));
  }

  key(c) {
    return `${c[0]},${c[1]},${c[2]}`;
  }

  // Points of the sets `allowed` accepts within (nearest distance + slack) of p: [{ set, index, d }].
  near(p, slack, allowed) {
    const q = this.coord(p, 0);
    const outside = Math.max(0, ...q.map((c) => Math.max(-c, c - this.span)));
    let best = Infinity;
    const found = [];
    for (let r = 0; r <= this.span + outside; r++) {
      for (let x = -r; x <= r; x++) {
        for (let y = -r; y <= r; y++) {
          for (let z = -r; z <= r; z++) {
            if (Math.max(Math.abs(x), Math.abs(y), Math.abs(z)) !== r) continue; // the shell only
            const list = this.cells.get(this.key([q[0] + x, q[1] + y, q[2] + z]));
            if (!list) continue;
            for (let k = 0; k < list.length; k += 2) {
              const set = list[k];
              if (!allowed(set)) continue;
              const s = this.sets[set];
              const i = list[k + 1];
              const d = Math.hypot(s[3 * i] - p[0], s[3 * i + 1] - p[1], s[3 * i + 2] - p[2]);
              best = Math.min(best, d);
              if (d <= best + slack) found.push({ set, index: i, d });
            }
          }
        }
      }
      if (best + slack < r * this.cell) break; // unvisited cells are at least r cells away
    }
    return found.filter((f) => f.d <= best + slack);
  }
}

// Among candidates, the one whose trajectory over the check frames is nearest to ORIGINAL vertex v's.
function pickByTrajectory(candidates, v, checkOriginal, checkOther) {
  let best = null;
  let bestSum = Infinity;
  for (const c of candidates) {
    let sum = 0;
    for (let f = 0; f < checkOriginal.length; f++) {
      const a = checkOriginal[f];
      const b = checkOther[f][c.set];
      for (let k = 0; k < 3; k++) sum += (a[3 * v + k] - b[3 * c.index + k]) ** 2;
    }
    if (sum < bestSum) (bestSum = sum), (best = c);
  }
  return best;
}

// Pairs one ORIGINAL primitive with an OTHER primitive and each of its vertices with one of that
// primitive's (see the header). `check*[f]`: world positions at the check frames (f = 0 the first
// frame), ORIGINAL's of this primitive, OTHER's of every primitive of `others`.
function pairPrimitive(grid, others, checkOriginal, checkOther, sameName) {
  const first = checkOriginal[0];
  const count = first.length / 3;
  const slack = TIE_SLACK * diagonal(first);
  const allowedByName = sameName.length ? (set) => sameName.includes(set) : () => true;
  const match = (allowed) => {
    const out = [];
    for (let v = 0; v < count; v++) {
      const candidates = grid.near(first.subarray(3 * v, 3 * v + 3), slack, allowed);
      out.push(candidates.length ? pickByTrajectory(candidates, v, checkOriginal, checkOther) : null);
    }
    return out;
  };
  const votes = new Map();
  for (const m of match(allowedByName)) if (m) votes.set(m.set, (votes.get(m.set) || 0) + 1);
  if (votes.size === 0) return null;
  const set = [...votes.entries()].sort((a, b) => b[1] - a[1])[0][0];
  const within = match((s) => s === set);
  const diag = diagonal(first);
  const distances = within.map((m) => m.d / (diag || 1));
  return {
    set,
    other: others[set],
    vertices: Int32Array.from(within, (m) => m.index),
    vote: votes.get(set) / count,
    byName: sameName.length > 0,
    maxDistance: Math.max(...distances), // at the first frame, over the primitive's diagonal
    meanDistance: distances.reduce((a, b) => a + b, 0) / count,
  };
}

// ---------------------------------------------------------------- KG

// Adds one frame to a KG accumulator: a = ORIGINAL's positions, b = OTHER's (paired vertices).
function addFrame(acc, a, b, vertices) {
  const count = a.length / 3;
  const centroid = [0, 0, 0];
  for (let i = 0; i < count; i++) for (let k = 0; k < 3; k++) centroid[k] += a[3 * i + k];
  for (let k = 0; k < 3; k++) centroid[k] /= count;
  for (let i = 0; i < count; i++) {
    const j = vertices[i];
    for (let k = 0; k < 3; k++) {
      acc.error += (a[3 * i + k] - b[3 * j + k]) ** 2;
      acc.spread += (a[3 * i + k] - centroid[k]) ** 2;
    }
  }
  acc.frames++;
}

const kg = (acc) => (acc.spread > 0 ? 100 * Math.sqrt(acc.error / acc.spread) : 0);
const accumulator = () => ({ error: 0, spread: 0, frames: 0 });

// The KG sums of a row, per clip and over its clips, in verify's space and in world space.
function accumulate(row) {
  row.total = accumulator();
  row.totalWorld = accumulator();
  for (const record of row.perClip) {
    record.acc = accumulator();
    record.accWorld = accumulator();
    for (const { a, b } of record.frames) {
      for (const [acc, space] of [[record.acc, 'model'], [row.total, 'model'], [record.accWorld, 'world'], [row.totalWorld, 'world']]) {
        addFrame(acc, a[space], b[space], row.pairing.vertices);
      }
    }
  }
}

// --pairing trajectory: each ORIGINAL vertex with the vertex of the paired OTHER primitive whose positions
// over every sampled frame (verify's space) are nearest in the sum of squared distances, as verify pairs.
// Candidates are visited by first-frame distance, which bounds the sum from below.
function trajectoryMatch(perClip) {
  const frames = perClip.flatMap((r) => r.frames.map((f) => [f.a.model, f.b.model]));
  const [a0, b0] = frames[0];
  const count = a0.length / 3;
  const otherCount = b0.length / 3;
  const match = new Int32Array(count);
  for (let v = 0; v < count; v++) {
    const order = [];
    for (let u = 0; u < otherCount; u++) {
      order.push({ u, d: (a0[3 * v] - b0[3 * u]) ** 2 + (a0[3 * v + 1] - b0[3 * u + 1]) ** 2 + (a0[3 * v + 2] - b0[3 * u + 2]) ** 2 });
    }
    order.sort((x, y) => x.d - y.d);
    let best = Infinity;
    for (const { u, d } of order) {
      if (d >= best) break;
      let sum = 0;
      for (let f = 0; f < frames.length && sum < best; f++) {
        const [a, b] = frames[f];
        for (let k = 0; k < 3; k++) sum += (a[3 * v + k] - b[3 * u + k]) ** 2;
      }
      if (sum < best) (best = sum), (match[v] = u);
    }
  }
  return match;
}

// ---------------------------------------------------------------- main

// ORIGINAL's animated primitives: [{ node, primitive, object, clips: [{ clip, times }] }].
function animatedPrimitives(original, fps) {
  const parent = parentsOf(original.json);
  const tracksByClip = original.clips.map((clip) => clipTracks(original, clip));
  const list = [];
  original.json.nodes.forEach((nodeDef, n) => {
    if (nodeDef.mesh === undefined || !original.nodeObjects.has(n)) return;
    const clips = [];
    tracksByClip.forEach((tracks, c) => {
      const moving = movingTracks(original, parent, n, tracks);
      if (moving.length) clips.push({ clip: c, times: frameTimes(moving, fps) });
    });
    if (clips.length === 0) return;
    primitiveObjects(original, n).forEach((object, p) => list.push({ node: n, mesh: nodeDef.mesh, primitive: p, object, clips }));
  });
  return list;
}

// Evenly spread frames of a time list, the first one first.
function checkTimes(times) {
  const out = [];
  for (let k = 0; k < CHECK_FRAMES; k++) out.push(times[Math.round((k * (times.length - 1)) / (CHECK_FRAMES - 1))]);
  return [...new Set(out)];
}

async function measure(opts) {
  const clock = { start: performance.now() };
  const original = await loadGltf(opts.files[0]);
  const other = await loadGltf(opts.files[1]);
  if (opts.normalizeRotations) [original, other].forEach(normalizeRotations);
  clock.loaded = performance.now();
  const originalPoser = new Poser(original);
  const otherPoser = new Poser(other);
  const others = allPrimitives(other);
  const failures = [];
  const warnings = [];

  const rows = animatedPrimitives(original, opts.fps).map((entry) => ({ ...entry, name: original.json.nodes[entry.node].name || '' }));
  if (rows.length === 0) failures.push('nothing in ORIGINAL is deformed by its animations');
  original.clips.forEach((clip, c) => {
    const counterpart = counterpartClip(original, other, c);
    if (counterpart && counterpart.name !== clip.name) warnings.push(`clip ${c} "${clip.name}" paired by index with OTHER's "${counterpart.name}"`);
  });

  // Pairing, at the first clip of each row's node.
  for (const row of rows) {
    const first = row.clips[0];
    const otherClip = counterpartClip(original, other, first.clip);
    if (!otherClip) {
      row.error = `OTHER has no clip for "${original.clips[first.clip].name}"`;
      continue;
    }
    const checkOriginal = [];
    const checkOther = [];
    for (const t of checkTimes(first.times)) {
      originalPoser.pose(original.clips[first.clip], t);
      otherPoser.pose(otherClip, t);
      checkOriginal.push(positions(originalPoser, row.object).world);
      checkOther.push(others.map((o) => positions(otherPoser, o.object).world));
    }
    const grid = new PointGrid(checkOther[0]);
    const sameName = row.name ? others.map((o, i) => (other.json.nodes[o.node].name === row.name ? i : -1)).filter((i) => i >= 0) : [];
    row.pairing = pairPrimitive(grid, others, checkOriginal, checkOther, sameName);
    if (!row.pairing) row.error = 'no OTHER vertex near its first frame';
    else if (row.pairing.maxDistance > PAIRING_WARNING) {
      warnings.push(`node ${row.node} primitive ${row.primitive}: a vertex is ${row.pairing.maxDistance.toExponential(1)} of the diagonal from its pair at the first frame; OTHER may not hold this primitive`);
    }
  }
  clock.paired = performance.now();

  // Sampling: per clip, pose both scenes once per time any row needs; the frames are kept.
  for (const row of rows) row.perClip = [];
  original.clips.forEach((clip, c) => {
    const otherClip = counterpartClip(original, other, c);
    const byTime = new Map();
    for (const row of rows) {
      if (row.error) continue;
      const entry = row.clips.find((e) => e.clip === c);
      if (!entry) continue;
      if (!otherClip) {
        row.error = `OTHER has no clip for "${clip.name}"`;
        continue;
      }
      const record = { row, clip: c, name: clip.name, otherClip: otherClip.name, times: entry.times, frames: [] };
      row.perClip.push(record);
      for (const t of entry.times) {
        if (!byTime.has(t)) byTime.set(t, []);
        byTime.get(t).push(record);
      }
    }
    for (const t of [...byTime.keys()].sort((a, b) => a - b)) {
      originalPoser.pose(clip, t);
      otherPoser.pose(otherClip, t);
      const otherCache = new Map();
      for (const record of byTime.get(t)) {
        const { row } = record;
        const o = row.pairing.other.object;
        if (!otherCache.has(o)) otherCache.set(o, positions(otherPoser, o));
        record.frames.push({ a: positions(originalPoser, row.object), b: otherCache.get(o) });
      }
    }
  });
  clock.sampled = performance.now();
  for (const row of rows) {
    if (row.error) continue;
    if (opts.pairing === 'trajectory') row.pairing.vertices = trajectoryMatch(row.perClip);
    accumulate(row);
  }
  clock.measured = performance.now();

  const primitives = rows.map((row) => primitiveReport(row, original, other));
  for (const p of primitives) if (p.error) failures.push(`node ${p.node} primitive ${p.primitive}: ${p.error}`);
  const measured = primitives.filter((p) => !p.error);
  const worst = measured.reduce((w, p) => (!w || p.kg_percent > w.kg_percent ? p : w), null);
  return {
    original: opts.files[0],
    other: opts.files[1],
    times: opts.fps > 0 ? `fps:${opts.fps}` : 'keys',
    kg_percent: worst ? worst.kg_percent : null,
    kg_percent_world: measured.length ? Math.max(...measured.map((p) => p.kg_percent_world)) : null,
    worst: worst && { node: worst.node, node_name: worst.node_name, primitive: worst.primitive },
    primitives,
    pairing: opts.pairing,
    normalize_rotations: opts.normalizeRotations,
    timings_ms: { load: round(clock.loaded - clock.start), pair: round(clock.paired - clock.loaded), sample: round(clock.sampled - clock.paired), measure: round(clock.measured - clock.sampled) },
    pass: failures.length === 0,
    failures,
    warnings,
  };
}

const round = (x) => Math.round(x * 10) / 10;

function primitiveReport(row, original, other) {
  const p = row.pairing;
  const report = {
    node: row.node,
    node_name: row.name,
    mesh: row.mesh,
    primitive: row.primitive,
    vertices: row.object.geometry.attributes.position.count,
    frames: row.total ? row.total.frames : 0,
    kind: `${row.object.isSkinnedMesh ? 'skinned' : ''}${row.object.morphTargetInfluences && row.object.morphTargetInfluences.length ? (row.object.isSkinnedMesh ? '+morph' : 'morph') : ''}`,
  };
  if (row.error) return { ...report, error: row.error };
  return {
    ...report,
    kg_percent: kg(row.total),
    kg_percent_world: kg(row.totalWorld),
    other: {
      node: p.other.node,
      node_name: other.json.nodes[p.other.node].name || '',
      mesh: p.other.mesh,
      primitive: p.other.primitive,
      vertices: p.other.object.geometry.attributes.position.count,
      paired_by: p.byName ? 'node name, then nearest vertices' : 'nearest vertices',
      vote: p.vote,
      max_first_frame_distance_over_diagonal: p.maxDistance,
      mean_first_frame_distance_over_diagonal: p.meanDistance,
    },
    clips: row.perClip.map((r) => ({ clip: r.clip, name: r.name, other_clip: r.otherClip, frames: r.times.length, kg_percent: kg(r.acc), kg_percent_world: kg(r.accWorld) })),
  };
}

function fmt(x, digits = 4) {
  return x === null || x === undefined ? '-' : x.toPrecision(digits);
}

function printTable(result) {
  const header = ['node', 'name', 'prim', 'kind', 'verts', 'frames', 'other', 'pairing', 'kg%', 'kg%_world', 'worst clip'];
  const lines = [header];
  for (const p of result.primitives) {
    if (p.error) {
      lines.push([String(p.node), p.node_name, String(p.primitive), p.kind, String(p.vertices), '-', '-', '-', '-', '-', `FAIL ${p.error}`]);
      continue;
    }
    const worstClip = p.clips.reduce((w, c) => (!w || c.kg_percent > w.kg_percent ? c : w), null);
    lines.push([
      String(p.node), p.node_name, String(p.primitive), p.kind, String(p.vertices), String(p.frames),
      `n${p.other.node}/m${p.other.mesh}/p${p.other.primitive} (${p.other.vertices} v)`,
      `${p.other.paired_by === 'nearest vertices' ? 'geom' : 'name+geom'} ${(100 * p.other.vote).toFixed(0)}% max ${p.other.max_first_frame_distance_over_diagonal.toExponential(1)}`,
      fmt(p.kg_percent), fmt(p.kg_percent_world),
      worstClip ? `${worstClip.name} ${fmt(worstClip.kg_percent)}` : '-',
    ]);
  }
  const widths = header.map((_, i) => Math.max(...lines.map((l) => l[i].length)));
  for (const l of lines) console.log(l.map((cell, i) => cell.padEnd(widths[i])).join('  ').trimEnd());
  for (const w of result.warnings) console.log(`warning: ${w}`);
  const t = result.timings_ms;
  console.log(
    `${result.pass ? 'OK' : 'FAIL'}: times ${result.times}, worst KG ${fmt(result.kg_percent)} %` +
      (result.worst ? ` (node ${result.worst.node} ${result.worst.node_name} primitive ${result.worst.primitive})` : '') +
      `, worst world-space KG ${fmt(result.kg_percent_world)} %; pairing ${result.pairing}; load ${t.load} ms, pairing ${t.pair} ms, sampling ${t.sample} ms, KG ${t.measure} ms` +
      (result.failures.length ? `; ${result.failures.join('; ')}` : ''),
  );
}

// ---------------------------------------------------------------- entry

let opts;
try {
  opts = parseArgs(process.argv.slice(2));
} catch (err) {
  console.error(`resampled_three.mjs: ${err.message}\n${USAGE}`);
  process.exit(2);
}
if (opts.json) console.log = console.info = (...args) => console.error(...args); // stdout: the JSON only
let result;
try {
  result = await measure(opts);
} catch (err) {
  console.error(`resampled_three.mjs: ${err instanceof UsageError ? err.message : `error: ${err && err.message ? err.message : err}`}`);
  process.exit(2);
}
if (opts.json) process.stdout.write(JSON.stringify(result) + '\n');
else printTable(result);
process.exit(result.pass ? 0 : 1);
