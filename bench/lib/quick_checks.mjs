// The checks of the quick mode (ctest bench_quick): every part produced its outputs and every measured value
// is sane. Correctness only: no time is compared with anything.

import { existsSync, readFileSync } from 'node:fs';
import path from 'node:path';
import { BAKE, CODECS, gltfpackModesDisagree } from './rate_distortion.mjs';
import { DELIVERIES } from './tools.mjs';

const finite = (x) => typeof x === 'number' && Number.isFinite(x);

// Returns one message per problem found.
export function checkQuick(parts, doc, chartDir) {
  const problems = [];
  const expect = (condition, message) => { if (!condition) problems.push(message); };
  for (const name of ['rd', 'speed', 'scaling', 'large']) expect(parts[name], `no results for the ${name} part`);

  for (const file of parts.rd?.files ?? []) {
    expect(file.shape && file.shape.vertex_frames > 0, `${file.label}: no vertex-frame count`);
    for (const family of CODECS.map((c) => c.family))
      expect(file.runs.some((r) => r.family === family && !r.failed && !r.unreachable), `${file.label}: no measured ${family} file`);
    for (const r of file.runs) {
      const what = `${file.label}, ${r.family} ${r.setting}`;
      if (r.failed || r.unreachable) continue;  // a flag already, or a target segmorph refuses with a reason
      // Every count positive; gzip and brotli add at most a few bytes of framing to data they cannot shrink.
      const bytes = DELIVERIES.map((d) => r.bytes?.[d.key]);
      expect(bytes.every((b) => Number.isInteger(b) && b > 0 && b <= r.bytes?.raw + 1024),
             `${what}: bytes ${JSON.stringify(r.bytes)}`);
      expect(finite(r.kg) && r.kg >= 0 && finite(r.rmse) && finite(r.max), `${what}: KG ${r.kg}, RMSE ${r.rmse}, max ${r.max}`);
      expect(r.wall_ms > 0 && r.max_rss_kb > 0, `${what}: no time or memory measured`);
      if (r.bound) expect(r.kg <= r.bound, `${what}: KG ${r.kg} % above ${r.bound} %`);
      if (r.family === BAKE) expect(r.kg < 1e-3, `${what}: raw float morph targets measure KG ${r.kg} %`);
      else if (r.family.startsWith('segmorph')) expect(r.encode && r.encode.milliseconds, `${what}: no encode report`);
      else expect(r.kg < 5, `${what}: KG ${r.kg} %: a misread or mispaired file`);
    }
  }
  for (const file of parts.rd?.files ?? [])
    for (const message of gltfpackModesDisagree(file.runs)) problems.push(`${file.label}, ${message}`);
  for (const file of parts.speed?.files ?? []) {
    const m = file.result;
    expect(!m.failed, `${file.label}: ${m.failed}`);
    if (m.failed) continue;
    for (const [name, run] of Object.entries({ encode: m.encode, decode: m.decode, gltfpack: m.gltfpack }))
      expect(run.wall_ms > 0 && run.cpu_ms >= 0 && run.max_rss_kb > 0, `${file.label}: ${name} has no time or memory`);
    for (const stage of ['segmentation', 'motion', 'prediction', 'rate_control', 'entropy', 'draco'])
      expect(finite(m.encode.stages[stage]), `${file.label}: encode reports no ${stage} time`);
  }
  for (const { label, result: m } of parts.large?.files ?? []) {
    expect(!m.failed, `${label}: large: ${m.failed}`);
    if (m.failed) continue;
    for (const [name, run] of Object.entries({ encode: m.encode, bake: m.bake, gltfpack: m.gltfpack }))
      expect(run.wall_ms > 0 && run.cpu_ms >= 0 && run.max_rss_kb > 0, `${label}: large: ${name} has no time or memory`);
    expect(m.modes.kept_skin > 1 && m.vertex_frames > 0, `${label}: large: modes ${JSON.stringify(m.modes)}, ${m.vertex_frames} vertex-frames`);
    expect(m.encode.bytes.brotli > 0 && m.gltfpack.bytes.brotli > 0 && m.bake.bytes > m.input_bytes, `${label}: large: sizes`);
    expect(finite(m.encode.kg) && m.encode.kg > 0 && m.encode.kg <= 0.15, `${label}: large: encode KG ${m.encode.kg} %`);
  }
  for (const { vertices, frames, result: m } of parts.large?.sequences ?? []) {
    const what = `large: sequence ${vertices} × ${frames}`;
    expect(!m.failed, `${what}: ${m.failed}`);
    if (m.failed) continue;
    for (const name of ['bake', 'encode', 'decode', 'gltfpack'])
      expect(m[name].wall_ms > 0 && m[name].max_rss_kb > 0, `${what}: ${name} has no time or memory`);
    expect(m.encode.frames === frames && m.gltf_bytes > m.encode.bytes && m.encode.bytes > 0, `${what}: sizes or frames`);
    expect(finite(m.encode.kg) && m.encode.kg > 0 && m.encode.kg <= 0.15, `${what}: encode KG ${m.encode.kg} %`);
  }
  if (parts.large) expect(parts.large.sequences?.length > 0, 'large: no sequence measured');
  for (const { label, stages } of parts.speed?.codec ?? []) {
    expect(!stages.failed, `${label}: ${stages.failed}`);
    for (const name of ['EncodeWhole', 'DecodeWhole', 'DecodeApiClips', 'DecodeApiFrames', 'DecodeFrameCopyLimit'])
      expect(stages[name] && stages[name].vfps > 0, `${label}: codec_benchmark has no ${name} throughput`);
  }
  for (const input of parts.browser?.inputs ?? []) {
    expect(!input.failed, `${input.label}: browser: ${input.failed}`);
    for (const kind of ['segmorph', 'gltfpack'])
      expect(input[kind]?.brotli > 0 && input[kind]?.browser?.median > 0, `${input.label}: browser: no ${kind} bytes or load time`);
  }
  if (parts.browser) expect(parts.browser.inputs?.length > 0, 'browser: no input measured');
  const scaling = parts.scaling?.result;
  expect(scaling && !scaling.failed, `scaling: ${scaling?.failed}`);
  for (const p of [...(scaling?.byVertices ?? []), ...(scaling?.byFrames ?? [])]) {
    const what = `scaling V ${p.vertices} × F ${p.frames}`;
    expect(p.stream_bytes > 0 && finite(p.kg_percent) && p.kg_percent <= 0.15 * 1.01, `${what}: stream ${p.stream_bytes} B, KG ${p.kg_percent} %`);
    expect(p.peak_rss_kb.encode > 0 && p.milliseconds.encode > 0, `${what}: no time or memory`);
  }

  const page = existsSync(doc) ? readFileSync(doc, 'utf8') : '';
  expect(page.includes('## Rate and distortion'), `${doc} was not written`);
  for (const { name } of DELIVERIES.filter((d) => d.key !== 'raw')) expect(page.includes(`after \`${name}\``), `${doc} gives no bytes after ${name}`);
  for (const chart of ['stages.svg', 'scaling.svg', ...(parts.rd?.files ?? []).map((f) => `rd-${path.basename(f.label).replace(/\.(glb|gltf)$/i, '').toLowerCase().replace(/[^a-z0-9]+/g, '-')}.svg`)]) {
    const file = path.join(chartDir, chart);
    const text = existsSync(file) ? readFileSync(file, 'utf8') : '';
    expect(text.startsWith('<svg') && text.trimEnd().endsWith('</svg>') && !text.includes('NaN'), `${file}: missing or not a whole SVG`);
  }
  return problems;
}
