#!/usr/bin/env bash
# segmorph against gltfpack -cc and -cz on every animated sample: sizes (raw, after gzip -9 and after brotli -q 11),
# KG error, validator results, one page of tables.
#
#   bench/compare_gltfpack.sh SEGMORPH OUTDIR SAMPLES_DIR [DOC]
#
# SEGMORPH     the segmorph binary (build/converter/segmorph)
# OUTDIR       where the files go; emptied first. OUTDIR/comparison.md is the table, OUTDIR/results.tsv
#              one line per run, OUTDIR/<n>-<name>/ the files and logs of input n
# SAMPLES_DIR  ../shared/samples: every .glb/.gltf under its gltf/ and sequences/ is measured, then the
#              project's samples/ (a file with the same bytes as one already measured is skipped). Files with
#              nothing animated are skipped. Without SAMPLES_DIR (or when it is absent), samples/ only.
# DOC          optional: a markdown file whose part between the lines
#              "<!-- compare_gltfpack: begin -->" and "<!-- compare_gltfpack: end -->" is replaced by the table
#              (docs/comparison.md)
#
# Per file: segmorph encode at --error 0.5, --error 0.15 and the default target, decode, verify (KG of the
# encoded and of the decoded file), the Khronos validator on both; gltfpack 1.3 (tests/js/node_modules)
# -cc -af 0 and -cz -af 0 at -vp 8 to 16, its meshopt compression undone by tests/js/meshopt_decode.mjs (segmorph
# decodes neither EXT_meshopt_compression, which -cc writes, nor KHR_meshopt_compression, which -cz writes),
# verify. Bytes are those of the files the tools wrote: raw here, and after gzip -9 and brotli -q 11 (Debian's
# gzip and brotli commands) in compare_gltfpack.mjs, whose headline is brotli's. Needs the Node.js tools of
# tests/js: npm ci --prefix tests/js (.ci/setup does it).
# Exit status: 0 when every step ran, every KG is within the requested bound and the validator found no
# error; 1 otherwise (the table says where); 2 on bad usage.
set -u
if [ $# -lt 2 ] || [ $# -gt 4 ]; then
  echo "usage: bench/compare_gltfpack.sh SEGMORPH OUTDIR [SAMPLES_DIR] [DOC]" >&2
  exit 2
fi
segmorph=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
out=$2 shared=${3:-} doc=${4:-}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
js=$root/tests/js
gltfpack=(node "$js/node_modules/gltfpack/cli.js")
[ -x "$segmorph" ] || { echo "compare_gltfpack: $1 is not an executable" >&2; exit 2; }
for package in gltfpack three gltf-validator; do
  if [ ! -d "$js/node_modules/$package" ]; then
    echo "compare_gltfpack: tests/js/node_modules/$package is missing; run: npm ci --prefix tests/js" >&2
    exit 2
  fi
done
for program in gzip brotli; do
  command -v "$program" >/dev/null || { echo "compare_gltfpack: $program is missing; install it: apt-get install $program" >&2; exit 2; }
done
[ -z "$doc" ] || grep -q '^<!-- compare_gltfpack: begin -->$' "$doc" ||
  { echo "compare_gltfpack: $doc has no '<!-- compare_gltfpack: begin -->' line" >&2; exit 2; }

segmorph_settings=("--error 0.5" "--error 0.15" "")  # "" is the default target
default_error=$("$segmorph" --help | sed -n 's/.*--error E .*(default \([0-9.]*\)).*/\1/p')
vp_levels=(8 9 10 11 12 13 14 15 16)
gltfpack_modes=(-cc -cz)  # EXT_meshopt_compression, KHR_meshopt_compression (attribute codec version 1)

inputs=()
if [ -n "$shared" ] && [ -d "$shared" ]; then
  while IFS= read -r file; do inputs+=("$file"); done < <(find "$shared/gltf" "$shared/sequences" -name '*.glb' -o -name '*.gltf' | sort)
else
  echo "compare_gltfpack: no shared samples directory: measuring samples/ only"
fi
while IFS= read -r file; do inputs+=("$file"); done < <(find "$root/samples" -name '*.glb' -o -name '*.gltf' | sort)

rm -rf "$out" && mkdir -p "$out"
out=$(cd "$out" && pwd)
results=$out/results.tsv
printf 'file\ttool\tsetting\tbound\toutput\tbytes\tencode\tverify\tverify_decoded\tvalidate_encoded\tvalidate_decoded\n' >"$results"

# The summary line of the validator for one file ("0 errors, 2 warnings"), or "failed".
validate() {
  local line
  line=$(node "$js/validate.mjs" "$1" 2>&1 | head -n 1)
  case "$line" in *errors,*warnings) echo "${line##*: }" ;; *) echo "failed: $line" ;; esac
}
# verify --json, stored in $2; prints nothing. Failure leaves the error message in $2.err.
verify() {
  "$segmorph" verify -q "$1" "$3" --json >"$2" 2>"$2.err" || { rm -f "$2"; return 1; }
}
size() { stat -c %s "$1"; }

declare -A seen=()
index=0
for input in "${inputs[@]}"; do
  sum=$(sha256sum <"$input" | cut -d" " -f1)
  label=${input#"$root"/}
  [ -z "$shared" ] || label=${label#"$shared"/}
  if [ -n "${seen[$sum]:-}" ]; then
    echo "skip $label: same bytes as ${seen[$sum]}"
    continue
  fi
  if ! message=$("$segmorph" info -q "$input" 2>&1 >/dev/null); then
    echo "skip $label: $message"
    continue
  fi
  seen[$sum]=$label
  index=$((index + 1))
  name=$(basename "${input%.*}")
  dir=$out/$index-$name
  mkdir -p "$dir"
  echo "== $label"

  for setting in "${segmorph_settings[@]}"; do
    tag=${setting:-default}
    tag=${tag#--error }
    bound=${setting#--error }
    [ -n "$setting" ] || bound=$default_error
    encoded=$dir/segmorph-$tag.glb decoded=$dir/segmorph-$tag.decoded.glb
    bytes="" encode_report="" report="" report_decoded="" valid_encoded="" valid_decoded=""
    # shellcheck disable=SC2086  # $setting is two words or none
    if "$segmorph" encode -q "$input" -o "$encoded" $setting --json >"$dir/segmorph-$tag.encode.json" 2>"$dir/segmorph-$tag.log"; then
      bytes=$(size "$encoded") encode_report=$dir/segmorph-$tag.encode.json
      verify "$input" "$dir/segmorph-$tag.verify.json" "$encoded" && report=$dir/segmorph-$tag.verify.json
      valid_encoded=$(validate "$encoded")
      if "$segmorph" decode -q "$encoded" -o "$decoded" 2>>"$dir/segmorph-$tag.log"; then
        verify "$input" "$dir/segmorph-$tag.decoded.verify.json" "$decoded" && report_decoded=$dir/segmorph-$tag.decoded.verify.json
        valid_decoded=$(validate "$decoded")
      fi
    fi
    printf '%s\tsegmorph\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "${setting:-default}" "$bound" "${encoded#"$out"/}" \
      "$bytes" "${encode_report#"$out"/}" "${report#"$out"/}" "${report_decoded#"$out"/}" "$valid_encoded" "$valid_decoded" >>"$results"
    echo "   segmorph ${setting:-default}: ${bytes:-FAILED} bytes"
  done

  for mode in "${gltfpack_modes[@]}"; do
    for vp in "${vp_levels[@]}"; do
      name=gltfpack$mode-vp$vp
      packed=$dir/$name.glb plain=$dir/$name.plain.glb
      bytes="" report=""
      if "${gltfpack[@]}" -i "$input" -o "$packed" "$mode" -af 0 -vp "$vp" >"$dir/$name.log" 2>&1 &&
         node "$js/meshopt_decode.mjs" "$packed" "$plain" 2>>"$dir/$name.log"; then
        bytes=$(size "$packed")
        verify "$input" "$dir/$name.verify.json" "$plain" && report=$dir/$name.verify.json
      fi
      printf '%s\tgltfpack\t%s -vp %s\t\t%s\t%s\t\t%s\t\t\t\n' "$label" "$mode" "$vp" "${packed#"$out"/}" "$bytes" "${report#"$out"/}" >>"$results"
    done
  done
  echo "   gltfpack ${gltfpack_modes[*]} -vp ${vp_levels[0]}..${vp_levels[-1]} done"
done

machine="$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1), $(nproc) cores, $(uname -sr)"
[ -f /etc/debian_version ] && machine="$machine, Debian $(cat /etc/debian_version)"
# The revision of the tree SEGMORPH was built from (its build folder's CMakeCache.txt), else of this one.
source=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$(dirname "$(dirname "$segmorph")")/CMakeCache.txt" 2>/dev/null)
[ -d "$source" ] || source=$root
revision=$(git -C "$source" rev-parse --short HEAD 2>/dev/null)
[ -n "$(git -C "$source" status --porcelain 2>/dev/null)" ] && revision="$revision with uncommitted changes"
SEGMORPH_VERSION=$("$segmorph" --version) GLTFPACK_VERSION=$("${gltfpack[@]}" -v 2>&1 | head -n 1) \
NODE_VERSION=$(node --version) MACHINE=$machine REVISION=$revision \
  node "$here/compare_gltfpack.mjs" "$out" >"$out/comparison.md"
status=$?
echo "table: $out/comparison.md"
if [ -n "$doc" ] && [ -s "$out/comparison.md" ]; then
  node -e '
    const fs = require("fs");
    const [doc, table] = process.argv.slice(1);
    const text = fs.readFileSync(doc, "utf8");
    const begin = "<!-- compare_gltfpack: begin -->\n", end = "<!-- compare_gltfpack: end -->";
    const from = text.indexOf(begin), to = text.indexOf(end);
    if (from < 0 || to < from) { console.error("compare_gltfpack: markers missing in " + doc); process.exit(1); }
    fs.writeFileSync(doc, text.slice(0, from + begin.length) + fs.readFileSync(table, "utf8") + text.slice(to));
  ' "$doc" "$out/comparison.md" && echo "updated $doc"
fi
exit $status
