#!/usr/bin/env node
// The tables of bench/compare_gltfpack.sh: reads OUTDIR/results.tsv and the verify reports it names, prints
// markdown on stdout.
//
//   node bench/compare_gltfpack.mjs OUTDIR
//
// Versions, machine and revision come from the environment (SEGMORPH_VERSION, GLTFPACK_VERSION,
// NODE_VERSION, MACHINE, REVISION). Exit status: 0 when every run produced its numbers, every KG is within
// the requested bound, the decoded file measures as the encoded one and the validator found no error;
// 1 otherwise; 2 on bad usage.
//
// "Smaller at equal or lower KG": segmorph's file against the least bytes gltfpack needs for a KG no higher
// than segmorph's, interpolated linearly in log KG between its -vp settings as ../shared/samples/README.md's
// reference figures are read (leastBytesAt in lib/rate_distortion.mjs says how the ends and settings that another beats are handled);
// "n/a" when segmorph's KG is above every gltfpack file's: there is no gltfpack file at equal or higher KG
// to be smaller than.

import { readFileSync } from 'node:fs';
import path from 'node:path';
import { readAsset } from '../tests/js/glb.mjs';
import { leastBytesAt } from './lib/rate_distortion.mjs';

if (process.argv.length !== 3) {
  console.error('usage: node bench/compare_gltfpack.mjs OUTDIR');
  process.exit(2);
}
const out = process.argv[2];
const TABLE_VP = ['-vp 10', '-vp 12', '-vp 14'];

const lines = readFileSync(path.join(out, 'results.tsv'), 'utf8').trim().split('\n');
const header = lines.shift().split('\t');
const readReport = (name) => (name ? JSON.parse(readFileSync(path.join(out, name), 'utf8')) : null);
// Bytes of the images a glTF file embeds (bufferViews named by images).
async function imageBytes(file) {
  const { json } = await readAsset(file);
  return (json.images || []).reduce((sum, image) =>
    sum + (image.bufferView === undefined ? 0 : json.bufferViews[image.bufferView].byteLength), 0);
}
const files = new Map(); // label -> { segmorph: [...], gltfpack: [...], shape }
for (const line of lines) {
  const row = Object.fromEntries(line.split('\t').map((value, i) => [header[i], value]));
  if (!files.has(row.file)) files.set(row.file, { segmorph: [], gltfpack: [], shape: null });
  const file = files.get(row.file);
  const report = readReport(row.verify);
  const encoded = readReport(row.encode);
  const run = {
    setting: row.setting,
    bound: row.bound === '' ? null : Number(row.bound),
    bytes: row.bytes === '' ? null : Number(row.bytes),
    imageBytes: row.bytes === '' ? null : await imageBytes(path.join(out, row.output)),
    streamBytes: encoded ? encoded.animation_bytes : null,
    dracoBytes: encoded ? encoded.draco_bytes : null,
    kg: report ? report.kg_percent : null,
    kgDecoded: row.verify_decoded ? readReport(row.verify_decoded).kg_percent : null,
    validateEncoded: row.validate_encoded,
    validateDecoded: row.validate_decoded,
  };
  if (report) file.shape = { vertices: report.vertices, frames: report.frames, vertexFrames: report.vertex_frames };
  file[row.tool].push(run);
}

const bpvf = (bytes, file) => (8 * bytes) / file.shape.vertexFrames;
const fixed = (x) => (x < 10 ? x.toFixed(3) : x < 100 ? x.toFixed(2) : x.toFixed(1));
const kgText = (kg) => (kg === null ? '—' : `${kg.toPrecision(3)} %`);
const cell = (run, file) =>
  run && run.bytes !== null && run.kg !== null && file.shape
    ? `${run.bytes} B · ${fixed(bpvf(run.bytes, file))} · ${kgText(run.kg)}`
    : 'failed';

const flags = [];
let failed = false;
const verdicts = new Map(); // label -> [{ run, at, smaller }]
for (const [label, file] of files) {
  const list = [];
  for (const run of file.segmorph) {
    if (run.bytes === null || run.kg === null || !file.shape) {
      flags.push(`${label}, segmorph ${run.setting}: encode, decode or verify failed (see its folder's logs)`);
      failed = true;
      list.push({ run, at: null, smaller: 'failed' });
      continue;
    }
    if (run.bound !== null && run.kg > run.bound) {
      flags.push(`${label}, segmorph ${run.setting}: KG ${run.kg} % is above the requested ${run.bound} %`);
      failed = true;
    }
    if (run.kgDecoded !== run.kg) {
      flags.push(`${label}, segmorph ${run.setting}: the decoded file measures KG ${run.kgDecoded} %, the encoded one ${run.kg} %`);
      failed = true;
    }
    for (const [what, result] of [['encoded', run.validateEncoded], ['decoded', run.validateDecoded]]) {
      if (!/^0 errors/.test(result)) {
        flags.push(`${label}, segmorph ${run.setting}: validator on the ${what} file: ${result || 'not run'}`);
        failed = true;
      }
    }
    const at = leastBytesAt(run.kg, file.gltfpack);
    const smaller = at === null ? 'n/a' : run.bytes < at.bytes ? 'yes' : 'no';
    if (smaller !== 'yes') flags.push(`${label}, segmorph ${run.setting}: ${smaller === 'no' ? 'not smaller than gltfpack at equal KG' : 'KG above gltfpack -vp 8\'s: nothing to compare with'}`);
    list.push({ run, at, smaller });
  }
  for (const run of file.gltfpack)
    if (run.bytes === null || run.kg === null) {
      flags.push(`${label}, gltfpack ${run.setting}: gltfpack, meshopt_decode or verify failed (see its folder's logs)`);
      failed = true;
    }
  verdicts.set(label, list);
}

const env = (name) => process.env[name] || 'unknown';
const print = (line = '') => process.stdout.write(line + '\n');
print(`Measured with ${env('SEGMORPH_VERSION')} (revision ${env('REVISION')}), ${env('GLTFPACK_VERSION')} (npm gltfpack, WASM) and Node.js ${env('NODE_VERSION')} on ${env('MACHINE')}.`);
print('Cells: whole-file bytes · bits per vertex per frame · KG error measured by `segmorph verify`.');
print();
const settings = [...new Set([...files.values()].flatMap((f) => f.segmorph.map((r) => r.setting)))];
print(`| file | V × F | ${settings.map((s) => `segmorph ${s === 'default' ? '(default)' : s}`).join(' | ')} | ${TABLE_VP.map((s) => `gltfpack ${s}`).join(' | ')} | segmorph smaller at equal or lower KG |`);
print(`|---|---|${settings.map(() => '---|').join('')}${TABLE_VP.map(() => '---|').join('')}---|`);
for (const [label, file] of files) {
  const shape = file.shape ? `${file.shape.vertices} × ${file.shape.frames}` : '—';
  const seg = settings.map((s) => cell(file.segmorph.find((r) => r.setting === s), file));
  const pack = TABLE_VP.map((s) => cell(file.gltfpack.find((r) => r.setting === s), file));
  const verdict = verdicts.get(label).map((v) => v.smaller).join(' / ');
  print(`| ${label} | ${shape} | ${seg.join(' | ')} | ${pack.join(' | ')} | ${verdict} |`);
}
print();
print('### At equal KG');
print();
print('The least bytes gltfpack needs for segmorph\'s KG or lower, interpolated in log KG between its -vp settings (8 to 16) ' +
      'that no other setting beats on both bytes and KG; ratio = gltfpack / segmorph.');
print();
print('| file | segmorph | bound | KG | segmorph bytes (bpvf) | gltfpack bytes (bpvf) at that KG | from | ratio | smaller |');
print('|---|---|---|---|---|---|---|---|---|');
for (const [label, file] of files)
  for (const { run, at, smaller } of verdicts.get(label)) {
    if (smaller === 'failed') {
      print(`| ${label} | ${run.setting} | ${run.bound ?? ''} % | failed | | | | | failed |`);
      continue;
    }
    const mark = run.bound !== null && run.kg > run.bound ? ' **(above)**' : '';
    const theirs = at ? `${Math.round(at.bytes)} (${fixed(bpvf(at.bytes, file))})` : '—';
    const ratio = at ? `${(at.bytes / run.bytes).toFixed(2)}×` : '—';
    const where = at ? at.where : `above -vp 8's KG (${kgText(file.gltfpack.find((r) => r.setting === '-vp 8')?.kg ?? null)})`;
    print(`| ${label} | ${run.setting} | ${run.bound} % | ${kgText(run.kg)}${mark} | ${run.bytes} (${fixed(bpvf(run.bytes, file))}) | ${theirs} | ${where} | ${ratio} | ${smaller} |`);
  }
print();
print('### Where the bytes go');
print();
print('segmorph at its default target: the SEGMORPH_animation_compression streams (frames and coded tracks), the Draco ' +
      'meshes (base meshes, kept skins, meshes that nodes move), the images the file carries (both tools copy them as ' +
      'they are), and the rest: JSON, meshes that nothing moves, inverse bind matrices, tracks the track stream does not ' +
      'hold (weights, CUBICSPLINE) and padding. Last columns: both files without their images, gltfpack at segmorph\'s ' +
      'KG as above.');
print();
print('| file | segmorph bytes | stream | Draco base | images | rest | segmorph without images | gltfpack without images |');
print('|---|---|---|---|---|---|---|---|');
for (const [label, file] of files) {
  const entry = verdicts.get(label).find((v) => v.run.setting === 'default');
  if (!entry || entry.smaller === 'failed') continue;
  const { run, at } = entry;
  const rest = run.bytes - run.streamBytes - run.dracoBytes - run.imageBytes;
  const packImages = file.gltfpack.find((r) => r.imageBytes !== null)?.imageBytes ?? 0;
  print(`| ${label} | ${run.bytes} | ${run.streamBytes} | ${run.dracoBytes} | ${run.imageBytes} | ${rest} | ` +
        `${run.bytes - run.imageBytes} | ${at ? Math.round(at.bytes - packImages) : '—'} |`);
}
print();
print('### gltfpack -cc -af 0 at every -vp');
print();
const levels = [...new Set([...files.values()].flatMap((f) => f.gltfpack.map((r) => r.setting)))];
print(`| file | ${levels.join(' | ')} |`);
print(`|---|${levels.map(() => '---|').join('')}`);
for (const [label, file] of files) {
  const cells = levels.map((s) => {
    const run = file.gltfpack.find((r) => r.setting === s);
    return run && run.bytes !== null && run.kg !== null && file.shape ? `${fixed(bpvf(run.bytes, file))} @ ${kgText(run.kg)}` : 'failed';
  });
  print(`| ${label} | ${cells.join(' | ')} |`);
}
print();
print('bpvf @ KG.');
print();
print('### Khronos glTF-Validator on segmorph\'s files');
print();
print(`| file | ${settings.map((s) => `${s}: encoded / decoded`).join(' | ')} |`);
print(`|---|${settings.map(() => '---|').join('')}`);
for (const [label, file] of files) {
  const cells = settings.map((s) => {
    const run = file.segmorph.find((r) => r.setting === s);
    return run ? `${run.validateEncoded || 'not run'} / ${run.validateDecoded || 'not run'}` : '—';
  });
  print(`| ${label} | ${cells.join(' | ')} |`);
}
print();
print('### Flags');
print();
if (flags.length === 0) print('None: every KG within its bound, segmorph smaller everywhere, no validator error.');
for (const flag of flags) print(`- ${flag}`);
process.exit(failed ? 1 : 0);
