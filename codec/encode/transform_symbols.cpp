#include "encode/transform_symbols.h"

#include "decode/transform_walk.h"

namespace segmorph {

std::vector<int32_t> transform_symbols(const StreamContent& content, const ResidualTraversal& traversal,
                                       const TransformCoefficients& coefficients) {
  std::vector<int32_t> symbols(coefficients.values.size());
  transform_code::walk(content, traversal, coefficients, [&](uint64_t index, int64_t prediction, uint64_t symbol) {
    symbols[size_t(symbol)] = int32_t(int64_t(coefficients.values[size_t(index)]) - prediction);
    return true;
  });
  return symbols;
}

}  // namespace segmorph
