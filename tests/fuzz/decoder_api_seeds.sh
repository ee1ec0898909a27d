#!/usr/bin/env bash
# The seeds of fuzz_decoder_api: the other targets' seeds behind the byte that chooses what it drives (see
# fuzz_decoder_api.cpp): each animation stream whole (0), again after a seek to clip 0 (1) and clip 1 (5), as kept
# targets (2); each track stream (3).
#   decoder_api_seeds.sh SEEDS   (SEEDS/animation_stream and SEEDS/track_stream in, SEEDS/decoder_api out)
set -euo pipefail
seeds=$1
mkdir -p "$seeds/decoder_api"
for stream in "$seeds"/animation_stream/*; do
  for choice in 000 001 005 002; do
    { printf "\\$choice"; cat "$stream"; } >"$seeds/decoder_api/$choice-$(basename "$stream")"
  done
done
for stream in "$seeds"/track_stream/*; do
  { printf '\003'; cat "$stream"; } >"$seeds/decoder_api/003-$(basename "$stream")"
done
echo "decoder_api_seeds: $(ls "$seeds/decoder_api" | wc -l) seeds"
