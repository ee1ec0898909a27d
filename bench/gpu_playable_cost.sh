#!/usr/bin/env bash
# What --gpu-playable costs: every benchmark file (each .glb/.gltf under SAMPLES_DIR's gltf/ and sequences/ that has
# an animation) encoded at each --error target with and without it; bytes as a server sends them (brotli -q 11 and
# gzip -9 of the file), the measured KG of each, and per file its streams' versions and how many play on the GPU
# (segmorph info --json). One markdown table on standard output, the files in OUTDIR. With --bake, both encodes also
# get --targets bake --skins bake (every animated primitive then has a stream of clips, which --gpu-playable makes
# version 4; by default kept morph targets and kept skins are coded as without it).
#
#   bench/gpu_playable_cost.sh SEGMORPH OUTDIR SAMPLES_DIR [--bake] [ERROR...]     (default errors: 0.15 0.5)
#
# A file that --gpu-playable cannot encode (a primitive without a version-4 stream at the target) shows the
# encoder's message in the table. Exit status 0 when every encode ran, 1 otherwise, 2 on bad usage.
set -u
if [ $# -lt 3 ]; then
  echo "usage: bench/gpu_playable_cost.sh SEGMORPH OUTDIR SAMPLES_DIR [--bake] [ERROR...]" >&2
  exit 2
fi
segmorph=$1 out=$2 samples=$3
shift 3
common=()
if [ "${1:-}" = --bake ]; then
  common=(--targets bake --skins bake)
  shift
fi
errors=("$@")
[ ${#errors[@]} -eq 0 ] && errors=(0.15 0.5)
for tool in brotli gzip node; do
  command -v "$tool" >/dev/null || { echo "gpu_playable_cost: $tool is missing" >&2; exit 2; }
done
rm -rf "$out" && mkdir -p "$out"
status=0
# The stream versions of an encoded file and how many of its clip primitives play on the GPU: "v4 v4 (2/2 GPU)".
versions() {
  "$segmorph" info -q "$1" --json | node -e '
    let text = ""; process.stdin.on("data", (d) => (text += d)).on("end", () => {
      const p = JSON.parse(text).primitives.filter((x) => x.stream_version !== null);
      const gpu = p.filter((x) => x.gpu_playable).length;
      console.log(p.length ? `${p.map((x) => "v" + x.stream_version).join(" ")} (${gpu}/${p.length} GPU)` : "none");
    });'
}
echo "| file | --error | default: brotli / gzip bytes, KG %, streams | --gpu-playable: brotli / gzip bytes, KG %, streams | brotli cost |"
echo "|---|---|---|---|---|"
while read -r input; do
  name=$(basename "${input%.*}")
  for error in "${errors[@]}"; do
    row="| $name | $error |"
    sizes=()
    for variant in default gpu; do
      file="$out/$name.$error.$variant.glb"
      options=(--error "$error" "${common[@]}")
      [ "$variant" = gpu ] && options+=(--gpu-playable)
      if ! message=$("$segmorph" encode -q "$input" -o "$file" "${options[@]}" --json 2>&1 >"$file.json"); then
        if grep -q "nothing animated" <<<"$message"; then continue 3; fi
        row+=" ${message##*: } |"
        sizes+=("")
        [ "$variant" = gpu ] || status=1
        continue
      fi
      b=$(brotli -q 11 -c "$file" | wc -c) g=$(gzip -9 -n -c "$file" | wc -c)
      kg=$(node -e 'console.log(JSON.parse(require("fs").readFileSync(process.argv[1])).kg_percent.toFixed(4))' "$file.json")
      row+=" $b / $g, $kg, $(versions "$file") |"
      sizes+=("$b")
    done
    if [ -n "${sizes[0]}" ] && [ -n "${sizes[1]:-}" ]; then
      row+=" $(node -e 'const [a, b] = process.argv.slice(1).map(Number); console.log(`${b - a >= 0 ? "+" : ""}${b - a} B (${((b / a - 1) * 100).toFixed(1)} %)`)' "${sizes[0]}" "${sizes[1]}") |"
    else
      row+=" - |"
    fi
    echo "$row"
  done
done < <(find "$samples/gltf" "$samples/sequences" \( -name '*.glb' -o -name '*.gltf' \) | sort)
exit $status
