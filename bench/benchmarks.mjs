#!/usr/bin/env node
// The benchmark harness: segmorph against raw float morph targets, gltfpack and glTF-Transform on every
// animated sample (rate and distortion), speed and memory per file, how the codec scales, large skinned files and
// the browser; then docs/benchmarks.md with its charts (docs/bench/*.svg).
//
//   node bench/benchmarks.mjs [--parts rd,speed,scaling,large,browser,gpu] [--build DIR] [--samples DIR] [--out DIR] [--doc FILE]
//   node bench/benchmarks.mjs --quick [--input FILE] [--build DIR] [--out DIR]
//
// --build    the Release build folder (default build/)
// --samples  ../shared/samples: every .glb/.gltf under its gltf/ and sequences/ that has an animation
// --out      where every file, log and result goes (default out/bench/, out/bench-quick/ with --quick);
//            OUT/results/PART.json keep each part's figures, so parts can be run one at a time
// --doc      the page to write (default docs/benchmarks.md; its charts go to docs/bench/)
// --parts    which parts to run (default all; --parts '' runs none); the page is always rebuilt from the saved
//            results of every part
// --quick    the test suite's run: one bundled file (samples/Fox/Fox.glb), two segmorph rates, one setting
//            per anchor, two tiny scaling points, three copies of the Fox as the large skinned file; the page goes
//            to OUT/benchmarks.md; then checks that every
//            output exists and every measured value is sane (no timing is judged)
// Progress on stderr. Exit status: 0 when every step ran and every segmorph file met its error bound; 1 when
// one did not (the page's Flags say which) or a tool is missing; 2 on bad usage.

import { existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { SWEEPS, sweepFile } from './lib/rate_distortion.mjs';
import { writeReport } from './lib/report.mjs';
import { SCALING, measureScaling } from './lib/scaling.mjs';
import { LARGE, measureLarge } from './lib/large.mjs';
import { CORES, benchmarkCodec, measureFile } from './lib/speed.mjs';
import { measureBrowser } from './lib/browser.mjs';
import { GPU, measureGpu } from './lib/gpu.mjs';
import { StepError, Tools, buildSource, gltfFiles, machine, progress, revision } from './lib/tools.mjs';
import { checkQuick } from './lib/quick_checks.mjs';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const USAGE = 'usage: node bench/benchmarks.mjs [--quick [--input FILE]] [--parts rd,speed,scaling,large,browser,gpu] [--build DIR] ' +
              '[--samples DIR] [--out DIR] [--doc FILE]';
const PARTS = ['rd', 'speed', 'scaling', 'large', 'browser', 'gpu'];

function parseArguments(argv) {
  const options = { quick: false, parts: PARTS, build: path.join(root, 'build'),
                    samples: path.join(root, '..', 'shared', 'samples'), out: null, doc: null, input: null };
  for (let i = 0; i < argv.length; i++) {
    const arg = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) throw new StepError(`${arg} needs a value`);
      return argv[++i];
    };
    if (arg === '--quick') options.quick = true;
    else if (arg === '--parts') options.parts = value().split(',').filter((p) => p !== '');
    else if (arg === '--build') options.build = path.resolve(value());
    else if (arg === '--samples') options.samples = path.resolve(value());
    else if (arg === '--out') options.out = path.resolve(value());
    else if (arg === '--doc') options.doc = path.resolve(value());
    else if (arg === '--input') options.input = path.resolve(value());
    else if (arg === '-h' || arg === '--help') { console.log(USAGE); process.exit(0); }
    else throw new StepError(`unknown argument ${arg}`);
  }
  const unknown = options.parts.filter((p) => !PARTS.includes(p));
  if (unknown.length) throw new StepError(`unknown part ${unknown[0]} (${PARTS.join(', ')})`);
  options.out ??= path.join(root, 'out', options.quick ? 'bench-quick' : 'bench');
  options.doc ??= options.quick ? path.join(options.out, 'benchmarks.md') : path.join(root, 'docs', 'benchmarks.md');
  return options;
}

// The inputs: { label, file } for every animated glTF file (segmorph info lists an animated primitive).
function inputs(tools, options) {
  let files;
  if (options.quick) files = [options.input || path.join(root, 'samples', 'Fox', 'Fox.glb')];
  else {
    if (!existsSync(options.samples)) throw new StepError(`${options.samples} is absent: the full run measures ../shared/samples (--samples DIR)`);
    files = ['gltf', 'sequences'].flatMap((folder) => gltfFiles(path.join(options.samples, folder)));
  }
  const list = [];
  for (const file of files) {
    if (!existsSync(file)) throw new StepError(`${file} is absent`);
    const log = path.join(options.out, 'info.log');
    const info = tools.run(log, 'segmorph', ['info', '-q', file, '--json']);
    const label = path.relative(options.quick ? root : options.samples, file);
    if (!info.ok && /nothing animated/.test(Tools.tail(log))) { progress(`skip ${label}: nothing animated`); continue; }
    if (!info.ok) throw new StepError(`segmorph info ${file} failed: ${Tools.tail(log)}`);
    list.push({ label, file });
  }
  return list;
}

function meta(tools, started, load) {
  return {
    machine: machine(), revision: revision(buildSource(tools.build) ?? root), started: started.toISOString().replace(/\.\d+Z$/, 'Z'),
    minutes: (Date.now() - started.getTime()) / 60000, load: [load, os.loadavg()[0]],
    versions: [tools.version('segmorph', ['--version']), tools.version('gltfpack', ['-v']),
               `glTF-Transform ${tools.version('gltf_transform', ['--version'])}`, `Node.js ${process.version}`],
  };
}

async function runPart(name, options, tools, body) {
  const started = new Date(), load = os.loadavg()[0];
  progress(`${name}: started`);
  const result = await body();
  const saved = { meta: meta(tools, started, load), ...result };
  mkdirSync(path.join(options.out, 'results'), { recursive: true });
  writeFileSync(path.join(options.out, 'results', `${name}.json`), JSON.stringify(saved, null, 1));
  progress(`${name}: done in ${saved.meta.minutes.toFixed(1)} min`);
}

async function main() {
  const options = parseArguments(process.argv.slice(2));
  const tools = new Tools(root, options.build);
  tools.require('segmorph', 'run_measured', 'gltfpack', 'gltf_transform', 'meshopt_decode', 'three');
  if (options.parts.includes('speed')) tools.require('codec_benchmark');
  if (options.parts.includes('scaling')) tools.require('codec_scaling');
  if (options.quick) rmSync(options.out, { recursive: true, force: true });
  mkdirSync(options.out, { recursive: true });
  const mode = options.quick ? 'quick' : 'full';
  const files = options.parts.some((p) => p !== 'scaling' && p !== 'large') ? inputs(tools, options) : [];
  const folder = (part, index, label) => path.join(options.out, part, `${index + 1}-${path.basename(label).replace(/\.(glb|gltf)$/i, '')}`);

  if (options.parts.includes('rd'))
    await runPart('rd', options, tools, () => ({
      files: files.map(({ label, file }, i) => {
        progress(`rate-distortion ${i + 1}/${files.length}: ${label}`);
        return { label, ...sweepFile(tools, file, folder('rd', i, label), SWEEPS[mode]) };
      }),
    }));
  if (options.parts.includes('speed')) {
    const repeats = options.quick ? 1 : 3;
    await runPart('speed', options, tools, () => ({
      repeats,
      cores: CORES,
      files: files.map(({ label, file }, i) => {
        progress(`speed ${i + 1}/${files.length}: ${label}`);
        return { label, result: measureFile(tools, file, folder('speed', i, label), repeats) };
      }),
      codec: files.filter(({ label }) => options.quick || label.startsWith('sequences/')).map(({ label, file }, i) => {
        progress(`codec_benchmark: ${label}`);
        return { label, stages: benchmarkCodec(tools, file, folder('codec_benchmark', i, label), options.quick) };
      }),
    }));
  }
  if (options.parts.includes('scaling'))
    await runPart('scaling', options, tools, () => ({ plan: SCALING[mode], result: measureScaling(tools, path.join(options.out, 'scaling'), SCALING[mode]) }));

  if (options.parts.includes('large')) {
    const samples = options.quick ? path.join(root, 'samples') : options.samples;
    if (!existsSync(samples)) throw new StepError(`${samples} is absent: the large part copies its skinned samples (--samples DIR)`);
    tools.require('codec_scaling');
    await runPart('large', options, tools, () => measureLarge(tools, samples, path.join(options.out, 'large'), LARGE[mode]));
  }

  if (options.parts.includes('browser')) {
    tools.require('three');
    const web = path.join(options.build, 'web', 'segmorph_decoder.wasm');
    if (!existsSync(web) && options.quick) {
      // A build without the web package (the sanitizers' build): nothing to load in a browser.
      progress(`browser: skipped, ${web} is absent (a build without the WebAssembly decoder)`);
      rmSync(path.join(options.out, 'results', 'browser.json'), { force: true });
    } else {
      if (!existsSync(web)) throw new StepError(`${web} is missing; build it: .ci/build release (bash .ci/setup installs its toolchain)`);
      const sequences = files.filter(({ label }) => options.quick || label.startsWith('sequences/'));
      await runPart('browser', options, tools, () => measureBrowser(tools, sequences, path.join(options.out, 'browser'), options.quick));
    }
  }

  if (options.parts.includes('gpu')) {
    tools.require('three');
    tools.require('codec_scaling');
    const web = path.join(options.build, 'web', 'segmorph_decoder.wasm');
    if (!existsSync(web) && options.quick) {
      progress(`gpu: skipped, ${web} is absent (a build without the WebAssembly decoder)`);
      rmSync(path.join(options.out, 'results', 'gpu.json'), { force: true });
    } else {
      if (!existsSync(web)) throw new StepError(`${web} is missing; build it: .ci/build release (bash .ci/setup installs its toolchain)`);
      const sequences = files.filter(({ label }) => options.quick || label.startsWith('sequences/'));
      await runPart('gpu', options, tools, () => measureGpu(tools, sequences, path.join(options.out, 'gpu'), GPU[mode]));
    }
  }

  // The page, from whatever parts have results.
  const parts = {};
  for (const name of PARTS) {
    const file = path.join(options.out, 'results', `${name}.json`);
    if (existsSync(file)) parts[name] = JSON.parse(readFileSync(file, 'utf8'));
  }
  const chartDir = options.quick ? path.join(options.out, 'charts') : path.join(path.dirname(options.doc), 'bench');
  const { flags } = writeReport({ parts, doc: options.doc, chartDir, quick: options.quick,
                                  command: options.quick ? 'node bench/benchmarks.mjs --quick' : 'node bench/benchmarks.mjs' });
  progress(`wrote ${path.relative(process.cwd(), options.doc)} and its charts in ${path.relative(process.cwd(), chartDir)}`);
  let failed = flags.filter((f) => /failed|above the requested/.test(f));
  if (options.quick) failed = failed.concat(checkQuick(parts, options.doc, chartDir));
  for (const flag of failed) progress(`FAIL: ${flag}`);
  return failed.length === 0 ? 0 : 1;
}

try {
  process.exitCode = await main();
} catch (error) {
  if (!(error instanceof StepError)) throw error;
  console.error(`bench: ${error.message}`);
  process.exitCode = /needs a value|unknown (argument|part)/.test(error.message) ? 2 : 1;
}
