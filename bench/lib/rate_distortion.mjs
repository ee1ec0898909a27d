// The rate-distortion sweep of one input: segmorph at several rates, raw float morph targets (segmorph bake),
// gltfpack -cc and -cz and glTF-Transform (quantize, meshopt, draco) at several position precisions; every output
// measured by segmorph verify against the input (files with EXT_ or KHR_meshopt_compression after
// meshopt_decode.mjs: verify decodes neither; bytes are always those of the file the tool wrote, raw, after
// gzip -9 and after brotli -q 11).

import { mkdirSync } from 'node:fs';
import path from 'node:path';
import { Tools, deliveredBytes, progress } from './tools.mjs';

// What each codec is run at. `full`: the published sweep; `quick`: the test suite's (two segmorph rates, one
// setting per anchor).
export const SWEEPS = {
  full: {
    segmorph: [['--bpvf', 0.5], ['--bpvf', 1], ['--bpvf', 2], ['--bpvf', 4], ['--bpvf', 8],
               ['--error', 1], ['--error', 0.5], ['--error', 0.15], ['--error', 0.05]],
    gltfpackBits: [8, 9, 10, 11, 12, 13, 14, 15, 16],
    transformBits: [8, 10, 12, 14, 16],
  },
  quick: {
    segmorph: [['--error', 0.5], ['--bpvf', 4]],
    gltfpackBits: [12],
    transformBits: [12],
  },
};

// The codecs in chart and table order; `family` groups a codec's settings into one curve.
export const CODECS = [
  { family: 'segmorph --error', tool: 'segmorph' },
  { family: 'segmorph --bpvf', tool: 'segmorph' },
  { family: 'gltfpack -cc', tool: 'gltfpack' },
  { family: 'gltfpack -cz', tool: 'gltfpack' },
  { family: 'glTF-Transform meshopt', tool: 'gltf-transform' },
  { family: 'glTF-Transform quantize', tool: 'gltf-transform' },
  { family: 'glTF-Transform draco', tool: 'gltf-transform' },
  { family: 'raw float morph targets (bake)', tool: 'segmorph' },
];

// The bake run's family: the reference every table and chart draws beside the codecs.
export const BAKE = CODECS[CODECS.length - 1].family;

// gltfpack's two meshopt modes: -cc writes EXT_meshopt_compression (attribute codec version 0), -cz
// KHR_meshopt_compression (version 1). Both are lossless on the same quantized data.
export const GLTFPACK_MODES = [['-cc', CODECS[2].family], ['-cz', CODECS[3].family]];

// gltfpack -cc and -cz write the same quantized data through two lossless codecs, so at one -vp they must measure
// the same KG; else a file was misread or mispaired. One message per -vp where they do not.
export function gltfpackModesDisagree(runs) {
  const [[, cc], [, cz]] = GLTFPACK_MODES;
  const measured = runs.filter((r) => !r.failed);
  return measured.filter((r) => r.family === cz).flatMap((z) => {
    const c = measured.find((r) => r.family === cc && r.setting === z.setting);
    return c && c.kg !== z.kg ? [`${cz} ${z.setting}: KG ${z.kg} %, ${cc}'s ${c.kg} %: the meshopt codecs are lossless`] : [];
  });
}

// Runs every setting of `sweep` on `input`, writing into `dir`. Returns
// { shape: { vertices, frames, vertex_frames }, runs: [run] }, run = { family, setting, bound, file,
// bytes: { raw, gzip, brotli }, kg, rmse, max, wall_ms, max_rss_kb, encode (segmorph's encode JSON),
// failed (a message) }.
export function sweepFile(tools, input, dir, sweep) {
  mkdirSync(dir, { recursive: true });
  const runs = [];
  let shape = null;
  const local = (name) => path.join(dir, name);

  // Measures `measured` (the file verify reads) and records `written`'s bytes.
  const record = (family, setting, written, measured, time, extra = {}) => {
    const report = tools.verify(local(`${path.basename(written)}.verify.log`), input, measured);
    if (!report) return fail(family, setting, 'segmorph verify failed', `${path.basename(written)}.verify.log`);
    shape ??= { vertices: report.vertices, frames: report.frames, vertex_frames: report.vertex_frames };
    runs.push({ family, setting, file: path.basename(written), bytes: deliveredBytes(written),
                kg: report.kg_percent, rmse: report.rmse_over_diag, max: report.max_error_over_diag,
                wall_ms: time?.wall_ms ?? null, max_rss_kb: time?.max_rss_kb ?? null, ...extra });
  };
  const fail = (family, setting, what, log) => {
    progress(`  FAILED ${family} ${setting}: ${what} (see ${path.join(dir, log)})`);
    runs.push({ family, setting, failed: `${what} (${log})` });
  };

  // Raw float morph targets: the size every tool starts from.
  let step = tools.run(local('bake.log'), 'segmorph', ['bake', '-q', input, '-o', local('bake.glb')]);
  if (step.ok) record(BAKE, 'bake', local('bake.glb'), local('bake.glb'), step.time);
  else fail(BAKE, 'bake', 'segmorph bake failed', 'bake.log');

  for (const [option, value] of sweep.segmorph) {
    const name = `segmorph${option.replace('--', '-')}-${value}`;
    const family = option === '--error' ? CODECS[0].family : CODECS[1].family;
    step = tools.run(local(`${name}.log`), 'segmorph', ['encode', '-q', input, '-o', local(`${name}.glb`), option, String(value), '--json']);
    if (!step.ok) {
      // A rate below what the rest of the file (images, JSON, ...) takes alone is refused, and said why: a fact
      // about the file, not a failure.
      const why = Tools.tail(local(`${name}.log`));
      if (option === '--bpvf' && why.includes('is below what the rest of the file takes'))
        runs.push({ family, setting: `${option} ${value}`, target_bpvf: value, unreachable: why.replace(/^.*: --bpvf/, '--bpvf') });
      else fail(family, `${option} ${value}`, 'segmorph encode failed', `${name}.log`);
      continue;
    }
    const encode = JSON.parse(step.stdout.trim().split('\n').pop());
    record(family, `${option} ${value}`, local(`${name}.glb`), local(`${name}.glb`), step.time,
           { bound: option === '--error' ? value : null, target_bpvf: option === '--bpvf' ? value : null, encode });
  }
  progress(`  segmorph: ${sweep.segmorph.length} rates`);

  const meshoptDecoded = (family, setting, name, step) => {
    if (!step.ok) return fail(family, setting, `${family} failed`, `${name}.log`);
    const plain = tools.run(local(`${name}.plain.log`), 'meshopt_decode', [local(`${name}.glb`), local(`${name}.plain.glb`)]);
    if (!plain.ok) return fail(family, setting, 'meshopt_decode.mjs failed', `${name}.plain.log`);
    record(family, setting, local(`${name}.glb`), local(`${name}.plain.glb`), step.time);
  };
  for (const [mode, family] of GLTFPACK_MODES) {
    for (const bits of sweep.gltfpackBits) {
      const name = `gltfpack${mode}-vp${bits}`;
      step = tools.run(local(`${name}.log`), 'gltfpack', ['-i', input, '-o', local(`${name}.glb`), mode, '-af', '0', '-vp', String(bits)]);
      meshoptDecoded(family, `-vp ${bits}`, name, step);
    }
  }
  progress(`  gltfpack: ${GLTFPACK_MODES.map(([mode]) => mode).join(' and ')} at -vp ${sweep.gltfpackBits.join(', ')}`);

  for (const [mode, codec] of [['meshopt', CODECS[4]], ['quantize', CODECS[5]], ['draco', CODECS[6]]]) {
    for (const bits of sweep.transformBits) {
      const name = `gltf-transform-${mode}-${bits}`, setting = `${mode} ${bits} bits`;
      step = tools.run(local(`${name}.log`), 'gltf_transform', [mode, input, local(`${name}.glb`), '--quantize-position', String(bits)]);
      if (mode === 'meshopt') meshoptDecoded(codec.family, setting, name, step);
      else if (step.ok) record(codec.family, setting, local(`${name}.glb`), local(`${name}.glb`), step.time);
      else fail(codec.family, setting, `gltf-transform ${mode} failed`, `${name}.log`);
    }
  }
  progress(`  glTF-Transform: meshopt, quantize, draco at ${sweep.transformBits.join(', ')} position bits`);
  return { shape, runs };
}

// The least bytes a codec needs for a KG of at most `kg`, from its measured runs, counted as `delivery` says
// (a key of each run's bytes: raw, gzip or brotli): { bytes, where }, or null when `kg` is above the KG of every
// run (nothing at equal or higher error to compare with). Between two runs on the front (those no other run
// beats on both bytes and KG) the bytes are interpolated linearly in log KG, as ../shared/samples/README.md's
// reference figures are read; past the front's coarsest end they stay at its bytes (its KG is lower); below its
// finest KG they are the finest run's, whose KG is then higher.
export function leastBytesAt(kg, runs, delivery) {
  const measured = runs.filter((r) => r.kg > 0 && Number.isFinite(r.bytes?.[delivery]))
    .map((r) => ({ x: Math.log(r.kg), bytes: r.bytes[delivery], setting: r.setting }));
  if (measured.length === 0 || kg > Math.max(...measured.map((p) => Math.exp(p.x)))) return null;
  measured.sort((a, b) => a.x - b.x || a.bytes - b.bytes);
  const front = measured.filter((p, i) => measured.slice(0, i).every((q) => q.bytes > p.bytes));
  const x = Math.log(kg);
  const first = front[0], last = front[front.length - 1];
  if (x <= first.x) return { bytes: first.bytes, where: `${first.setting}, whose KG is higher` };
  if (x >= last.x) return { bytes: last.bytes, where: `${last.setting}, whose KG is lower` };
  for (let i = 1; i < front.length; i++) {
    if (x <= front[i].x) {
      const t = (x - front[i - 1].x) / (front[i].x - front[i - 1].x);
      return { bytes: front[i - 1].bytes + t * (front[i].bytes - front[i - 1].bytes),
               where: `between ${front[i].setting} and ${front[i - 1].setting}` };
    }
  }
  return null;  // not reached: x lies within the front
}
