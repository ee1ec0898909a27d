// docs/benchmarks.md and its charts, from the results the harness saved (any subset of its parts).

import { mkdirSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { BAKE, CODECS, gltfpackModesDisagree, leastBytesAt } from './rate_distortion.mjs';
import { SPEED_ERROR, SPEED_GLTFPACK_BITS, STAGES } from './speed.mjs';
import { LINKS_MBIT } from './browser.mjs';
import { DELIVERIES } from './tools.mjs';
import { barChart, lineChart, panels } from './svg_chart.mjs';

const ANCHORS = CODECS.slice(2, -1).map((c) => c.family);
const GLTFPACK = CODECS.filter((c) => c.tool === 'gltfpack').map((c) => c.family);
const HEADLINE = DELIVERIES[0];
// "after brotli -q 11 / after gzip -9 / raw": the order of the figures where a line gives all three.
const DELIVERY_LIST = DELIVERIES.map((d) => (d.key === 'raw' ? 'raw' : `after ${d.name}`)).join(' / ');
const fixed = (x) => (x === null || x === undefined || !Number.isFinite(x) ? '—'
  : x < 10 ? x.toFixed(3) : x < 100 ? x.toFixed(2) : x.toFixed(1));
const kgText = (kg) => (kg === null || kg === undefined ? '—' : kg === 0 ? '0' : `${kg.toPrecision(3)} %`);
const mb = (kb) => (kb ? (kb / 1024).toFixed(0) : '—');
const ms = (x) => (x === null || x === undefined ? '—' : x >= 100 ? x.toFixed(0) : x.toFixed(1));
const seconds = (x) => (x / 1000).toFixed(x >= 10000 ? 1 : 2);
const slug = (label) => path.basename(label).replace(/\.(glb|gltf)$/i, '').toLowerCase().replace(/[^a-z0-9]+/g, '-');
const shapeText = (shape) => (shape ? `${shape.vertices} × ${shape.frames}` : '—');
const ok = (runs) => runs.filter((r) => !r.failed && !r.unreachable);
// Bits per vertex per frame of `bytes`: the input's Σ V × F is every tool's denominator.
const bpvf = (bytes, shape) => (8 * bytes) / shape.vertex_frames;

function metaLine(name, meta) {
  if (!meta) return null;
  const load = meta.load ? `, load average ${meta.load.map((x) => x.toFixed(2)).join(' / ')} (start / end)` : '';
  return `- ${name}: segmorph revision ${meta.revision}, ${meta.started}, ${meta.minutes.toFixed(1)} min${load}.`;
}

// The rate-distortion chart of one file: bpvf after brotli against KG, every codec a curve, bake a reference line.
function rdChart(file) {
  const runs = ok(file.runs);
  const rate = (r) => bpvf(r.bytes[HEADLINE.key], file.shape);
  const series = CODECS.filter((c) => c.family !== BAKE).map((c) => ({
    name: c.family,
    points: runs.filter((r) => r.family === c.family).map((r) => [r.kg, rate(r)]).sort((a, b) => a[0] - b[0]),
    dashed: c.tool === 'gltf-transform',
  })).filter((s) => s.points.length > 0);
  const bake = runs.find((r) => r.family === BAKE);
  return lineChart({
    title: `${file.label} (V × F = ${shapeText(file.shape)}), bytes after ${HEADLINE.name}`,
    x: { label: 'KG error (%)', log: true },
    y: { label: `bits per vertex per frame, ${HEADLINE.name}`, log: true },
    series,
    references: bake ? [{ name: `raw floats (bake): ${fixed(rate(bake))} bpvf, KG 0`, y: rate(bake) }] : [],
  });
}

// When every run of an anchor has a lower KG than `kg`: its smallest file counted as `delivery` says, an upper
// bound on what it needs.
function upperBound(kg, runs, delivery) {
  const below = runs.filter((r) => r.kg <= kg);
  if (below.length === 0) return null;
  return { bytes: Math.min(...below.map((r) => r.bytes[delivery])), upper: true };
}

// segmorph's --error `target` run of a file, or undefined when it failed.
const segmorphAt = (runs, target) => runs.find((r) => r.family === CODECS[0].family && r.bound === target);

// One equal-KG table: per file, bpvf of segmorph --error `target` and of the least bytes each anchor needs at its
// KG, all counted as `delivery` says, with each anchor's bytes over segmorph's.
function equalKgTable(rd, target, delivery, print) {
  print(`| file | V × F | raw float (bake) | segmorph --error ${target} | ${ANCHORS.join(' | ')} |`);
  print(`|---|---|---|---|${ANCHORS.map(() => '---|').join('')}`);
  for (const file of rd.files) {
    const runs = ok(file.runs);
    const seg = segmorphAt(runs, target);
    const bake = runs.find((r) => r.family === BAKE);
    const bakeRate = bake ? fixed(bpvf(bake.bytes[delivery], file.shape)) : '—';
    if (!seg) { print(`| ${file.label} | ${shapeText(file.shape)} | ${bakeRate} | failed |${ANCHORS.map(() => ' |').join('')}`); continue; }
    const cells = ANCHORS.map((family) => {
      const anchor = runs.filter((r) => r.family === family);
      const at = leastBytesAt(seg.kg, anchor, delivery) ?? upperBound(seg.kg, anchor, delivery);
      if (!at) return '—';
      const bound = at.upper ? '≤ ' : '';
      return `${bound}${fixed(bpvf(at.bytes, file.shape))} (${bound}${(at.bytes / seg.bytes[delivery]).toFixed(2)}×)`;
    });
    print(`| ${file.label} | ${shapeText(file.shape)} | ${bakeRate} | ${fixed(bpvf(seg.bytes[delivery], file.shape))} @ ${kgText(seg.kg)} | ${cells.join(' | ')} |`);
  }
  print();
}

function rateDistortion(rd, charts, lines, flags) {
  const print = (line = '') => lines.push(line);
  print('## Rate and distortion');
  print();
  print('Every output of every tool measured by `segmorph verify` against its input. **Bytes** are those of the file ' +
        `the tool wrote as a web server sends it: after \`${HEADLINE.name}\` (the headline: the equal-KG ratios, the ` +
        'summary and the charts), after `gzip -9`, and raw (the file as written) beside them. gltfpack\'s meshopt ' +
        'codecs are made to be followed by one of those; segmorph\'s range-coded streams do not shrink further. ' +
        '**bpvf**: 8 × those bytes / Σ V × F over the input\'s animated primitives and clips (the same denominator ' +
        'for every tool); **KG**: Karni & Gotsman\'s error in %, the worst animated primitive; RMSE and maximum ' +
        'error over the first frame\'s bounding-box diagonal in the full tables. Charts: both axes logarithmic; the ' +
        'dashed line is the raw float morph targets `segmorph bake` writes (KG 0).');
  print();
  print('Settings: segmorph `encode --bpvf 0.5, 1, 2, 4, 8` and `--error 1, 0.5, 0.15, 0.05`; gltfpack 1.3 ' +
        '`-cc -af 0 -vp 8` to `16` (EXT_meshopt_compression) and `-cz -af 0 -vp 8` to `16` (KHR_meshopt_compression, ' +
        'attribute codec version 1: both lossless on the same quantized data, so their KG is the same at each -vp); ' +
        'glTF-Transform 4.5 `meshopt`, `quantize` and `draco` with `--quantize-position ' +
        '8, 10, 12, 14, 16` (their other options at their defaults). Draco (KHR_draco_mesh_compression) does not ' +
        'cover morph targets: on morph-target files glTF-Transform compresses the base mesh only and leaves the ' +
        'targets as floats; on skinned files it compresses the whole mesh, and the animation is the joints\'.');
  print();

  for (const target of [0.15, 0.5]) {
    print(`### At segmorph's KG, --error ${target}`);
    print();
    print('bpvf of the least bytes each anchor needs for segmorph\'s KG or lower, interpolated in log KG between its ' +
          'settings (the settings no other beats on both bytes and KG), and in brackets its bytes over segmorph\'s. ' +
          '"≤": even the anchor\'s coarsest setting measured has a lower KG than segmorph, so its smallest file is an ' +
          'upper bound (a coarser setting might need fewer bytes); "—": the anchor produced nothing measurable. ' +
          `First with every file after \`${HEADLINE.name}\`, then after \`${DELIVERIES[1].name}\`, then raw (the files as written).`);
    print();
    for (const delivery of DELIVERIES) {
      print(`Bytes ${delivery.key === 'raw' ? 'raw, as written' : `after \`${delivery.name}\``}${delivery === HEADLINE ? ' (the headline)' : ''}:`);
      print();
      equalKgTable(rd, target, delivery.key, print);
    }
  }

  print('### Per file');
  print();
  print(`Charts: bpvf after \`${HEADLINE.name}\`. Tables: bytes after each, bpvf after \`${HEADLINE.name}\` and raw.`);
  print();
  for (const file of rd.files) {
    const name = `rd-${slug(file.label)}.svg`;
    charts.set(name, rdChart(file));
    print(`#### ${file.label}`);
    print();
    print(`![bpvf after ${HEADLINE.name} against KG error, ${file.label}](${charts.link(name)})`);
    print();
    print('<details><summary>every run</summary>');
    print();
    print(`| codec | setting | ${DELIVERIES.map((d) => `${d.name} bytes`).join(' | ')} | bpvf ${HEADLINE.name} | bpvf raw | KG | RMSE / diag | max / diag | wall time | peak memory |`);
    print(`|---|---|${DELIVERIES.map(() => '---|').join('')}---|---|---|---|---|---|---|`);
    const blank = ' |'.repeat(DELIVERIES.length + 6);
    for (const r of file.runs) {
      if (r.failed) { print(`| ${r.family} | ${r.setting} | failed: ${r.failed} |${blank}`); continue; }
      if (r.unreachable) { print(`| ${r.family} | ${r.setting} | refused: ${r.unreachable} |${blank}`); continue; }
      print(`| ${r.family} | ${r.setting} | ${DELIVERIES.map((d) => r.bytes[d.key]).join(' | ')} | ` +
            `${fixed(bpvf(r.bytes[HEADLINE.key], file.shape))} | ${fixed(bpvf(r.bytes.raw, file.shape))} | ${kgText(r.kg)} | ` +
            `${r.rmse.toExponential(2)} | ${r.max.toExponential(2)} | ${ms(r.wall_ms)} ms | ${mb(r.max_rss_kb)} MB |`);
    }
    print();
    print('</details>');
    print();
    for (const r of file.runs) {
      if (r.failed) flags.push(`${file.label}, ${r.family} ${r.setting}: ${r.failed}`);
      else if (r.unreachable) continue;
      else if (r.bound !== null && r.bound !== undefined && r.kg > r.bound)
        flags.push(`${file.label}, segmorph ${r.setting}: KG ${kgText(r.kg)} is above the requested ${r.bound} %`);
    }
    flags.push(...gltfpackModesDisagree(file.runs).map((message) => `${file.label}, ${message}`));
  }
  bpvfTargets(rd, lines);
}

// segmorph --bpvf: the whole file against the target, split into what the rate control budgets (the animation
// streams and the Draco base meshes) and the rest of the file (images, JSON, meshes and animation it leaves as
// they are).
function bpvfTargets(rd, lines) {
  const print = (line = '') => lines.push(line);
  const targets = [...new Set(rd.files.flatMap((f) => f.runs.filter((r) => r.target_bpvf).map((r) => r.target_bpvf)))];
  if (targets.length === 0) return;
  print('### segmorph --bpvf: target and result');
  print();
  print('Per target: the whole file\'s bpvf, raw (the rate control budgets the file as written), then in brackets the ' +
        'part the animation streams and the Draco base meshes take (from encode --json) and the part the rest of the ' +
        'file takes (images, JSON, and the meshes, skins and node animation segmorph leaves as they are). A whole file ' +
        'more than 10 % off its target is in bold. "below the rest": segmorph refuses a target below what the rest of ' +
        'the file takes alone.');
  print();
  print(`| file | ${targets.map((t) => `--bpvf ${t}`).join(' | ')} |`);
  print(`|---|${targets.map(() => '---|').join('')}`);
  for (const file of rd.files) {
    const cells = targets.map((target) => {
      const r = file.runs.find((x) => x.target_bpvf === target);
      if (r?.unreachable) return 'below the rest';
      if (!r || r.failed || !r.encode) return 'failed';
      const coded = bpvf(r.encode.animation_bytes + r.encode.draco_bytes, file.shape), rate = bpvf(r.bytes.raw, file.shape);
      const whole = Math.abs(rate - target) > 0.1 * target ? `**${fixed(rate)}**` : fixed(rate);
      return `${whole} (${fixed(coded)} + ${fixed(rate - coded)})`;
    });
    print(`| ${file.label} | ${cells.join(' | ')} |`);
  }
  print();
}

// Vertex-frames per second of a whole command.
const throughput = (shape, wallMs) => (shape ? `${(shape.vertex_frames / (wallMs / 1000) / 1e6).toFixed(1)} M` : '—');

// One thread against every core: per stage, the time summed over the files (the sequences, and every file), and the
// speedup; the encode's wall time too.
function threadSpeedups(speed, print, flags) {
  const measured = speed.files.filter((f) => !f.result.failed && f.result.encode_one_thread);
  if (measured.length === 0) return;
  const cores = speed.cores ?? 0;
  print('### Threads');
  print();
  print(`The same encodes with \`--threads 1\` against the default (every core: ${cores} here), each run ${speed.repeats === 1 ? 'once' : `${speed.repeats} times`} ` +
        'and the median run\'s stage times summed over the files, and the speedup (one thread\'s time over every ' +
        'core\'s). The output is the same bytes for every thread count: the harness compares the two files of each input ' +
        'and flags any that differ. The work that splits over threads (`segmorph encode --help`, --threads): the ' +
        'heat-diffusion eigenpairs of a mesh\'s connected parts (side by side), the cluster count\'s candidates, the ' +
        'per-frame motion fits, the motion refinement\'s vertex moves and the cluster weights, each frame\'s ' +
        'reference, the rate control\'s measurements and its motion step trials, the version-4 bases (the stream\'s ' +
        'beside the residual coding), the decodes of version-4 frames, the Draco coding of rigid meshes, and the ' +
        'comparison with the input (its nodes, vertex pairing and rigid meshes); the eigenpairs of one connected part ' +
        'below 60,000 vertices, the residual coding and the writing of each stream run on one.');
  print();
  const groups = [['sequences', measured.filter((f) => f.label.startsWith('sequences/'))], ['every file', measured]];
  print(`| stage | ${groups.map(([name]) => `${name}: 1 thread | ${cores} threads | speedup`).join(' | ')} |`);
  print(`|---|${groups.map(() => '---|---|---|').join('')}`);
  const sum = (files, get) => files.reduce((total, f) => total + (get(f) ?? 0), 0);
  const rows = [...STAGES.map((s) => [s.replace('_', ' '), (e) => e.stages[s]]), ['whole encode (wall)', (e) => e.wall_ms]];
  for (const [name, get] of rows) {
    const cells = groups.map(([, files]) => {
      const one = sum(files, (f) => get(f.result.encode_one_thread)), all = sum(files, (f) => get(f.result.encode));
      return `${ms(one)} ms | ${ms(all)} ms | ${all > 0 ? (one / all).toFixed(2) + '×' : '—'}`;
    });
    print(`| ${name} | ${cells.join(' | ')} |`);
  }
  print();
  if (speed.files.some((f) => !f.result.failed && !f.result.encode_one_thread))
    flags.push('speed: some files have no one-thread measurement (results from an older harness)');
}

function speedAndMemory(speed, shapes, charts, lines, flags) {
  const print = (line = '') => lines.push(line);
  print('## Speed and memory');
  print();
  print(`Per file, each command run ${speed.repeats} times under \`run_measured\` (bench/run_measured.cpp: wall time, ` +
        'user + system CPU time and the peak resident set from wait4), median wall and CPU time, largest peak memory. ' +
        `segmorph \`encode --error ${SPEED_ERROR}\` (its default, on every core; the stage times are those its --json reports ` +
        'for the median run, summed over primitives: "segmentation" includes the cluster count\'s search and the motion ' +
        'refinement, "tracks" the coding of node tracks and the kept skins\' search, "measure" the decoding of the encode ' +
        'and its comparison with the input; "rest": loading, sampling, baking, the check that a version-1 to 3 stream ' +
        'decodes to the encoder\'s frames, writing), segmorph `decode` of that file (reading, Draco, the animation, writing standard morph ' +
        `targets; its throughput counts the input's vertex-frames over the whole command), and gltfpack \`-cc -af 0 -vp ${SPEED_GLTFPACK_BITS}\` on the same input (a Node.js process: WebAssembly).`);
  print();
  const stageNames = STAGES.map((s) => s.replace('_', ' '));
  print(`| file | V × F | encode wall (CPU) | ${stageNames.join(' | ')} | rest | encode peak | decode wall (CPU) | decode vertex-frames/s | decode peak | gltfpack wall (CPU) | gltfpack peak | encode / gltfpack wall |`);
  print(`|---|---|---|${STAGES.map(() => '---|').join('')}---|---|---|---|---|---|---|---|`);
  const rows = [];
  for (const file of speed.files) {
    const m = file.result;
    if (m.failed) { flags.push(`${file.label}, speed: ${m.failed}`); print(`| ${file.label} | | failed: ${m.failed} |`); continue; }
    const stages = STAGES.map((s) => m.encode.stages[s] ?? 0);
    const rest = Math.max(0, m.encode.wall_ms - stages.reduce((a, b) => a + b, 0));
    rows.push({ label: file.label, stages, rest, decode: m.decode.wall_ms, gltfpack: m.gltfpack.wall_ms });
    print(`| ${file.label} | ${shapeText(shapes.get(file.label))} | ${ms(m.encode.wall_ms)} (${ms(m.encode.cpu_ms)}) ms | ${stages.map(ms).join(' | ')} | ${ms(rest)} | ` +
          `${mb(m.encode.max_rss_kb)} MB | ${ms(m.decode.wall_ms)} (${ms(m.decode.cpu_ms)}) ms | ${throughput(shapes.get(file.label), m.decode.wall_ms)} | ${mb(m.decode.max_rss_kb)} MB | ` +
          `${ms(m.gltfpack.wall_ms)} (${ms(m.gltfpack.cpu_ms)}) ms | ${mb(m.gltfpack.max_rss_kb)} MB | ${(m.encode.wall_ms / m.gltfpack.wall_ms).toFixed(2)}× |`);
  }
  print();
  if (rows.length > 0) {
    charts.set('stages.svg', barChart({
      title: `segmorph encode --error ${SPEED_ERROR}: wall time per stage`,
      x: { label: 'milliseconds (wall, median)' },
      categories: rows.map((r) => path.basename(r.label)),
      stacks: [...stageNames.map((name, k) => ({ name, values: rows.map((r) => r.stages[k]) })),
               { name: 'rest of the command (load, sample, bake, check, write)', values: rows.map((r) => r.rest), color: '#c7c7c7' }],
      marks: [{ name: `gltfpack -cc -vp ${SPEED_GLTFPACK_BITS}, whole command`, values: rows.map((r) => r.gltfpack) },
              { name: 'segmorph decode, whole command', values: rows.map((r) => r.decode), color: '#d62728' }],
    }));
    print(`![encode time per stage](${charts.link('stages.svg')})`);
    print();
  }

  threadSpeedups(speed, print, flags);
  if (speed.codec.length === 0) return;
  print('### The codec alone (Google Benchmark)');
  print();
  print(`\`build/bench/codec_benchmark FILE --error ${SPEED_ERROR}\` on each sequence: the codec's stages on the first ` +
        'animated primitive, encoded against a stand-in base mesh (no glTF, no Draco, no files); CPU time per ' +
        'iteration, one core. Decode throughput in vertex-frames per second, next to a plain copy of the restored ' +
        'frames (V × F × 3 floats copied once, `DecodeFrameCopyLimit`: the practical limit of any decoder).');
  print();
  const names = ['EncodeWhole', 'EncodeSpectralMorseFunction', 'EncodeAffineMotion', 'EncodePrediction',
                 'EncodeMeasureSubbands/3', 'EncodeEntropy', 'DecodeWhole', 'DecodeEntropy', 'DecodeFrames'];
  print(`| sequence | V × F | ${names.join(' | ')} | decode throughput | copy throughput | copy / decode |`);
  print(`|---|---|${names.map(() => '---|').join('')}---|---|---|`);
  for (const { label, stages } of speed.codec) {
    if (stages.failed) { flags.push(`${label}, codec_benchmark: ${stages.failed}`); continue; }
    const decode = stages.DecodeWhole?.vfps, copy = stages.DecodeFrameCopyLimit?.vfps;
    print(`| ${label} | ${shapeText(shapes.get(label))} | ${names.map((n) => (stages[n] ? `${ms(stages[n].ms)} ms` : '—')).join(' | ')} | ` +
          `${decode ? (decode / 1e6).toFixed(1) : '—'} M vf/s | ${copy ? (copy / 1e6).toFixed(0) : '—'} M vf/s | ${decode && copy ? (copy / decode).toFixed(0) : '—'}× |`);
  }
  print();
  print('EncodeSpectralMorseFunction is the Laplace–Beltrami eigenpairs and heat-diffusion function of the segmentation; ' +
        'EncodeMeasureSubbands/3 one rate-control measurement of the residuals at 3 candidate steps per axis (the rate ' +
        'control makes several); DecodeEntropy the range decoder alone and DecodeFrames everything after it.');
  print();

  const api = speed.codec.filter(({ stages }) => !stages.failed && stages.DecodeWhole && stages.DecodeApiClips && stages.DecodeApiFrames);
  if (api.length === 0) return;
  print('### The runtime decoder through its C API');
  print();
  print('The same streams and runs through `include/segmorph/decoder_c.h`, as an engine calls it (docs/runtime.md): the ' +
        'stream opened, then every clip into memory the caller allocated beforehand (`DecodeApiClips`), or every frame ' +
        'into one V × 3 buffer, as a player that streams frames does (`DecodeApiFrames`); next to the decoder inside ' +
        'the tool (`DecodeWhole`, which grows the frames as it decodes) and a copy of the frames. CPU time per ' +
        'decode of the whole stream and vertex-frames per second; the API\'s cost is its time over DecodeWhole\'s.');
  print();
  print('| sequence | V × F | DecodeWhole | DecodeApiClips | DecodeApiFrames | copy of the frames | API cost: clips, frames |');
  print('|---|---|---|---|---|---|---|');
  const cell = (stage) => `${ms(stage.ms)} ms, ${(stage.vfps / 1e6).toFixed(1)} M vf/s`;
  const cost = (stage, base) => `${stage.ms >= base.ms ? '+' : ''}${((stage.ms / base.ms - 1) * 100).toFixed(1)} %`;
  for (const { label, stages } of api)
    print(`| ${label} | ${shapeText(shapes.get(label))} | ${cell(stages.DecodeWhole)} | ${cell(stages.DecodeApiClips)} | ` +
          `${cell(stages.DecodeApiFrames)} | ${stages.DecodeFrameCopyLimit ? cell(stages.DecodeFrameCopyLimit) : '—'} | ` +
          `${cost(stages.DecodeApiClips, stages.DecodeWhole)}, ${cost(stages.DecodeApiFrames, stages.DecodeWhole)} |`);
  print();
}

// Large skinned files, whole commands (bench/lib/large.mjs).
function largePart(large, lines, flags) {
  const print = (line = '') => lines.push(line);
  print('## Large skinned files');
  print();
  print('Production-size skinned characters, whole commands, each run ' + large.repeats + ' times (median wall and CPU ' +
        'time, largest peak memory): shared samples as they are, and files written from one (FILE × N) with its skinned ' +
        'mesh copied into N primitives of their own (each copy\'s positions moved by copy × 0.1 % of the mesh\'s extent, ' +
        'so that no tool merges them: a character split by material, as game assets are; bench/lib/large.mjs). ' +
        `segmorph \`encode --error ${SPEED_ERROR}\` keeps the skins and searches for the tracks' ` +
        'precision (encode\'s KG is measured on its decoded result); segmorph `bake` writes every frame as morph targets ' +
        `(what a runtime without skinning needs); gltfpack \`-cc -af 0 -vp ${SPEED_GLTFPACK_BITS}\` on the same input. ` +
        'Bytes after `brotli -q 11` (raw in brackets).');
  print();
  print('| file | primitives (modes) | V × F | input | encode wall (CPU) | encode peak | encode KG | encode bytes | bake wall (CPU) | bake peak | baked | gltfpack wall (CPU) | gltfpack peak | gltfpack bytes | encode / gltfpack wall |');
  print('|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|');
  const kB = (bytes) => `${(bytes / 1000).toFixed(1)} kB`;
  const mB = (bytes) => `${(bytes / 1e6).toPrecision(3)} MB`;
  for (const { label, result: m } of large.files) {
    if (m.failed) { flags.push(`${label}, large: ${m.failed}`); print(`| ${label} | failed: ${m.failed} |`); continue; }
    const count = Object.values(m.modes).reduce((a, b) => a + b, 0);
    const modes = Object.entries(m.modes).map(([mode, n]) => `${n} ${mode.replace('_', ' ')}`).join(', ');
    print(`| ${label} | ${count} (${modes}) | ${(m.vertex_frames / 1e6).toFixed(2)} M | ${mB(m.input_bytes)} | ` +
          `${seconds(m.encode.wall_ms)} (${seconds(m.encode.cpu_ms)}) s | ${mb(m.encode.max_rss_kb)} MB | ${kgText(m.encode.kg)} | ` +
          `${kB(m.encode.bytes.brotli)} (${kB(m.encode.bytes.raw)}) | ${seconds(m.bake.wall_ms)} (${seconds(m.bake.cpu_ms)}) s | ` +
          `${mb(m.bake.max_rss_kb)} MB | ${mB(m.bake.bytes)} | ${seconds(m.gltfpack.wall_ms)} (${seconds(m.gltfpack.cpu_ms)}) s | ` +
          `${mb(m.gltfpack.max_rss_kb)} MB | ${kB(m.gltfpack.bytes.brotli)} (${kB(m.gltfpack.bytes.raw)}) | ` +
          `${(m.encode.wall_ms / m.gltfpack.wall_ms).toFixed(1)}× |`);
    if (!(m.encode.kg <= SPEED_ERROR)) flags.push(`${label}, large: encode KG ${m.encode.kg} % above the requested ${SPEED_ERROR} %`);
  }
  print();
  print('V × F: vertex-frames of the animated (skinned and morphed) primitives, what bpvf counts; gltfpack\'s KG is not ' +
        'measured here (rate and distortion above measures it on the shared samples).');
  print();
  const sequences = large.sequences ?? [];
  if (sequences.length === 0) return;
  print('### Sequences as glTF morph targets');
  print();
  print('Cloth-like sequences at production size: `bench/codec_scaling --vertices V --frames F --write-cache PREFIX` ' +
        'writes the scaling torus (travelling waves, a bend, a twist: non-rigid everywhere) as an OBJ and a PC2 vertex ' +
        'cache, `segmorph bake PREFIX.obj --cache PREFIX.pc2` turns it into the glTF of one-hot morph targets such ' +
        `animation reaches glTF in, then segmorph \`encode --error ${SPEED_ERROR}\` and \`decode\` of that file, and ` +
        `gltfpack \`-cc -af 0 -vp ${SPEED_GLTFPACK_BITS}\` on it. One run each (the largest take minutes); raw bytes ` +
        '(brotli -q 11 of gltfpack\'s hundreds of MB would take longer than the run). The scale target (issue 19): ' +
        '200k vertices × 300 frames encoded in under 2 minutes and 4 GiB on this 2-core machine.');
  print();
  print('| V × F | glTF | bake from the cache: wall, peak | encode wall (CPU) | encode peak | KG | encoded | decode wall, peak | gltfpack wall (CPU) | gltfpack peak | gltfpack file | encode / gltfpack wall |');
  print('|---|---|---|---|---|---|---|---|---|---|---|---|');
  for (const { vertices, frames, result: m } of sequences) {
    if (m.failed) { flags.push(`sequence ${vertices} × ${frames}, large: ${m.failed}`); print(`| ${vertices} × ${frames} | failed: ${m.failed} |`); continue; }
    print(`| ${m.encode.vertices} × ${m.encode.frames} | ${mB(m.gltf_bytes)} | ${seconds(m.bake.wall_ms)} s, ${mb(m.bake.max_rss_kb)} MB | ` +
          `${seconds(m.encode.wall_ms)} (${seconds(m.encode.cpu_ms)}) s | ${mb(m.encode.max_rss_kb)} MB | ${kgText(m.encode.kg)} | ${mB(m.encode.bytes)} | ` +
          `${seconds(m.decode.wall_ms)} s, ${mb(m.decode.max_rss_kb)} MB | ${seconds(m.gltfpack.wall_ms)} (${seconds(m.gltfpack.cpu_ms)}) s | ` +
          `${mb(m.gltfpack.max_rss_kb)} MB | ${mB(m.gltfpack.bytes)} | ${(m.encode.wall_ms / m.gltfpack.wall_ms).toFixed(1)}× |`);
    if (!(m.encode.kg <= SPEED_ERROR)) flags.push(`sequence ${vertices} × ${frames}, large: encode KG ${m.encode.kg} % above the requested ${SPEED_ERROR} %`);
  }
  print();
  const target = sequences.find((s) => !s.result.failed && s.vertices >= 200000 && s.frames >= 300);
  if (target) {
    const m = target.result, met = m.encode.wall_ms < 120000 && m.encode.max_rss_kb < 4 * 1024 * 1024;
    print(`The scale target at ${m.encode.vertices} × ${m.encode.frames}: encode ${seconds(m.encode.wall_ms)} s and ` +
          `${mb(m.encode.max_rss_kb)} MB against 120 s and 4096 MiB: ${met ? 'met' : 'not met yet'}.`);
    print();
  }
}

// What a web page pays: bytes as delivered and load times in Chromium (bench/lib/browser.mjs).
function browserPart(browser, lines, flags) {
  const print = (line = '') => lines.push(line);
  print('## In the browser');
  print();
  print(`Each sequence encoded by segmorph \`--error ${SPEED_ERROR}\` and by gltfpack 1.3 \`-cc -af 0\` swept over \`-vp\`, the ` +
        'gltfpack file smallest after brotli -q 11 at equal or lower KG (measured by `segmorph verify` after ' +
        'meshopt_decode.mjs) as the anchor. ' +
        'Bytes as a web server sends them (brotli -q 11, gzip -9, raw). **Load**: the time GLTFLoader takes from the ' +
        'bytes in memory to a scene ready to play, in one page of headless Chromium ' +
        `(${browser.chromium ?? 'Chromium'}, software rendering, no GPU): segmorph's file with \`GLTFSegmorphExtension\` ` +
        '(docs/web.md) and DRACOLoader, gltfpack\'s with MeshoptDecoder; the median of ' +
        `${browser.repeats} loads after the page's first (**first**: that first load, which also starts the decoders' ` +
        'WebAssembly and workers), and **decode** the decoder\'s own share (the plugin\'s WebAssembly decode, or ' +
        'MeshoptDecoder.decodeGltfBuffer). **First frame at N Mbit/s**: brotli bytes / link rate + median load.');
  print();
  print(`| sequence | file | KG | brotli | gzip | raw | load (first) | decode | first frame at ${LINKS_MBIT.map((r) => `${r} Mbit/s`).join(' / ')} |`);
  print('|---|---|---|---|---|---|---|---|---|');
  const kb = (bytes) => `${(bytes / 1000).toFixed(1)} kB`;
  const seconds = (bytes, rate, ms) => ((bytes * 8) / (rate * 1e6) + ms / 1000).toFixed(2);
  for (const input of browser.inputs) {
    if (input.failed) { flags.push(`${input.label}, browser: ${input.failed}`); continue; }
    for (const [kind, name] of [['segmorph', `segmorph --error ${SPEED_ERROR}`], ['gltfpack', `gltfpack ${input.gltfpack.setting}`]]) {
      const f = input[kind], b = f.browser;
      if (!b) continue;
      print(`| ${input.label} | ${name} | ${f.kg.toPrecision(3)} %${f.kg_higher ? ' (higher)' : ''} | ${kb(f.brotli)} | ${kb(f.gzip)} | ` +
            `${kb(f.raw)} | ${ms(b.median)} ms (${ms(b.first)}) | ${ms(b.decode.median)} ms | ` +
            `${LINKS_MBIT.map((rate) => `${seconds(f.brotli, rate, b.median)} s`).join(' / ')} |`);
    }
  }
  print();
}

// Playing on the GPU: GPU bytes, load to first frame, time per frame (bench/lib/gpu.mjs).
function gpuPart(gpu, lines, flags) {
  const print = (line = '') => lines.push(line);
  const mb = (bytes) => `${(bytes / 1e6).toFixed(2)} MB`;
  print('## Playing on the GPU');
  print();
  print(`Each sequence encoded by segmorph \`--error ${SPEED_ERROR}\` (stream version 4) and by gltfpack 1.3 \`-cc -af 0 -vp ` +
        `${SPEED_GLTFPACK_BITS}\`, played in one page of headless Chromium (${gpu.chromium ?? 'Chromium'}, **software ` +
        'rendering**: SwiftShader\'s WebGL 2 on the CPU, so times are ratios within this run, not what a GPU takes): ' +
        'segmorph\'s file with the plugin\'s default, the model evaluated in the vertex shader (**gpu**), the same file ' +
        'with `{ playback: \'morph\' }` (every frame a morph target, **morph**), and gltfpack\'s file with MeshoptDecoder ' +
        '(morph targets). **GPU bytes**: what the load and the first frame allocate through WebGL (bufferData, texImage, ' +
        'texStorage, renderbufferStorage counted by web/gpu_bytes.js). **First frame**: from the bytes in memory to the ' +
        `first drawn frame (the drawing waited for), median of ${gpu.repeats} loads after a first. Per frame, the median ` +
        `over ${gpu.frames} times of the first clip: **CPU** the time of \`mixer.setTime\` and \`renderer.render\` (the ` +
        'plugin\'s blend and upload included), **frame** with the drawing waited for (a 1-pixel readPixels), and the ' +
        'bytes uploaded per frame.');
  print();
  print('| sequence | file | brotli | GPU bytes | vs gpu | first frame | CPU per frame | frame | uploaded per frame |');
  print('|---|---|---|---|---|---|---|---|---|');
  for (const input of gpu.inputs) {
    if (input.failed) { flags.push(`${input.label}, gpu: ${input.failed}`); continue; }
    const p = input.playback;
    if (!p) continue;
    for (const [mode, file, name] of [['gpu', input.segmorph, 'segmorph, gpu'], ['morph', input.segmorph, 'segmorph, morph'],
                                      ['gltfpack', input.gltfpack, 'gltfpack']]) {
      const m = p[mode];
      print(`| ${input.label} | ${name} | ${(file.brotli / 1000).toFixed(1)} kB | ${mb(m.allocated)} | ` +
            `${(m.allocated / p.gpu.allocated).toFixed(1)}x | ${ms(m.first)} ms | ${ms(m.cpu)} ms | ${ms(m.frame)} ms | ` +
            `${Math.round(m.uploaded).toLocaleString('en')} B |`);
    }
  }
  const t = gpu.torus;
  if (t?.failed) flags.push(`gpu, torus: ${t.failed}`);
  else if (t?.playback) {
    const g = t.playback.gpu;
    print(`| torus ${t.vertices.toLocaleString('en')} x ${t.frames} | segmorph, gpu | ${(t.bytes / 1000).toFixed(1)} kB raw | ` +
          `${mb(g.allocated)} | 1.0x | ${ms(g.first)} ms | ${ms(g.cpu)} ms | ${ms(g.frame)} ms | ` +
          `${Math.round(g.uploaded).toLocaleString('en')} B |`);
    print(`| torus ${t.vertices.toLocaleString('en')} x ${t.frames} | morph targets | | ${mb(t.morph_bytes_computed)} ` +
          `(computed as three.js stores them, V x F x ${t.normals ? 32 : 16} B: not loaded) | ` +
          `${(t.morph_bytes_computed / g.allocated).toFixed(1)}x | | | | |`);
  }
  print();
}

// Log-log slope of `y` against `x` between two points: the exponent of the growth.
const exponent = (a, b, x, y) => Math.log(y(b) / y(a)) / Math.log(x(b) / x(a));

function scalingPart(scaling, charts, lines, flags) {
  const print = (line = '') => lines.push(line);
  print('## Scaling');
  print();
  const result = scaling.result;
  if (result.failed) { flags.push(`scaling: ${result.failed}`); print(`Failed: ${result.failed}`); print(); return; }
  const { plan } = scaling;
  print('`build/bench/codec_scaling --vertices V --frames F` (bench/codec_scaling.cpp): a torus of about V vertices ' +
        '(one closed surface, 2V triangles) whose ring and tube swell in travelling waves while it bends, twists and ' +
        `drifts, generated in memory; encoded at the default --error ${SPEED_ERROR} against a stand-in base, decoded, ` +
        'measured. One process per point, with glibc\'s large buffers on transparent huge pages ' +
        '(`GLIBC_TUNABLES=glibc.malloc.hugetlb=1`, as the segmorph tool asks for itself). Times are wall clock; "draco" is the Draco encoding, decoding and vertex ' +
        'matching of the base mesh the container does; peak memory is the process\'s peak resident set while building ' +
        'the frames ("input"), during the encoder and during the decoder (reset between them).');
  print();
  const stageKeys = ['segmentation', 'motion', 'prediction', 'rate_control', 'entropy'];
  const table = (points) => {
    print(`| V | F | input | K | encode | ${stageKeys.map((s) => s.replace('_', ' ')).join(' | ')} | draco | decode | copy | peak: input | encode | decode | stream bpvf | KG |`);
    print(`|---|---|---|---|---|${stageKeys.map(() => '---|').join('')}---|---|---|---|---|---|---|---|`);
    for (const p of points) {
      const t = p.milliseconds;
      print(`| ${p.vertices} | ${p.frames} | ${p.input_mb.toFixed(0)} MB | ${p.clusters} | ${seconds(t.encode)} s | ` +
            `${stageKeys.map((s) => seconds(t[s])).join(' | ')} | ${ms(t.draco)} ms | ${ms(t.decode)} ms | ${ms(t.copy)} ms | ` +
            `${mb(p.peak_rss_kb.input)} MB | ${mb(p.peak_rss_kb.encode)} MB | ${mb(p.peak_rss_kb.decode)} MB | ${fixed(p.bpvf)} | ${kgText(p.kg_percent)} |`);
      if (!(p.kg_percent <= SPEED_ERROR * 1.01)) flags.push(`scaling V ${p.vertices} × F ${p.frames}: KG ${p.kg_percent} % above ${SPEED_ERROR} %`);
    }
    print();
  };
  const growth = (points, x, what) => {
    if (points.length < 3) return;
    const [a, b, c] = [points[0], points[points.length - 2], points[points.length - 1]];
    const rate = (y) => `${exponent(a, c, x, y).toFixed(2)} over the whole range, ${exponent(b, c, x, y).toFixed(2)} between the last two points`;
    print(`Growth exponents (log-log slope, ${what}): encode time ${rate((p) => p.milliseconds.encode)}; ` +
          `segmentation ${rate((p) => p.milliseconds.segmentation)}; rate control ${rate((p) => p.milliseconds.rate_control)}; ` +
          `decode ${rate((p) => p.milliseconds.decode)}; encoder peak memory ${rate((p) => p.peak_rss_kb.encode)}.`);
    print();
  };
  print(`### Against V (F = ${plan.fixedFrames})`);
  print();
  table(result.byVertices);
  growth(result.byVertices, (p) => p.vertices, 'against V');
  const largest = result.byVertices[result.byVertices.length - 1];
  if (largest) {
    const t = largest.milliseconds, share = (x) => `${(100 * x / t.encode).toFixed(0)} %`;
    print(`Where it stops: at V = ${largest.vertices} the segmentation stage takes ${share(t.segmentation)} of the ` +
          'encoder\'s time (it also holds the cluster count\'s search and the motion refinement; its heat-diffusion ' +
          'eigenpairs, two sparse LDLᵀ factorizations and a Lanczos iteration, run on one core), ' +
          `the rate control ${share(t.rate_control)}; the encoder's peak is ` +
          `${(largest.peak_rss_kb.encode * 1024 / (largest.vertices * largest.frames)).toFixed(0)} bytes per ` +
          'vertex-frame (the frames themselves are 12' +
          `${largest.peak_reset === false ? '; the peak could not be reset after building the frames: it includes that' : ''}).`);
    print();
  }
  print(`### Against F (V ≈ ${plan.fixedVertices})`);
  print();
  table(result.byFrames);
  growth(result.byFrames, (p) => p.frames, 'against F');

  const timeSeries = (points, x) => [
    ['encode (whole)', (p) => p.milliseconds.encode], ['segmentation', (p) => p.milliseconds.segmentation],
    ['rate control', (p) => p.milliseconds.rate_control], ['motion, prediction, entropy', (p) => p.milliseconds.motion + p.milliseconds.prediction + p.milliseconds.entropy],
    ['Draco base mesh', (p) => p.milliseconds.draco], ['decode', (p) => p.milliseconds.decode], ['copying the frames', (p) => p.milliseconds.copy],
  ].map(([name, y]) => ({ name, points: points.map((p) => [x(p), y(p) / 1000]) }));
  const memorySeries = (points, x) => [
    ['encoder peak', (p) => p.peak_rss_kb.encode], ['decoder peak', (p) => p.peak_rss_kb.decode], ['the frames, V × F × 3 floats', (p) => p.input_mb * 1e6 / 1024],
  ].map(([name, y]) => ({ name, points: points.map((p) => [x(p), y(p) / 1024]) }));
  const size = { width: 720, height: 380, legendWidth: 250 };
  charts.set('scaling.svg', panels([
    lineChart({ ...size, title: `Time against V (F = ${plan.fixedFrames})`, x: { label: 'vertices', log: true }, y: { label: 'seconds', log: true }, series: timeSeries(result.byVertices, (p) => p.vertices) }),
    lineChart({ ...size, title: `Peak memory against V (F = ${plan.fixedFrames})`, x: { label: 'vertices', log: true }, y: { label: 'MB', log: true }, series: memorySeries(result.byVertices, (p) => p.vertices) }),
    lineChart({ ...size, title: `Time against F (V ≈ ${plan.fixedVertices})`, x: { label: 'frames', log: true }, y: { label: 'seconds', log: true }, series: timeSeries(result.byFrames, (p) => p.frames) }),
    lineChart({ ...size, title: `Peak memory against F (V ≈ ${plan.fixedVertices})`, x: { label: 'frames', log: true }, y: { label: 'MB', log: true }, series: memorySeries(result.byFrames, (p) => p.frames) }),
  ], 2));
  print(`![time and memory against V and F](${charts.link('scaling.svg')})`);
  print();
}

// Values over files: "median 2.1× (0.5× to 19×)", each value written by `text` (a ratio by default).
const ratioText = (v) => `${v.toFixed(v < 10 ? 2 : 1)}×`;
function spread(values, text = ratioText) {
  const sorted = [...values].sort((a, b) => a - b);
  const median = sorted.length % 2 ? sorted[(sorted.length - 1) / 2] : (sorted[sorted.length / 2 - 1] + sorted[sorted.length / 2]) / 2;
  return `median ${text(median)} (${text(sorted[0])} to ${text(sorted[sorted.length - 1])})`;
}

// The rate-distortion lines of the summary: segmorph against each anchor at its KG, the bytes counted after
// brotli, then raw; the sequences against gltfpack's better mode and against raw floats; what brotli takes off.
function rdSummary(rd, print) {
  const raw = DELIVERIES.find((d) => d.key === 'raw');
  // The least bytes the runs of `families` need at the KG of segmorph's --error `target` over segmorph's, for one
  // file; null when segmorph failed or leastBytesAt has no answer.
  const ratioAt = (file, target, families, delivery) => {
    const runs = ok(file.runs);
    const seg = segmorphAt(runs, target);
    const at = seg && leastBytesAt(seg.kg, runs.filter((r) => families.includes(r.family)), delivery);
    return at ? at.bytes / seg.bytes[delivery] : null;
  };
  for (const target of [0.5, 0.15]) {
    for (const delivery of [HEADLINE, raw]) {
      const cells = ANCHORS.map((family) => {
        const ratios = rd.files.map((file) => ratioAt(file, target, [family], delivery.key)).filter((x) => x !== null);
        const smaller = ratios.filter((x) => x > 1).length;
        return ratios.length ? `${family}: smaller on ${smaller} of ${ratios.length} files, its bytes / segmorph's ${spread(ratios)}`
                             : `${family}: nothing to compare`;
      });
      const bytes = delivery === raw ? 'raw bytes, as written' : `bytes after \`${delivery.name}\``;
      print(`- segmorph \`--error ${target}\` against each anchor at equal or lower KG, ${bytes} (files where the anchor has ` +
            `settings on both sides of segmorph's KG): ${cells.join('; ')}.`);
    }
  }

  const sequences = rd.files.filter((f) => f.label.startsWith('sequences/'));
  if (sequences.length === 0) return;
  const name = (file) => path.basename(file.label);
  for (const target of [0.5, 0.15]) {
    const cells = sequences.map((file) => {
      const ratios = DELIVERIES.map((d) => ratioAt(file, target, GLTFPACK, d.key));
      return `${name(file)} ${ratios.map((x) => (x === null ? '—' : ratioText(x))).join(' / ')}`;
    });
    print(`- The sequences at \`--error ${target}\`: gltfpack's least bytes at segmorph's KG, the better of ` +
          `${GLTFPACK.join(' and ')}, over segmorph's, ${DELIVERY_LIST}: ${cells.join(', ')}.`);
  }
  const bake = sequences.map((file) => {
    const runs = ok(file.runs);
    const seg = segmorphAt(runs, 0.15), floats = runs.find((r) => r.family === BAKE);
    if (!seg || !floats) return null;
    return `${name(file)} ${DELIVERIES.map((d) => (floats.bytes[d.key] / seg.bytes[d.key]).toFixed(0)).join(' / ')}×`;
  }).filter(Boolean);
  if (bake.length) print(`- Against raw float morph targets at \`--error 0.15\`, ${DELIVERY_LIST}: ${bake.join(', ')} fewer bytes.`);
  const shrink = CODECS.map(({ family }) => {
    const runs = rd.files.flatMap((f) => ok(f.runs).filter((r) => r.family === family));
    const percent = (v) => `${Math.round(v) || 0} %`;  // no "-0 %" for a file brotli grows by a few bytes
    return runs.length ? `${family} ${spread(runs.map((r) => 100 * (1 - r.bytes[HEADLINE.key] / r.bytes.raw)), percent)}` : null;
  }).filter(Boolean);
  print(`- What \`${HEADLINE.name}\` takes off the file as written, over every run of every file: ${shrink.join('; ')}.`);
}

// The headline figures, computed from the tables below.
function summary(parts, lines) {
  const print = (line = '') => lines.push(line);
  print('## Summary');
  print();
  if (parts.rd) rdSummary(parts.rd, print);
  if (parts.speed) {
    const ratios = parts.speed.files.filter((f) => !f.result.failed).map((f) => f.result.encode.wall_ms / f.result.gltfpack.wall_ms);
    if (ratios.length) print(`- Encode time (whole command) over gltfpack's on the same file: ${spread(ratios)}.`);
    const decode = parts.speed.codec.filter((c) => !c.stages.failed && c.stages.DecodeWhole && c.stages.DecodeFrameCopyLimit)
      .map((c) => `${path.basename(c.label)} ${(c.stages.DecodeWhole.vfps / 1e6).toFixed(0)} M vf/s (copy ${(c.stages.DecodeFrameCopyLimit.vfps / 1e6).toFixed(0)} M)`);
    if (decode.length) print(`- Codec decode throughput, vertex-frames per second: ${decode.join(', ')}.`);
    const api = parts.speed.codec.filter((c) => !c.stages.failed && c.stages.DecodeWhole && c.stages.DecodeApiClips && c.stages.DecodeApiFrames)
      .map((c) => `${path.basename(c.label)} ${((c.stages.DecodeApiClips.ms / c.stages.DecodeWhole.ms - 1) * 100).toFixed(1)} % / ` +
                  `${((c.stages.DecodeApiFrames.ms / c.stages.DecodeWhole.ms - 1) * 100).toFixed(1)} %`);
    if (api.length) print(`- The runtime decoder's C API (whole clips / frame by frame) over the tool's decoder: ${api.join(', ')}.`);
  }
  const large = (parts.large?.files ?? []).filter((f) => !f.result.failed);
  if (large.length)
    print('- Large skinned files, segmorph encode / bake / gltfpack, wall time and peak memory: ' + large.map(({ label, result: m }) =>
      `${path.basename(label)} ${seconds(m.encode.wall_ms)} s ${mb(m.encode.max_rss_kb)} MB / ${seconds(m.bake.wall_ms)} s ` +
      `${mb(m.bake.max_rss_kb)} MB / ${seconds(m.gltfpack.wall_ms)} s ${mb(m.gltfpack.max_rss_kb)} MB`).join('; ') + '.');
  const web = (parts.browser?.inputs ?? []).filter((i) => !i.failed && i.segmorph.browser && i.gltfpack.browser);
  if (web.length) {
    const rate = LINKS_MBIT[0];
    const at = (f) => (f.brotli * 8) / (rate * 1e6) + f.browser.median / 1000;
    print(`- In Chromium, the first played frame over a ${rate} Mbit/s link (brotli bytes / rate + load): ` +
          web.map((i) => `${path.basename(i.label)} ${at(i.segmorph).toFixed(2)} s (gltfpack ${at(i.gltfpack).toFixed(2)} s)`).join(', ') + '.');
  }
  const gpu = parts.gpu;
  const played = (gpu?.inputs ?? []).filter((i) => i.playback);
  if (played.length) {
    const megabytes = (bytes) => (bytes / 1e6).toFixed(2);
    const torus = gpu.torus?.playback
      ? `; a ${gpu.torus.vertices.toLocaleString('en')} × ${gpu.torus.frames} cache ${megabytes(gpu.torus.playback.gpu.allocated)} MB ` +
        `(its morph targets would take ${megabytes(gpu.torus.morph_bytes_computed)} MB)` : '';
    print('- GPU bytes to play a sequence, the model on the GPU / its frames as morph targets / gltfpack\'s file: ' +
          played.map((i) => `${path.basename(i.label)} ${megabytes(i.playback.gpu.allocated)} / ` +
                            `${megabytes(i.playback.morph.allocated)} / ${megabytes(i.playback.gltfpack.allocated)} MB`).join(', ') +
          `${torus}.`);
  }
  const scaling = parts.scaling?.result;
  if (scaling && !scaling.failed && scaling.byVertices.length > 1) {
    const [a, z] = [scaling.byVertices[0], scaling.byVertices[scaling.byVertices.length - 1]];
    print(`- Scaling: ${z.vertices} vertices × ${z.frames} frames encode in ${seconds(z.milliseconds.encode)} s with a ` +
          `${mb(z.peak_rss_kb.encode)} MB peak (frames ${z.input_mb.toFixed(0)} MB) and decode in ${seconds(z.milliseconds.decode)} s; ` +
          `from ${a.vertices} vertices, encode time grows as V^${exponent(a, z, (p) => p.vertices, (p) => p.milliseconds.encode).toFixed(2)}.`);
  }
  print();
}

// Writes `doc` (markdown) and the charts into `chartDir`, linked from the doc by relative paths. `parts`:
// { rd, speed, scaling } (each optional: the saved results of that part), `command`: how to regenerate.
// Returns the flags (failures and targets missed).
export function writeReport({ parts, doc, chartDir, command, quick }) {
  mkdirSync(chartDir, { recursive: true });
  mkdirSync(path.dirname(doc), { recursive: true });
  const charts = new Map();
  charts.link = (name) => path.relative(path.dirname(doc), path.join(chartDir, name)).split(path.sep).join('/');
  const lines = [], flags = [];
  const print = (line = '') => lines.push(line);
  const anyMeta = parts.rd?.meta || parts.speed?.meta || parts.scaling?.meta || parts.large?.meta || parts.browser?.meta ||
                  parts.gpu?.meta;
  print('# Benchmarks');
  print();
  print(quick ? 'The quick mode of the harness (the test suite runs it): one file, two segmorph rates, one setting per ' +
                'anchor, tiny scaling points. Correctness only: these figures mean nothing about speed.'
              : 'segmorph against the tools its users would otherwise pick, on the same files, in one run: raw float morph ' +
                'targets, gltfpack and glTF-Transform; then speed, memory, and how the codec scales. Every figure on this ' +
                'page, and every chart, is written by the harness; nothing is edited by hand.');
  print();
  print('## How to regenerate');
  print();
  print('From the repository root, after `bash .ci/setup` (Debian packages; `npm ci --prefix tests/js` installs gltfpack ' +
        '1.3.0, @gltf-transform/cli 4.5.1, three and the Khronos validator at the versions tests/js/package-lock.json ' +
        'pins) and `.ci/build release`:');
  print();
  print('```sh');
  print(command);
  print('```');
  print();
  print('It writes every file and log under `out/bench/` (`results/*.json` hold the figures), then this page and ' +
        '`docs/bench/*.svg`. `--parts rd,speed,scaling,large,browser,gpu` runs some parts only (the page is rebuilt from the ' +
        'saved results of all six); `--quick` is the test suite\'s small run (ctest `bench_quick`). Exit status 1 when a step fails ' +
        'or a segmorph file misses its error bound.');
  print();
  if (anyMeta) {
    print('## Where it ran');
    print();
    print(`- Machine: ${anyMeta.machine}. Other work shared the 2 cores while this ran (the load averages below), so ` +
          'times are upper bounds; CPU times are steadier than wall times.');
    // Each part names the revision it ran: the parts are saved, and can be run at different times.
    print(`- ${anyMeta.versions.join('; ')}.`);
    for (const [name, key] of [['Rate and distortion', 'rd'], ['Speed and memory', 'speed'], ['Scaling', 'scaling'],
                               ['Large skinned files', 'large'], ['In the browser', 'browser'],
                               ['Playing on the GPU', 'gpu']])
      if (parts[key]) print(metaLine(name, parts[key].meta));
    print();
  }
  summary(parts, lines);
  if (parts.rd) rateDistortion(parts.rd, charts, lines, flags);
  const shapes = new Map((parts.rd?.files ?? []).map((f) => [f.label, f.shape]));
  if (parts.speed) speedAndMemory(parts.speed, shapes, charts, lines, flags);
  if (parts.scaling) scalingPart(parts.scaling, charts, lines, flags);
  if (parts.large) largePart(parts.large, lines, flags);
  if (parts.browser) browserPart(parts.browser, lines, flags);
  if (parts.gpu) gpuPart(parts.gpu, lines, flags);
  print('## Flags');
  print();
  print('Failed steps and segmorph files above their error bound (the harness exits with 1 when there is one).');
  print();
  if (flags.length === 0) print('None.');
  for (const flag of flags) print(`- ${flag}`);
  print();
  for (const [name, svg] of charts) writeFileSync(path.join(chartDir, name), svg);
  writeFileSync(doc, lines.join('\n'));
  return { flags, charts: [...charts.keys()] };
}
