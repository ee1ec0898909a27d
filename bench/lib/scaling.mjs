// How the codec's time and memory grow with V (F fixed) and with F (V fixed): bench/codec_scaling, one process
// per point (its peak memory is the process's), with glibc's large buffers on transparent huge pages as the
// segmorph tool asks for itself (converter/cli/main.cpp).

import { mkdirSync } from 'node:fs';
import path from 'node:path';
import { progress } from './tools.mjs';

export const SCALING = {
  full: { vertices: [2000, 8000, 32000, 128000, 200000, 300000, 600000, 1000000], fixedFrames: 100,
          frames: [25, 50, 100, 200, 400], fixedVertices: 32000 },
  quick: { vertices: [500, 2000], fixedFrames: 10, frames: [5, 10], fixedVertices: 500 },
};

// GLIBC_TUNABLES with glibc.malloc.hugetlb=1 added to what the environment sets.
function hugePages() {
  const tunables = process.env.GLIBC_TUNABLES ?? '';
  if (tunables.includes('glibc.malloc.hugetlb')) return tunables;
  return tunables === '' ? 'glibc.malloc.hugetlb=1' : `${tunables}:glibc.malloc.hugetlb=1`;
}

// { byVertices: [point], byFrames: [point] } (codec_scaling's JSON objects), or { failed }.
export function measureScaling(tools, dir, plan) {
  mkdirSync(dir, { recursive: true });
  const measured = new Map();  // the point the two sweeps share is run once
  const point = (vertices, frames) => {
    const key = `${vertices}x${frames}`;
    if (!measured.has(key)) measured.set(key, run(vertices, frames));
    return measured.get(key);
  };
  const run = (vertices, frames) => {
    const started = Date.now();
    const result = tools.run(path.join(dir, `v${vertices}-f${frames}.log`), 'codec_scaling',
                             ['--vertices', String(vertices), '--frames', String(frames)],
                             { GLIBC_TUNABLES: hugePages() });
    if (!result.ok) throw new Error(`codec_scaling --vertices ${vertices} --frames ${frames} failed (${path.join(dir, `v${vertices}-f${frames}.log`)})`);
    progress(`  scaling: V ${vertices} × F ${frames}: ${((Date.now() - started) / 1000).toFixed(1)} s`);
    return JSON.parse(result.stdout);
  };
  try {
    return {
      byVertices: plan.vertices.map((v) => point(v, plan.fixedFrames)),
      byFrames: plan.frames.map((f) => point(plan.fixedVertices, f)),
    };
  } catch (error) {
    return { failed: error.message };
  }
}
