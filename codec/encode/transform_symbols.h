// The encoder's side of version 4's coefficients (decode/transform_residuals.h is the decoder's).
#pragma once

#include <cstdint>
#include <vector>

#include "common/reconstruction.h"
#include "common/stream.h"
#include "decode/transform_residuals.h"

namespace segmorph {

// The encoder's inverse: the symbols that give `coefficients` (each within ±kMaxTransformValue), in stream order.
std::vector<int32_t> transform_symbols(const StreamContent& content, const ResidualTraversal& traversal,
                                       const TransformCoefficients& coefficients);

}  // namespace segmorph
