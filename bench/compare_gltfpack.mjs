#!/usr/bin/env node
// The tables of bench/compare_gltfpack.sh: reads OUTDIR/results.tsv and the verify reports it names, prints
// markdown on stdout.
//
//   node bench/compare_gltfpack.mjs OUTDIR
//
// Versions, machine and revision come from the environment (SEGMORPH_VERSION, GLTFPACK_VERSION,
// NODE_VERSION, MACHINE, REVISION). Exit status: 0 when every run produced its numbers, every KG is within
// the requested bound, the decoded file measures as the encoded one, gltfpack -cz measures as -cc at every -vp
// and the validator found no error; 1 otherwise; 2 on bad usage.
//
// Bytes: those of the files the tools wrote, raw, after gzip -9 and after brotli -q 11 (deliveredBytes in
// lib/tools.mjs), brotli's the headline: a web server sends glTF compressed, and gltfpack's meshopt codecs are
// made to be followed by a general-purpose compressor.
//
// "Smaller at equal or lower KG": segmorph's file against the least bytes gltfpack needs for a KG no higher
// than segmorph's, with -cc or -cz (the better of the two at each KG), after brotli, interpolated linearly in log
// KG between its -vp settings as ../shared/samples/README.md's reference figures are read (leastBytesAt in
// lib/rate_distortion.mjs says how the ends and settings that another beats are handled); "n/a" when segmorph's KG
// is above every gltfpack file's: there is no gltfpack file at equal or higher KG to be smaller than.

import { readFileSync } from 'node:fs';
import path from 'node:path';
import { readAsset } from '../tests/js/glb.mjs';
import { leastBytesAt } from './lib/rate_distortion.mjs';
import { DELIVERIES, deliveredBytes } from './lib/tools.mjs';

if (process.argv.length !== 3) {
  console.error('usage: node bench/compare_gltfpack.mjs OUTDIR');
  process.exit(2);
}
const out = process.argv[2];
const TABLE_VP = ['-vp 10', '-vp 12', '-vp 14'];
const MODES = ['-cc', '-cz'];  // gltfpack's EXT_meshopt_compression and KHR_meshopt_compression
const HEADLINE = DELIVERIES[0].key;

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
    mode: MODES.find((m) => row.setting.startsWith(`${m} `)) ?? null,
    bound: row.bound === '' ? null : Number(row.bound),
    bytes: row.bytes === '' ? null : deliveredBytes(path.join(out, row.output)),
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
const measured = (run, file) => run && run.bytes !== null && run.kg !== null && file.shape;
const cell = (run, file) =>
  measured(run, file) ? `${run.bytes[HEADLINE]} B · ${fixed(bpvf(run.bytes[HEADLINE], file))} · ${kgText(run.kg)}` : 'failed';
// gltfpack's least bytes for segmorph's KG or lower, counted as `delivery` says: leastBytesAt over both modes.
const gltfpackAt = (run, file, delivery) => leastBytesAt(run.kg, file.gltfpack, delivery);

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
    const at = gltfpackAt(run, file, HEADLINE);
    const smaller = at === null ? 'n/a' : run.bytes[HEADLINE] < at.bytes ? 'yes' : 'no';
    if (smaller !== 'yes') flags.push(`${label}, segmorph ${run.setting}: ${smaller === 'no' ? `not smaller than gltfpack at equal KG after ${DELIVERIES[0].name}` : 'KG above gltfpack -vp 8\'s: nothing to compare with'}`);
    list.push({ run, at, smaller });
  }
  for (const run of file.gltfpack) {
    if (run.bytes === null || run.kg === null) {
      flags.push(`${label}, gltfpack ${run.setting}: gltfpack, meshopt_decode or verify failed (see its folder's logs)`);
      failed = true;
    }
    // -cz and -cc are two lossless codecs on the same quantized data: the same KG, else a file was misread.
    const cc = run.mode === '-cz' && file.gltfpack.find((r) => r.setting === run.setting.replace('-cz', '-cc'));
    if (cc && run.kg !== null && cc.kg !== null && run.kg !== cc.kg) {
      flags.push(`${label}, gltfpack ${run.setting}: KG ${run.kg} %, ${cc.setting}'s ${cc.kg} %: the meshopt codecs are lossless`);
      failed = true;
    }
  }
  verdicts.set(label, list);
}

const env = (name) => process.env[name] || 'unknown';
const print = (line = '') => process.stdout.write(line + '\n');
const [brotli, gzip] = DELIVERIES.map((d) => d.name);
const ratio = (theirs, ours) => `${(theirs / ours).toFixed(2)}×`;
print(`Measured with ${env('SEGMORPH_VERSION')} (revision ${env('REVISION')}), ${env('GLTFPACK_VERSION')} (npm gltfpack, WASM) and Node.js ${env('NODE_VERSION')} on ${env('MACHINE')}.`);
print(`Cells: whole-file bytes after \`${brotli}\` · bits per vertex per frame of those bytes · KG error measured by \`segmorph verify\`. ` +
      `The raw bytes (the files as written) and those after \`${gzip}\` are in the tables below.`);
print();
const settings = [...new Set([...files.values()].flatMap((f) => f.segmorph.map((r) => r.setting)))];
const packSettings = MODES.flatMap((mode) => TABLE_VP.map((vp) => `${mode} ${vp}`));
print(`| file | V × F | ${settings.map((s) => `segmorph ${s === 'default' ? '(default)' : s}`).join(' | ')} | ${packSettings.map((s) => `gltfpack ${s}`).join(' | ')} | segmorph smaller at equal or lower KG, after \`${brotli}\` |`);
print(`|---|---|${settings.map(() => '---|').join('')}${packSettings.map(() => '---|').join('')}---|`);
for (const [label, file] of files) {
  const shape = file.shape ? `${file.shape.vertices} × ${file.shape.frames}` : '—';
  const seg = settings.map((s) => cell(file.segmorph.find((r) => r.setting === s), file));
  const pack = packSettings.map((s) => cell(file.gltfpack.find((r) => r.setting === s), file));
  const verdict = verdicts.get(label).map((v) => v.smaller).join(' / ');
  print(`| ${label} | ${shape} | ${seg.join(' | ')} | ${pack.join(' | ')} | ${verdict} |`);
}
print();
print('### At equal KG');
print();
print(`The least bytes gltfpack needs for segmorph's KG or lower, with -cc or -cz, whichever needs fewer: interpolated in log KG ` +
      'between its settings (-vp 8 to 16 in both modes) that no other setting beats on both bytes and KG, the bytes ' +
      `counted after \`${brotli}\` (the headline, and the "smaller" verdict), after \`${gzip}\` and raw, each on its own ` +
      `(so the settings it comes from may differ; "from" names those after \`${brotli}\`); ratio = gltfpack / segmorph.`);
print();
print(`| file | segmorph | bound | KG | segmorph ${brotli} (bpvf) | gltfpack ${brotli} (bpvf) at that KG | from | ratio ${brotli} | ` +
      `ratio ${gzip} | segmorph raw | gltfpack raw at that KG | ratio raw | smaller |`);
print('|---|---|---|---|---|---|---|---|---|---|---|---|---|');
for (const [label, file] of files)
  for (const { run, at, smaller } of verdicts.get(label)) {
    if (smaller === 'failed') {
      print(`| ${label} | ${run.setting} | ${run.bound ?? ''} % | failed | | | | | | | | | failed |`);
      continue;
    }
    const mark = run.bound !== null && run.kg > run.bound ? ' **(above)**' : '';
    const atGzip = gltfpackAt(run, file, 'gzip'), atRaw = gltfpackAt(run, file, 'raw');
    const theirs = at ? `${Math.round(at.bytes)} (${fixed(bpvf(at.bytes, file))})` : '—';
    const where = at ? at.where : `above -vp 8's KG (${kgText(file.gltfpack.find((r) => r.setting === '-cc -vp 8')?.kg ?? null)})`;
    print(`| ${label} | ${run.setting} | ${run.bound} % | ${kgText(run.kg)}${mark} | ${run.bytes[HEADLINE]} (${fixed(bpvf(run.bytes[HEADLINE], file))}) | ` +
          `${theirs} | ${where} | ${at ? ratio(at.bytes, run.bytes[HEADLINE]) : '—'} | ${atGzip ? ratio(atGzip.bytes, run.bytes.gzip) : '—'} | ` +
          `${run.bytes.raw} | ${atRaw ? Math.round(atRaw.bytes) : '—'} | ${atRaw ? ratio(atRaw.bytes, run.bytes.raw) : '—'} | ${smaller} |`);
  }
print();
print('### Where the bytes go');
print();
print('segmorph at its default target, raw bytes (the parts of a file, before any transfer compression): the ' +
      'SEGMORPH_animation_compression streams (frames and coded tracks), the Draco ' +
      'meshes (base meshes, kept skins, meshes that nodes move), the images the file carries (both tools copy them as ' +
      'they are), and the rest: JSON, meshes that nothing moves, inverse bind matrices, tracks the track stream does not ' +
      'hold (weights, CUBICSPLINE) and padding. Last columns: both files without their images, gltfpack at segmorph\'s ' +
      'KG as above (raw, the better of -cc and -cz).');
print();
print('| file | segmorph bytes | stream | Draco base | images | rest | segmorph without images | gltfpack without images |');
print('|---|---|---|---|---|---|---|---|');
for (const [label, file] of files) {
  const entry = verdicts.get(label).find((v) => v.run.setting === 'default');
  if (!entry || entry.smaller === 'failed') continue;
  const { run } = entry;
  const at = gltfpackAt(run, file, 'raw');
  const rest = run.bytes.raw - run.streamBytes - run.dracoBytes - run.imageBytes;
  const packImages = file.gltfpack.find((r) => r.imageBytes !== null)?.imageBytes ?? 0;
  print(`| ${label} | ${run.bytes.raw} | ${run.streamBytes} | ${run.dracoBytes} | ${run.imageBytes} | ${rest} | ` +
        `${run.bytes.raw - run.imageBytes} | ${at ? Math.round(at.bytes - packImages) : '—'} |`);
}
print();
const levels = [...new Set([...files.values()].flatMap((f) => f.gltfpack.map((r) => r.setting.replace(/^-c. /, ''))))];
for (const mode of MODES) {
  print(`### gltfpack ${mode} -af 0 at every -vp`);
  print();
  print(`| file | ${levels.join(' | ')} |`);
  print(`|---|${levels.map(() => '---|').join('')}`);
  for (const [label, file] of files) {
    const cells = levels.map((vp) => {
      const run = file.gltfpack.find((r) => r.setting === `${mode} ${vp}`);
      return measured(run, file) ? `${fixed(bpvf(run.bytes[HEADLINE], file))} (${fixed(bpvf(run.bytes.raw, file))}) @ ${kgText(run.kg)}` : 'failed';
    });
    print(`| ${label} | ${cells.join(' | ')} |`);
  }
  print();
}
print(`bpvf after \`${brotli}\` (raw) @ KG. -cz and -cc measure the same KG at each -vp (the Flags below say where not): ` +
      'the same quantized data through two lossless codecs.');
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
if (flags.length === 0) print(`None: every KG within its bound, -cz measuring as -cc, segmorph smaller everywhere after \`${brotli}\`, no validator error.`);
for (const flag of flags) print(`- ${flag}`);
process.exit(failed ? 1 : 0);
