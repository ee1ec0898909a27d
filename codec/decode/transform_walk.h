// The walk over a version-4 stream's coefficients (spec/bitstream.md 8.7.1) that its decoder
// (decode/transform_residuals.cpp, symbols to coefficients) and its encoder (encode/transform_symbols.cpp, the inverse)
// share, so that the two cannot disagree on an order or a prediction.
#pragma once

#include <cstdint>
#include <vector>

#include "common/reconstruction.h"
#include "common/stream.h"
#include "decode/transform_residuals.h"

namespace segmorph {
namespace transform_code {

// The nearest integer to sum / count (count > 0), halves away from zero, in integers.
inline int64_t rounded_mean(int64_t sum, int64_t count) {
  return sum >= 0 ? (2 * sum + count) / (2 * count) : -((-2 * sum + count) / (2 * count));
}

// The same with the division by 2 × count done as a multiplication where the dividend has 32 bits (nearly always):
// magic = reciprocal(count). Exact (Lemire, Kaser and Kurz, "Faster remainder by direct computation", 2019: for
// 32-bit dividends and divisors, x / d = (⌈2^64 / d⌉ × x) >> 64); a 64-bit division costs more than the rest of the
// walk.
inline uint64_t reciprocal(int64_t count) { return UINT64_MAX / uint64_t(2 * count) + 1; }
inline int64_t rounded_mean(int64_t sum, int64_t count, uint64_t magic) {
  const uint64_t x = 2 * uint64_t(sum >= 0 ? sum : -sum) + uint64_t(count);
  const uint64_t q = x >> 32 == 0 ? uint64_t((static_cast<unsigned __int128>(magic) * x) >> 64) : x / uint64_t(2 * count);
  return sum >= 0 ? int64_t(q) : -int64_t(q);
}

// Per welded vertex, its place among its cluster's welded vertices (ascending); per cluster, where its symbols start.
struct SymbolLayout {
  std::vector<uint32_t> rank;
  std::vector<uint64_t> start;
  std::vector<uint32_t> members;  // per cluster
};

inline SymbolLayout symbol_layout(const StreamContent& content) {
  SymbolLayout layout;
  layout.rank.resize(content.welded_count);
  layout.members.assign(content.cluster_count, 0);
  for (uint32_t w = 0; w < content.welded_count; ++w) layout.rank[w] = layout.members[content.labels[w]]++;
  layout.start.resize(content.cluster_count);
  uint64_t at = 0;
  for (size_t k = 0; k < content.cluster_count; ++k) {
    layout.start[k] = at;
    at += uint64_t(content.basis_size[k]) * 3 * layout.members[k];
  }
  return layout;
}

// Walks the traversal: for each welded vertex, axis and vector, the prediction from its earlier neighbours in its
// cluster (their values already final), then `code(index, prediction, symbol)` makes values[index], the vertex's,
// final (the callback may write it: `coefficients` is read here, never written).
template <typename Code>
bool walk(const StreamContent& content, const ResidualTraversal& traversal, const TransformCoefficients& coefficients,
          Code code) {
  const SymbolLayout layout = symbol_layout(content);
  std::vector<uint64_t> same;  // the offsets of the vertex's earlier neighbours in its cluster
  for (size_t p = 0; p < traversal.order.size(); ++p) {
    const uint32_t w = traversal.order[p], k = content.labels[w], m = content.basis_size[k];
    if (m == 0) continue;
    same.clear();
    for (uint32_t j = traversal.earlier_offset[p]; j < traversal.earlier_offset[p + 1]; ++j) {
      const uint32_t neighbour = traversal.order[traversal.earlier[j]];
      if (content.labels[neighbour] == k) same.push_back(coefficients.offset[neighbour]);
    }
    const int64_t count = int64_t(same.size());
    const uint64_t magic = count > 0 ? reciprocal(count) : 0;
    for (uint32_t a = 0; a < 3; ++a)
      for (uint32_t i = 0; i < m; ++i) {
        int64_t sum = 0;
        for (uint64_t offset : same) sum += coefficients.values[offset + a * m + i];
        const int64_t prediction = count == 0 ? 0 : rounded_mean(sum, count, magic);
        const uint64_t symbol = layout.start[k] + (uint64_t(i) * 3 + a) * layout.members[k] + layout.rank[w];
        if (!code(coefficients.offset[w] + a * m + i, prediction, symbol)) return false;
      }
  }
  return true;
}

}  // namespace transform_code
}  // namespace segmorph
