// The table residual code of stream version 2 (flag TABLE_RESIDUALS; spec/entropy-coding.md, section 9, is the
// bit-exact description): a lossy stream's residual symbols coded for decoding speed rather than for the last bytes.
//
// The adaptive residual code (residual_contexts.h) spends about five binary decisions on a vertex, each one a
// probability lookup, a multiplication and an adaptation in a chain. This code spends one table lookup: each
// (frame, welded vertex) is one symbol of 125, its three residuals clamped to [−2, 2], coded with rANS (asymmetric
// numeral systems, 12-bit frequencies, two interleaved states) from frequency tables the stream carries, one per
// context of 16 (the vertex's nonzero axes in the frame before, and whether any was nonzero two frames before). The
// magnitudes above 2 follow in the range-coded body, where the tables also are; the rANS words follow the body.
// Measured (docs/codec.md): the cow decodes in about two thirds of the time; whole files are 1 to 11 % larger on
// the cow, chicken and horse at --error 0.15 and 0.5.
//
// This header holds what its encoder (encode/table_residual_encoder.h) and decoder (decode/table_residual_decoder.h)
// share: the constants, the symbols' meaning, the contexts and the models of the magnitudes above 2.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "common/range_coder.h"

namespace segmorph {

namespace table_code {
constexpr int kSymbols = 125;       // 5^3: (x, y, z) clamped to [−2, 2]
constexpr int kContexts = 16;       // nonzero pattern one frame before (8) × any nonzero two before (2)
constexpr int kFrequencyBits = 12;  // frequencies sum to 2^12 in every context
constexpr uint32_t kTotal = 1u << kFrequencyBits;
constexpr uint32_t kMaxFrequency = kTotal - 64;  // 4032: every symbol costs at least 0.021 bits (frame bounds)
constexpr uint32_t kStateLow = 1u << 16;         // rANS states lie in [2^16, 2^32) between symbols
constexpr int kStates = 2;                       // interleaved, vertex-frame by vertex-frame
constexpr int kZeroSymbol = 62;                  // (0, 0, 0)
constexpr size_t kMinSymbolBytes = 4 * kStates;  // the states' initial words
// A byte of the symbol stream holds at most this many vertex-frames (section 9.5 of the spec's Appendix B).
constexpr size_t kVertexFramesPerByte = 376;

// What a symbol stands for: the clamped values, the axes that are nonzero (bit a for axis a) and the axes whose
// magnitude may be above 2 (clamped to ±2, an excess follows in the body).
struct SymbolValues {
  int8_t value[3];
  uint8_t nonzero;
  uint8_t clamped;
};

struct SymbolTable {
  SymbolValues symbol[kSymbols] = {};
};

constexpr SymbolTable make_symbol_table() {
  SymbolTable table;
  for (int s = 0; s < kSymbols; ++s) {
    SymbolValues& v = table.symbol[s];
    v.value[0] = int8_t(s / 25 - 2), v.value[1] = int8_t(s / 5 % 5 - 2), v.value[2] = int8_t(s % 5 - 2);
    for (int a = 0; a < 3; ++a) {
      v.nonzero = uint8_t(v.nonzero | (v.value[a] != 0) << a);
      v.clamped = uint8_t(v.clamped | (v.value[a] == 2 || v.value[a] == -2) << a);
    }
  }
  return table;
}
inline constexpr SymbolTable kSymbolTable = make_symbol_table();

// A vertex's history: its nonzero pattern one frame before (bits 0–2) and two frames before (bits 3–5).
inline uint32_t context_of(uint32_t history) {
  return (history & 7u) | uint32_t((history & 0x38u) != 0) << 3;
}
inline uint8_t next_history(uint32_t history, uint32_t nonzero) {
  return uint8_t(nonzero | (history & 7u) << 3);
}

}  // namespace table_code

// The models of the magnitudes above 2, in the body: per axis, for each residual clamped to ±2, one adaptive bit
// "the magnitude is above 2" and, when it is, the magnitude − 3.
struct ExcessModels {
  std::array<BitModel, 3> above_two;
  std::array<UnsignedModel, 3> minus_three;
};

}  // namespace segmorph
