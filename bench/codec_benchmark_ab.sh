#!/usr/bin/env bash
# Two builds' codec_benchmark side by side on the benchmark sequences, for a change's before/after figures:
#   bench/codec_benchmark_ab.sh BEFORE_BENCHMARK AFTER_BENCHMARK [ROUNDS] [FILTER] [-- codec_benchmark options]
# e.g. bench/codec_benchmark_ab.sh /tmp/old/build/bench/codec_benchmark build/bench/codec_benchmark 3 'Decode'
# Each round runs before, then after, on each sequence (../shared/samples/sequences), so that the machine's drift
# falls on both alike; per benchmark it prints the median CPU time of the rounds, each build's, their ratio
# (after / before) and after's vertex-frames per second. Release builds; one core each; an idle machine.
set -euo pipefail
before=$1 after=$2 rounds=${3:-3} filter=${4:-Decode}
shift $(( $# < 4 ? $# : 4 ))
[ "${1:-}" = "--" ] && shift
samples="$(cd "$(dirname "$0")/.." && pwd)/../shared/samples/sequences"
[ -d "$samples" ] || { echo "codec_benchmark_ab: no sequences at $samples" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for round in $(seq "$rounds"); do
  for file in "$samples"/*/*.glb; do
    name=$(basename "$file" .glb)
    for side in before after; do
      binary=$before
      [ "$side" = after ] && binary=$after
      "$binary" "$file" "$@" --benchmark_filter="$filter" --benchmark_format=json >"$out/$name.$side.$round.json" \
        2>/dev/null || true
    done
  done
done
node - "$out" "$rounds" <<'EOF'
const fs = require('fs');
const [dir, rounds] = [process.argv[2], Number(process.argv[3])];
const median = (x) => { const s = [...x].sort((a, b) => a - b); return s[Math.floor((s.length - 1) / 2)]; };
const runs = {};  // sequence -> benchmark -> CPU times of each side, after's vertex-frames per second
for (const file of fs.readdirSync(dir)) {
  const [name, side] = file.split('.');
  let report;
  try { report = JSON.parse(fs.readFileSync(`${dir}/${file}`, 'utf8')); } catch { continue; }
  for (const b of report.benchmarks ?? []) {
    const entry = ((runs[name] ??= {})[b.name] ??= {before: [], after: [], rate: []});
    entry[side].push(b.cpu_time);
    if (side === 'after' && b['vf/s'] !== undefined) entry.rate.push(b['vf/s']);
  }
}
console.log(`| sequence | benchmark | before CPU ms | after CPU ms | after / before | after vf/s |`);
console.log(`|---|---|---|---|---|---|`);
for (const [name, benchmarks] of Object.entries(runs))
  for (const [benchmark, e] of Object.entries(benchmarks)) {
    if (e.before.length !== rounds || e.after.length !== rounds) continue;
    const b = median(e.before), a = median(e.after);
    const rate = e.rate.length ? `${(median(e.rate) / 1e6).toFixed(1)} M` : '';
    console.log(`| ${name} | ${benchmark} | ${b.toFixed(2)} | ${a.toFixed(2)} | ${(a / b).toFixed(3)} | ${rate} |`);
  }
EOF
