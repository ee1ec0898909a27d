// The contexts of the adaptive residual code (spec/entropy-coding.md, section 8), shared by its encoder
// (encode/residual_encoder.cpp) and decoder (decode/residual_decoder.cpp) so that they cannot disagree.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "common/range_coder.h"

namespace segmorph {

// The models of one axis (spec section 8.1).
struct AxisModels {
  std::array<BitModel, 36> nonzero;
  std::array<BitModel, 9> negative;
  std::array<BitModel, 9> above_one;  // |r| > 1, given r ≠ 0
  std::array<BitModel, 9> above_two;  // |r| > 2, given |r| > 1
  UnsignedModel magnitude_minus_three;
};

struct ResidualModels {
  std::array<BitModel, 64> vertex;  // some residual of the vertex is nonzero
  std::array<AxisModels, 3> axis;
};

namespace residual_code {

constexpr int64_t kEscape = INT32_MIN;  // lossless only: the residual follows as 64 direct bits

// What the contexts of a residual use of the residuals p1, p2, p3 at the same vertex and axis one, two and three
// frames earlier (0 before the first frame), packed in a byte that is updated as each frame is coded, so that a
// symbol's contexts cost one byte load instead of three 8-byte loads a row apart (measured on cow at --error 0.15:
// read_stream takes 23 ms with the byte, 35 ms reading the three frames):
//   bits 0-1: q(p1) = min(|p1|, 2)    bit 2: p1 < 0
//   bits 3-4: q(p2)                   bit 5: p2 < 0
//   bit 6:    p3 ≠ 0
using History = uint8_t;

// The history with p1 moved to p2 and p2 to p3, p1 still 0: the history after a zero residual.
inline History aged_history(History h) {
  return History((h & 7u) << 3 | uint32_t((h & 0x18u) != 0) << 6);
}

inline History next_history(History h, int64_t value) {
  const uint32_t q = value == 0 ? 0u : (value == 1 || value == -1) ? 1u : 2u;
  return History(aged_history(h) | q | uint32_t(value < 0) << 2);
}

// The context indices of spec/entropy-coding.md section 8.2 as functions of the history byte.
struct ContextTables {
  uint8_t nonzero[128] = {};    // 2 · (2 · (3 q(p1) + q(p2)) + [p3 ≠ 0]); the caller adds the "earlier axis" bit
  uint8_t negative[128] = {};   // 3 t(p1) + t(p2), t = 0 for zero, 1 for positive, 2 for negative
  uint8_t magnitude[128] = {};  // 3 q(p1) + q(p2)
  uint8_t vertex[128] = {};     // this axis's share of the vertex context: 16 [p1 ≠ 0] + 4 [p2 ≠ 0] + [p3 ≠ 0]
};

constexpr ContextTables make_context_tables() {
  ContextTables tables;
  for (uint32_t h = 0; h < 128; ++h) {
    const uint32_t q1 = h & 3u, q2 = (h >> 3) & 3u, nonzero3 = h >> 6;
    if (q1 > 2 || q2 > 2) continue;  // not a history next_history() makes
    const uint32_t t1 = q1 == 0 ? 0 : 1 + ((h >> 2) & 1u), t2 = q2 == 0 ? 0 : 1 + ((h >> 5) & 1u);
    tables.nonzero[h] = uint8_t(2 * (2 * (3 * q1 + q2) + nonzero3));
    tables.negative[h] = uint8_t(3 * t1 + t2);
    tables.magnitude[h] = uint8_t(3 * q1 + q2);
    tables.vertex[h] = uint8_t(16 * (q1 != 0) + 4 * (q2 != 0) + nonzero3);
  }
  return tables;
}
inline constexpr ContextTables kContexts = make_context_tables();

// n1 · 16 + n2 · 4 + n3, nk the number of the vertex's three residuals k frames earlier that are nonzero.
inline size_t vertex_context(const History* h) {
  return size_t(kContexts.vertex[h[0]]) + kContexts.vertex[h[1]] + kContexts.vertex[h[2]];
}

}  // namespace residual_code
}  // namespace segmorph
