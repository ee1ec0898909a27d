#!/usr/bin/env bash
# The runtime decoder as its users get it (ctest install_engine_decode):
#   1. `cmake --install` of the build into a temporary prefix (static library, headers, CMake package, pkg-config
#      file, the segmorph tool), and a decoder-only shared build installed into another, whose library must export
#      the API's symbols and nothing else;
#   2. examples/engine_decode built from outside the source tree against each installed package, as an engine would
#      build it (find_package(segmorph CONFIG)), and a C99 program built with pkg-config's flags;
#   3. every bundled sample and every shared sample and sequence encoded by the installed tool in several modes; the
#      example's frames (tinygltf, Draco and the C API) must equal `segmorph decode --frames` bit for bit;
#   4. examples/pipeline, built against the installed pipeline API (segmorph::segmorph), encodes, decodes and verifies
#      every bundled sample and shared sequence: the same bytes as the installed tool, within the error target.
#
#   check_install.sh SOURCE_DIR BUILD_DIR WORK_DIR SHARED_SAMPLES_DIR
set -euo pipefail
source_dir=$1
build_dir=$2
work=$3
shared_samples=$4
rm -rf "$work"
mkdir -p "$work"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
fail() {
  echo "check_install: $*" >&2
  exit 1
}

echo "check_install: installing the build into $work/static"
cmake --install "$build_dir" --prefix "$work/static" >/dev/null
echo "check_install: a decoder-only shared library, installed into $work/shared"
cmake -S "$source_dir" -B "$work/build-shared" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DSEGMORPH_DECODER_ONLY=ON \
  -DBUILD_SHARED_LIBS=ON -DSEGMORPH_WEB=OFF >/dev/null
cmake --build "$work/build-shared" --parallel "$(nproc)" >/dev/null
cmake --install "$work/build-shared" --prefix "$work/shared" >/dev/null
[ -f "$work/static/include/segmorph/segmorph.h" ] && [ -f "$work/static/lib/libsegmorph.a" ] ||
  fail "the install has no pipeline API (include/segmorph/segmorph.h, lib/libsegmorph.a)"
for file in include/segmorph/decoder.h include/segmorph/decoder_c.h include/segmorph/status.h \
  include/segmorph/version.h lib/cmake/segmorph/segmorph-config.cmake lib/pkgconfig/segmorph.pc; do
  for kind in static shared; do
    [ -f "$work/$kind/$file" ] || fail "the $kind install has no $file"
  done
done
[ -f "$work/static/lib/libsegmorph_decoder.a" ] || fail "the static install has no libsegmorph_decoder.a"
[ -x "$work/static/bin/segmorph" ] || fail "the install has no segmorph tool"
library="$work/shared/lib/libsegmorph_decoder.so"
[ -f "$library" ] || fail "the shared install has no libsegmorph_decoder.so"

# The shared library's exports: the C API's functions (every one the header declares) and the C++ API, nothing else
# (no internal function, no instantiation of the standard library's templates).
exported=$(nm -D --defined-only "$library" | awk '{print $3}' | c++filt)
unexpected=$(grep -v -E '^segmorph_[a-z_]+$|^segmorph::(AnimationDecoder::|track_stream_floats\(|decode_track_stream\()' \
  <<<"$exported" || true)
[ -z "$unexpected" ] || fail "libsegmorph_decoder.so exports more than its API: $(head -5 <<<"$unexpected" | tr '\n' ' ')"
declared=$(grep -o -E 'segmorph_[a-z_]+\(' "$source_dir/include/segmorph/decoder_c.h" | tr -d '(' | sort -u)
for function in $declared; do
  grep -q -x "$function" <<<"$exported" || fail "libsegmorph_decoder.so does not export $function"
done
grep -q '^segmorph::AnimationDecoder::decode_clip' <<<"$exported" || fail "the C++ API is not exported"
echo "check_install: libsegmorph_decoder.so exports $(wc -l <<<"$exported") symbols, all of the API"

for kind in static shared; do
  echo "check_install: examples/engine_decode against the $kind package"
  cmake -S "$source_dir/examples/engine_decode" -B "$work/example-$kind" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$work/$kind" >/dev/null
  cmake --build "$work/example-$kind" >/dev/null
  # A C program with pkg-config's flags (the static library needs --static: its C++ runtime is in Libs.private).
  static=()
  [ "$kind" = static ] && static=(--static)
  read -r -a flags <<<"$(PKG_CONFIG_PATH="$work/$kind/lib/pkgconfig" pkg-config --cflags --libs "${static[@]}" segmorph)"
  cc -std=c99 -Wall -Wextra -pedantic -Werror "$source_dir/tests/install/c_api_check.c" "${flags[@]}" \
    -o "$work/c_api_check-$kind"
  LD_LIBRARY_PATH="$work/$kind/lib" "$work/c_api_check-$kind"
done
# The shared example must use the installed shared library.
# (ldd's output is read whole: `ldd | grep -q` fails under pipefail when grep stops reading before ldd ends.)
linked=$(ldd "$work/example-shared/engine_decode")
[[ "$linked" == *"$library"* ]] || fail "engine_decode (shared) does not load $library"

segmorph="$work/static/bin/segmorph"
inputs=()
for input in "$source_dir"/samples/*/*.glb "$source_dir"/samples/*/*.gltf; do inputs+=("$input"); done
if [ -d "$shared_samples" ]; then
  for input in "$shared_samples"/gltf/*/*.glb "$shared_samples"/gltf/*/*.gltf "$shared_samples"/sequences/*/*.glb; do
    inputs+=("$input")
  done
else
  echo "check_install: $shared_samples is absent: the shared samples and sequences are skipped"
fi
compared=0
frames_bytes=0
for input in "${inputs[@]}"; do
  name=$(basename "$(dirname "$input")")
  for mode in default keep-targets fast-decode lossless; do
    case $mode in
      default) options=() ;;
      keep-targets) options=(--targets keep) ;;
      fast-decode) options=(--fast-decode --skins bake) ;;
      lossless) options=(--lossless) ;;
    esac
    encoded="$work/$name.$mode.glb"
    if ! "$segmorph" encode -q "$input" -o "$encoded" "${options[@]}" 2>"$work/encode.err"; then
      # A file without animation (MorphPrimitivesTest) is refused: fine.
      grep -q "nothing animated" "$work/encode.err" ||
        fail "encode $mode $input: $(cat "$work/encode.err")"
      continue
    fi
    "$segmorph" decode -q "$encoded" --frames "$work/reference.bin" 2>"$work/decode.err" ||
      fail "segmorph decode --frames $encoded: $(cat "$work/decode.err")"
    for kind in static shared; do
      "$work/example-$kind/engine_decode" "$encoded" "$work/engine.bin" >"$work/engine.json" 2>"$work/engine.err" ||
        fail "engine_decode ($kind) $encoded: $(cat "$work/engine.err")"
      cmp -s "$work/engine.bin" "$work/reference.bin" ||
        fail "engine_decode ($kind) and segmorph decode --frames disagree on $encoded ($mode)"
    done
    # One JSON line per clip, whose frames add up to the file.
    floats=$(awk -F'[:,}]' '{for (i = 1; i < NF; ++i) { if ($i == "\"vertices\"") v = $(i + 1); if ($i == "\"frames\"") f = $(i + 1) } s += v * f * 3} END {print s + 0}' "$work/engine.json")
    [ $((floats * 4)) -eq "$(stat -c %s "$work/reference.bin")" ] ||
      fail "engine_decode's JSON lines do not add up to its frames on $encoded"
    compared=$((compared + 1))
    frames_bytes=$((frames_bytes + $(stat -c %s "$work/reference.bin")))
  done
done
[ "$compared" -gt 0 ] && [ "$frames_bytes" -gt 0 ] || fail "nothing was compared"
echo "check_install: $compared encoded files, $frames_bytes bytes of frames: engine_decode (static and shared) equals segmorph decode --frames bit for bit"

echo "check_install: examples/pipeline against the installed pipeline API"
cmake -S "$source_dir/examples/pipeline" -B "$work/pipeline" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/static" >/dev/null
cmake --build "$work/pipeline" >/dev/null
pipelined=0
for input in "$source_dir"/samples/*/*.glb "$source_dir"/samples/*/*.gltf "$shared_samples"/sequences/*/*.glb; do
  [ -f "$input" ] || continue
  name=$(basename "$(dirname "$input")")
  "$work/pipeline/pipeline" "$input" "$work/$name.pipeline.glb" 2>"$work/pipeline.err" >"$work/pipeline.json" ||
    fail "examples/pipeline $input: $(tail -1 "$work/pipeline.err") $(cat "$work/pipeline.json")"
  grep -q '"within_target":true' "$work/pipeline.json" || fail "examples/pipeline $input: $(cat "$work/pipeline.json")"
  "$segmorph" encode -q "$input" -o "$work/$name.tool.glb" >/dev/null
  cmp -s "$work/$name.pipeline.glb" "$work/$name.tool.glb" ||
    fail "examples/pipeline and segmorph encode wrote different bytes for $input"
  pipelined=$((pipelined + 1))
done
echo "check_install: examples/pipeline encoded, decoded and verified $pipelined files: the installed tool's bytes, within the error target"
