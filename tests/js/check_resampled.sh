#!/usr/bin/env bash
# Checks that `segmorph verify` samples a file another tool resampled (gltfpack's default -af 30) at the
# original's frame times as an independent three.js playback does (resampled_three.mjs).
#   check_resampled.sh SEGMORPH WORKDIR SHARED_SAMPLES_DIR
# For RobotExpressive (7 animated primitives in 7 nodes: 4 skinned, 3 morphed under animated joints),
# CesiumMan and Fox (skinned, one primitive each) and MorphStressTest (one mesh of 2 morphed primitives),
# from SHARED_SAMPLES_DIR/gltf: gltfpack 1.3 -c with its default animation settings (every track
# resampled at 30 Hz), and with -af 0 (keys kept) as the control; meshopt_decode.mjs; then
# `SEGMORPH verify -q ORIGINAL OTHER --json` and `node resampled_three.mjs ORIGINAL OTHER --json`, the latter
# twice: with --normalize-rotations (verify normalizes rotation keys; gltfpack's are int16 and off unit
# length by up to 2.6e-5) and as three renders them. Every primitive verify reports must be measured by
# three.js with the same frame count, and the KG errors (per primitive and worst) must agree within:
#   normalized rotations: 0.1 % relative or 1e-4 percentage points, whichever is larger (measured: at
#     most 0.005 % relative and 6e-5 pp; the rest is verify's float32 frames against three's doubles);
#   as three renders:     5 % relative or 0.002 percentage points (measured: at most 2.4 % / 3.4e-4 pp,
#     Fox -af 0, where the non-unit quaternions add ~0.003 pp in quadrature to a KG of 0.014 %).
# A wrong frame time, a wrapped last key, a dropped track or a wrong pairing moves KG by far more: on
# RobotExpressive -af 30, verify at 30 fps measures 0.46 % and at its key times 6.10 %.
# Exit status: 0 when all agree, or when SHARED_SAMPLES_DIR/gltf is absent (skipped, with a message);
# 1 when any disagree or a step fails (tests/js/node_modules missing included); 2 on bad usage.
set -u
if [ $# -ne 3 ]; then
  echo "usage: check_resampled.sh SEGMORPH WORKDIR SHARED_SAMPLES_DIR" >&2
  exit 2
fi
segmorph=$1 work=$2 shared=$3
here=$(cd "$(dirname "$0")" && pwd)

if [ ! -d "$shared/gltf" ]; then
  echo "check_resampled: skip: $shared/gltf is absent (the shared samples are not installed)"
  exit 0
fi
if [ ! -d "$here/node_modules/three" ] || [ ! -d "$here/node_modules/gltfpack" ]; then
  echo "check_resampled: tests/js/node_modules is missing; run: npm ci --prefix tests/js" >&2
  exit 1
fi

now_ms() { date +%s%3N; }

# Compares verify's report with the two three.js reports; prints one line per primitive and the worst,
# exit status 1 on disagreement.
compare_reports() {
  node - "$@" <<'EOF'
const fs = require('fs');
const [label, verifyFile, normFile, renderFile] = process.argv.slice(2);
const read = (f) => JSON.parse(fs.readFileSync(f, 'utf8'));
const verify = read(verifyFile);
const three = { norm: read(normFile), render: read(renderFile) };
const TOLERANCE = { norm: { rel: 0.001, abs: 0.0001 }, render: { rel: 0.05, abs: 0.002 } };
const problems = [];
const agree = (a, b, t) => Math.abs(a - b) <= Math.max(t.rel * Math.abs(a), t.abs);
const check = (what, v, key) => {
  const x = key.kg_percent;
  if (!agree(v, x, TOLERANCE[key.mode])) problems.push(`${what}: verify ${v} vs three (${key.mode}) ${x}`);
};
const fmt = (x) => (x === undefined || x === null ? '-' : Number(x).toPrecision(5));
const rel = (a, b) => (a > 0 ? `${((100 * (b - a)) / a).toFixed(3)}%` : '-');
for (const p of verify.primitives) {
  const find = (r) => r.primitives.find((q) => q.node === p.node && q.primitive === p.primitive);
  const n = find(three.norm);
  const r = find(three.render);
  const what = `${label} node ${p.node} ${p.node_name} primitive ${p.primitive}`;
  if (!n || !r || n.error || r.error) {
    problems.push(`${what}: three.js did not measure it${n && n.error ? ` (${n.error})` : ''}`);
    continue;
  }
  if (n.frames !== p.frames) problems.push(`${what}: ${p.frames} frames in verify, ${n.frames} in three.js`);
  check(what, p.kg_percent, { mode: 'norm', kg_percent: n.kg_percent });
  check(what, p.kg_percent, { mode: 'render', kg_percent: r.kg_percent });
  console.log(
    `${label.padEnd(26)} ${String(p.node).padStart(3)} ${(p.node_name || '-').padEnd(8)} p${p.primitive} ${String(p.frames).padStart(4)} fr  ` +
      `verify ${fmt(p.kg_percent).padStart(8)}  three ${fmt(n.kg_percent).padStart(8)} (${rel(p.kg_percent, n.kg_percent).padStart(8)})  ` +
      `as rendered ${fmt(r.kg_percent).padStart(8)} (${rel(p.kg_percent, r.kg_percent).padStart(8)})  world ${fmt(r.kg_percent_world)}  ` +
      `-> other n${n.other.node}/p${n.other.primitive} ${n.other.vertices} v`,
  );
}
for (const [mode, report] of Object.entries(three)) {
  for (const q of report.primitives) {
    if (!verify.primitives.some((p) => p.node === q.node && p.primitive === q.primitive)) problems.push(`${label}: three.js (${mode}) measures node ${q.node} primitive ${q.primitive}, verify does not`);
  }
  check(`${label} worst`, verify.kg_percent, { mode, kg_percent: report.kg_percent });
}
console.log(`${label.padEnd(26)} worst: verify ${fmt(verify.kg_percent)}  three ${fmt(three.norm.kg_percent)}  as rendered ${fmt(three.render.kg_percent)}`);
for (const p of problems) console.log(`DISAGREE ${p}`);
process.exit(problems.length ? 1 : 0);
EOF
}

rm -rf "$work" && mkdir -p "$work"
failures=0 checked=0
for sample in RobotExpressive/RobotExpressive.glb CesiumMan/CesiumMan.glb Fox/Fox.glb MorphStressTest/morph-stress-test.glb; do
  input="$shared/gltf/$sample"
  if [ ! -f "$input" ]; then
    echo "check_resampled: $input is absent, skipped"
    continue
  fi
  name=$(basename "${sample%.*}")
  for mode in af30 af0; do
    options="-c"
    [ "$mode" = af0 ] && options="-c -af 0"
    packed="$work/$name.$mode.glb" plain="$work/$name.$mode.decoded.glb" label="$name $mode"
    t0=$(now_ms)
    # shellcheck disable=SC2086  # options is a word list
    if ! node "$here/node_modules/gltfpack/cli.js" -i "$input" -o "$packed" $options >"$work/$name.$mode.gltfpack.log" 2>&1 ||
       ! node "$here/meshopt_decode.mjs" "$packed" "$plain"; then
      echo "FAIL $label: gltfpack or meshopt_decode (see $work/$name.$mode.gltfpack.log)"; failures=$((failures + 1)); continue
    fi
    t1=$(now_ms)
    if ! "$segmorph" verify -q "$input" "$plain" --json >"$work/$name.$mode.verify.json"; then
      echo "FAIL $label: segmorph verify"; failures=$((failures + 1)); continue
    fi
    t2=$(now_ms)
    if ! node "$here/resampled_three.mjs" "$input" "$plain" --json --normalize-rotations >"$work/$name.$mode.three.json"; then
      echo "FAIL $label: resampled_three.mjs --normalize-rotations"; failures=$((failures + 1)); continue
    fi
    t3=$(now_ms)
    if ! node "$here/resampled_three.mjs" "$input" "$plain" --json >"$work/$name.$mode.three-rendered.json"; then
      echo "FAIL $label: resampled_three.mjs"; failures=$((failures + 1)); continue
    fi
    t4=$(now_ms)
    checked=$((checked + 1))
    compare_reports "$label" "$work/$name.$mode.verify.json" "$work/$name.$mode.three.json" "$work/$name.$mode.three-rendered.json" ||
      failures=$((failures + 1))
    echo "$label: gltfpack+decode $((t1 - t0)) ms, verify $((t2 - t1)) ms, three.js $((t3 - t2)) ms (+ $((t4 - t3)) ms as rendered)"
  done
done
echo "check_resampled: $checked comparisons, $failures failed"
[ "$checked" -gt 0 ] && [ "$failures" = 0 ]
