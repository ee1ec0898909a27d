// Speed and memory of one input: segmorph encode (per stage, from its --json) on every core and on one thread (the
// same bytes, checked) and decode, gltfpack on the same file in the same run, each repeated and the median wall time
// kept; and, for the sequences, Google Benchmark
// of the codec's stages (bench/codec_benchmark), whose decoder figures give the throughput in vertex-frames per
// second next to a plain copy of the restored frames.

import { mkdirSync, readFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { progress } from './tools.mjs';

export const STAGES = ['segmentation', 'motion', 'prediction', 'rate_control', 'entropy', 'draco', 'tracks', 'measure'];
// The encode's default thread count (every core: std::thread::hardware_concurrency, which counts the online
// processors as os.cpus does, whatever the affinity), which the speed part compares with one thread.
export const CORES = os.cpus().length;
export const SPEED_ERROR = 0.15;  // segmorph's default target
export const SPEED_GLTFPACK_BITS = 12;

const median = (values) => [...values].sort((a, b) => a - b)[Math.floor((values.length - 1) / 2)];

// Runs `args` `repeats` times; { ok, wall_ms and cpu_ms (user + system; medians), max_rss_kb (the largest),
// stdout (the run of median wall time) }. CPU time is the steadier figure on a machine shared with other work.
export function repeated(tools, log, command, args, repeats) {
  const results = [];
  for (let i = 0; i < repeats; i++) {
    const result = tools.run(`${log}.${i}`, command, args);
    if (!result.ok || !result.time) return { ok: false, log: `${log}.${i}` };
    results.push(result);
  }
  const wall = median(results.map((r) => r.time.wall_ms));
  const chosen = results.find((r) => r.time.wall_ms === wall);
  return { ok: true, wall_ms: wall, cpu_ms: median(results.map((r) => r.time.user_ms + r.time.sys_ms)),
           max_rss_kb: Math.max(...results.map((r) => r.time.max_rss_kb)), stdout: chosen.stdout };
}

const pick = ({ wall_ms, cpu_ms, max_rss_kb }) => ({ wall_ms, cpu_ms, max_rss_kb });

// { encode: { wall_ms, cpu_ms, max_rss_kb, stages: { name: ms }, bytes }, encode_one_thread: { the same },
//   decode: {...}, gltfpack: {...}, failed }
export function measureFile(tools, input, dir, repeats) {
  mkdirSync(dir, { recursive: true });
  const encoded = path.join(dir, 'encoded.glb');
  const encode = repeated(tools, path.join(dir, 'encode.log'), 'segmorph',
                          ['encode', '-q', input, '-o', encoded, '--error', String(SPEED_ERROR), '--json'], repeats);
  if (!encode.ok) return { failed: `segmorph encode failed (${encode.log})` };
  const report = JSON.parse(encode.stdout.trim().split('\n').pop());
  const single = path.join(dir, 'encoded-one-thread.glb');
  const one = repeated(tools, path.join(dir, 'encode-one-thread.log'), 'segmorph',
                       ['encode', '-q', input, '-o', single, '--error', String(SPEED_ERROR), '--json', '--threads', '1'],
                       repeats);
  if (!one.ok) return { failed: `segmorph encode --threads 1 failed (${one.log})` };
  if (!readFileSync(single).equals(readFileSync(encoded)))
    return { failed: `segmorph encode --threads 1 wrote other bytes than on ${CORES} threads (${single})` };
  const oneReport = JSON.parse(one.stdout.trim().split('\n').pop());
  const decode = repeated(tools, path.join(dir, 'decode.log'), 'segmorph',
                          ['decode', '-q', encoded, '-o', path.join(dir, 'decoded.glb')], repeats);
  if (!decode.ok) return { failed: `segmorph decode failed (${decode.log})` };
  const gltfpack = repeated(tools, path.join(dir, 'gltfpack.log'), 'gltfpack',
                            ['-i', input, '-o', path.join(dir, 'gltfpack.glb'), '-cc', '-af', '0', '-vp', String(SPEED_GLTFPACK_BITS)], repeats);
  if (!gltfpack.ok) return { failed: `gltfpack failed (${gltfpack.log})` };
  return {
    encode: { ...pick(encode), stages: report.milliseconds, bytes: report.bytes },
    encode_one_thread: { ...pick(one), stages: oneReport.milliseconds },
    decode: pick(decode),
    gltfpack: pick(gltfpack),
  };
}

// Google Benchmark of the codec's stages on the first animated primitive of `input`: { name: { ms (CPU time
// per iteration), vfps (vertex-frames per second, where the benchmark counts them) } }, or { failed }.
// `quick` runs each benchmark for the least time Google Benchmark allows (correctness, not timing).
export function benchmarkCodec(tools, input, dir, quick) {
  mkdirSync(dir, { recursive: true });
  const json = path.join(dir, 'codec_benchmark.json');
  const args = [input, '--error', String(SPEED_ERROR), `--benchmark_out=${json}`, '--benchmark_out_format=json'];
  if (quick) args.push('--benchmark_min_time=0.001', '--benchmark_filter=EncodeWhole|DecodeWhole|DecodeApiClips|DecodeApiFrames|DecodeFrameCopyLimit');
  const result = tools.run(path.join(dir, 'codec_benchmark.log'), 'codec_benchmark', args);
  if (!result.ok) return { failed: `codec_benchmark failed (${path.join(dir, 'codec_benchmark.log')})` };
  const stages = {};
  for (const b of JSON.parse(readFileSync(json, 'utf8')).benchmarks) {
    const scale = { ns: 1e-6, us: 1e-3, ms: 1, s: 1e3 }[b.time_unit];
    stages[b.name] = { ms: b.cpu_time * scale, vfps: b['vf/s'] ?? null };
  }
  progress(`  codec_benchmark: ${Object.keys(stages).length} benchmarks`);
  return stages;
}
