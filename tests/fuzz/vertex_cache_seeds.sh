#!/usr/bin/env bash
# Writes fuzz_vertex_cache's seeds from samples/WavingFlag: a mode byte, the OBJ's length (4 bytes, little-endian),
# the OBJ, then the cache or the second frame (fuzz_vertex_cache.cpp).
#   vertex_cache_seeds.sh SAMPLES_DIR SEEDS_DIR
set -euo pipefail
flag=$1/WavingFlag seeds=$2/vertex_cache
mkdir -p "$seeds"
le32() {
  local n=$1
  printf "\\x$(printf %02x $((n & 255)))\\x$(printf %02x $((n >> 8 & 255)))"
  printf "\\x$(printf %02x $((n >> 16 & 255)))\\x$(printf %02x $((n >> 24 & 255)))"
}
seed() {  # mode obj rest name
  { printf "\\x0$1"; le32 "$(stat -c %s "$2")"; cat "$2" "$3"; } >"$seeds/$4"
}
seed 0 "$flag/flag.obj" "$flag/flag.pc2" pc2
seed 0 "$flag/flag.obj" "$flag/flag.mdd" mdd
seed 1 "$flag/obj_sequence/flag_0001.obj" "$flag/obj_sequence/flag_0002.obj" sequence
