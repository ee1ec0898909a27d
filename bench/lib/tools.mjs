// The programs the benchmarks run, found and run the same way for every tool: each run under run_measured
// (wall time, CPU time, peak resident memory), its output and errors kept in a log beside the files it writes,
// one progress line on stderr per step that takes long.

import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, readFileSync, writeFileSync, statSync, readdirSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';

// A step that could not run: the message is one line naming the file and what to do.
export class StepError extends Error {}

export function progress(message) {
  process.stderr.write(`bench: ${message}\n`);
}

export class Tools {
  // root: the repository; build: the CMake build folder (build/, Release).
  constructor(root, build) {
    const js = path.join(root, 'tests', 'js');
    this.root = root;
    this.build = build;
    this.paths = {
      segmorph: path.join(build, 'converter', 'segmorph'),
      run_measured: path.join(build, 'bench', 'run_measured'),
      codec_benchmark: path.join(build, 'bench', 'codec_benchmark'),
      codec_scaling: path.join(build, 'bench', 'codec_scaling'),
      gltfpack: path.join(js, 'node_modules', 'gltfpack', 'cli.js'),
      gltf_transform: path.join(js, 'node_modules', '@gltf-transform', 'cli', 'bin', 'cli.js'),
      meshopt_decode: path.join(js, 'meshopt_decode.mjs'),
      three: path.join(js, 'node_modules', 'three'),
    };
  }

  // Throws a StepError naming the first missing tool and how to get it.
  require(...names) {
    for (const name of names) {
      const file = this.paths[name];
      if (existsSync(file)) continue;
      const fix = ['segmorph', 'run_measured', 'codec_scaling'].includes(name) ? 'build it: .ci/build release'
        : name === 'codec_benchmark' ? 'install libbenchmark-dev (.ci/setup) and build: .ci/build release'
        : 'install the Node.js tools: npm ci --prefix tests/js (.ci/setup does it)';
      throw new StepError(`${file} is missing; ${fix}`);
    }
  }

  // Runs `command args` (command: a tool name of this.paths, or a program) under run_measured. Writes
  // LOG (stdout and stderr) and LOG's .time.json. Returns { ok, stdout, time: { wall_ms, user_ms, sys_ms,
  // max_rss_kb } }; never throws for a failing command (ok is false, the log says why). `env`: variables added to
  // the command's environment.
  run(log, command, args, env = {}) {
    const program = this.paths[command] || command;
    const argv = program.endsWith('.js') || program.endsWith('.mjs') ? [process.execPath, program, ...args] : [program, ...args];
    const timeFile = `${log}.time.json`;
    const result = spawnSync(this.paths.run_measured, [timeFile, '--', ...argv],
                             { encoding: 'utf8', maxBuffer: 1 << 28, cwd: this.root, env: { ...process.env, ...env } });
    const assignments = Object.entries(env).map(([name, value]) => `${name}=${value} `).join('');
    writeFileSync(log, `$ ${assignments}${argv.join(' ')}\n${result.stdout || ''}${result.stderr || ''}`);
    const time = existsSync(timeFile) ? JSON.parse(readFileSync(timeFile, 'utf8')) : null;
    return { ok: result.status === 0, stdout: result.stdout || '', time };
  }

  // The log of a run: what a failed step printed, for the error message.
  static tail(log) {
    return existsSync(log) ? readFileSync(log, 'utf8').trim().split('\n').pop() : '';
  }

  // segmorph verify ORIGINAL FILE --json, or null when it fails (the log says why).
  verify(log, original, file) {
    const result = this.run(log, 'segmorph', ['verify', '-q', original, file, '--json']);
    return result.ok ? JSON.parse(result.stdout) : null;
  }

  version(command, args) {
    const program = this.paths[command] || command;
    const argv = program.endsWith('.js') ? [process.execPath, program, ...args] : [program, ...args];
    const result = spawnSync(argv[0], argv.slice(1), { encoding: 'utf8' });
    return `${result.stdout || ''}${result.stderr || ''}`.trim().split('\n')[0];
  }
}

export const fileBytes = (file) => statSync(file).size;

// The ways a file reaches a web page, the headline first: what a web server sends after brotli or gzip (gltfpack's
// meshopt codecs are designed to be followed by one; segmorph's range-coded streams do not shrink further), and
// the file as written. Each names a key of deliveredBytes's answer and how the tables and captions say it.
export const DELIVERIES = [
  { key: 'brotli', name: 'brotli -q 11' },
  { key: 'gzip', name: 'gzip -9' },
  { key: 'raw', name: 'raw' },
];

// Bytes of `file` as a web server sends it: { raw, gzip, brotli } (Debian's gzip and brotli commands).
export function deliveredBytes(file) {
  const gzip = execFileSync('gzip', ['-9', '-c', file], { maxBuffer: 1 << 30 }).length;
  const brotli = execFileSync('brotli', ['-q', '11', '-c', file], { maxBuffer: 1 << 30 }).length;
  return { raw: fileBytes(file), gzip, brotli };
}

// The machine, in one line: processor, cores, memory, kernel, distribution.
export function machine() {
  const cpu = os.cpus()[0]?.model?.trim() || 'unknown processor';
  let distribution = '';
  if (existsSync('/etc/debian_version')) distribution = `, Debian ${readFileSync('/etc/debian_version', 'utf8').trim()}`;
  return `${cpu}, ${os.cpus().length} cores, ${(os.totalmem() / 2 ** 30).toFixed(0)} GiB, ${os.type()} ${os.release()}${distribution}`;
}

// The source tree `build` was configured from (its CMakeCache.txt's CMAKE_HOME_DIRECTORY), or null: the tree whose
// revision the binaries are, which is not the harness's when --build names a build of another checkout.
export function buildSource(build) {
  const cache = path.join(build, 'CMakeCache.txt');
  if (!existsSync(cache)) return null;
  return readFileSync(cache, 'utf8').match(/^CMAKE_HOME_DIRECTORY:INTERNAL=(.+)$/m)?.[1] ?? null;
}

// The git revision of `root`, with a note when the work tree has changes.
export function revision(root) {
  const head = spawnSync('git', ['-C', root, 'rev-parse', '--short', 'HEAD'], { encoding: 'utf8' }).stdout.trim();
  const dirty = spawnSync('git', ['-C', root, 'status', '--porcelain', '--untracked-files=no'], { encoding: 'utf8' }).stdout.trim();
  return head ? `${head}${dirty ? ' with uncommitted changes' : ''}` : 'unknown';
}

// Every .glb/.gltf below `folder`, sorted by path.
export function gltfFiles(folder) {
  const found = [];
  const walk = (dir) => {
    for (const entry of readdirSync(dir, { withFileTypes: true })) {
      const file = path.join(dir, entry.name);
      if (entry.isDirectory()) walk(file);
      else if (/\.(glb|gltf)$/i.test(entry.name)) found.push(file);
    }
  };
  walk(folder);
  return found.sort();
}
