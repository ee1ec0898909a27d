// Constants of the segmorph track stream (spec/tracks.md), shared by its encoder and decoder. Values are part of
// the format: never renumber them.
#pragma once

#include <cstddef>
#include <cstdint>

namespace segmorph::track_format {

constexpr uint8_t kMagic[4] = {'S', 'G', 'M', 'T'};
constexpr uint8_t kVersion = 1;
constexpr size_t kHeaderBytes = 5;  // magic, version; the range-coded body follows, to the end of the stream

// Quantization steps are (8 + m) · 2^(e − 3): 3 bits of mantissa m, an exponent e in this range, so that every step
// is an exact binary64 (and binary32) value between 2^-40 and 15 · 2^17.
constexpr int kStepMantissaBits = 3;
constexpr int kMinStepExponent = -40;
constexpr int kMaxStepExponent = 20;

// Quantized values and predictions lie in [−kMaxQuantized, kMaxQuantized], so that a residual (value minus
// prediction) fits int32 and every integer a decoder handles is exact in binary64 (JavaScript numbers).
constexpr int64_t kMaxQuantized = (int64_t(1) << 30) - 1;

// A rotation key rebuilds its largest component from the other three unless the rebuilt value misses the
// quantized one by more than this many steps; then all four are coded (an escape).
constexpr int64_t kMaxRebuildError = 2;

// Binary32 patterns of key times: non-negative finite floats are the patterns below +infinity's, and their order
// is the order of the patterns.
constexpr uint32_t kInfinityBits = 0x7F800000u;

}  // namespace segmorph::track_format
