#!/usr/bin/env bash
# Whether two builds of segmorph write the same bytes: every file (each .glb/.gltf under SAMPLES_DIR) encoded by
# both in five settings (default; --targets bake --skins bake --gpu-playable; --fast-decode --error 0.5;
# --max-stream-version 3 --bpvf 3; --lossless, the sequences left out) and each default encode decoded. The check a
# refactoring or a speed change that promises "byte-identical" runs (docs/architecture.md): a line per file that
# differs, and a summary. Encodes a build refuses (a file with nothing animated, a bpvf target below what a small file
# takes) must be refused by both with the same message.
#
#   bench/same_bytes.sh SEGMORPH_BEFORE SEGMORPH_AFTER OUTDIR SAMPLES_DIR
#
# Exit status 0 when every output is the same bytes, 1 when one differs, 2 on bad usage.
set -u
if [ $# -ne 4 ]; then
  echo "usage: bench/same_bytes.sh SEGMORPH_BEFORE SEGMORPH_AFTER OUTDIR SAMPLES_DIR" >&2
  exit 2
fi
before=$1 after=$2 out=$3 samples=$4
for tool in "$before" "$after"; do
  [ -x "$tool" ] || { echo "bench/same_bytes.sh: $tool is not an executable" >&2; exit 2; }
done
[ -d "$samples" ] || { echo "bench/same_bytes.sh: $samples is not a folder" >&2; exit 2; }
mkdir -p "$out/before" "$out/after"

settings=("default:" "bake:--targets bake --skins bake --gpu-playable" "fast:--fast-decode --error 0.5"
          "v3:--max-stream-version 3 --bpvf 3" "lossless:--lossless")
outputs=0 differ=0
# One output of both builds: the same bytes, or the same refusal.
compare() {  # NAME COMMAND-ARGUMENTS... (the output path as @OUTPUT@)
  local name=$1
  shift
  local a="$out/before/$name" b="$out/after/$name" status_a status_b message_a message_b
  message_a=$("$before" "${@/@OUTPUT@/$a}" -q 2>&1 >/dev/null)
  status_a=$?
  message_b=$("$after" "${@/@OUTPUT@/$b}" -q 2>&1 >/dev/null)
  status_b=$?
  outputs=$((outputs + 1))
  if [ $status_a -ne 0 ] || [ $status_b -ne 0 ]; then
    if [ $status_a -ne $status_b ] || [ "${message_a//$a/@OUTPUT@}" != "${message_b//$b/@OUTPUT@}" ]; then
      echo "differs: $name: exit $status_a / $status_b: ${message_a:-ok} / ${message_b:-ok}"
      differ=$((differ + 1))
    fi
  elif ! cmp -s "$a" "$b"; then
    echo "differs: $name ($(stat -c %s "$a") / $(stat -c %s "$b") bytes)"
    differ=$((differ + 1))
  fi
}

while IFS= read -r file; do
  stem=$(basename "$file" | sed 's/\.[a-zA-Z]*$//')
  for setting in "${settings[@]}"; do
    label=${setting%%:*} options=${setting#*:}
    case "$file:$label" in */sequences/*:lossless) continue ;; esac
    # shellcheck disable=SC2086
    compare "$stem.$label.glb" encode "$file" -o @OUTPUT@ $options
  done
  if [ -f "$out/before/$stem.default.glb" ] && [ -f "$out/after/$stem.default.glb" ]; then
    outputs=$((outputs + 1))
    "$before" decode -q "$out/before/$stem.default.glb" -o "$out/before/$stem.decoded.glb" &&
      "$after" decode -q "$out/after/$stem.default.glb" -o "$out/after/$stem.decoded.glb"
    if ! cmp -s "$out/before/$stem.decoded.glb" "$out/after/$stem.decoded.glb"; then
      echo "differs: $stem.decoded.glb"
      differ=$((differ + 1))
    fi
  fi
done < <(find "$samples" \( -name '*.glb' -o -name '*.gltf' \) | sort)

echo "$outputs outputs compared, $differ differ"
[ $differ -eq 0 ]
