// Entropy coding of the residual section of a stream (decode/residual_decoder.h describes the code; spec/entropy-coding.md,
// section 8, is the bit-exact description).
#pragma once

#include <cstddef>
#include <vector>

#include "common/range_coder.h"

namespace segmorph {

// Appends the residual symbols to the encoder's stream. residuals: F × W × 3, frame by frame, welded vertex by
// vertex, x y z (StreamContent::residuals, or its narrow_residuals: Symbol is int64_t or int32_t); welded_count:
// W ≥ 1. Lossy residuals must lie in (INT32_MIN, INT32_MAX].
template <typename Symbol>
void encode_residuals(RangeEncoder& encoder, const std::vector<Symbol>& residuals, size_t welded_count, bool lossless);

}  // namespace segmorph
