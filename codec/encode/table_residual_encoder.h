// The encoder of the table residual code of stream version 2 (common/table_residual_format.h describes the code).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/range_coder.h"

namespace segmorph {

// Codes `residuals` (F × W × 3 lossy quantizer indices in (INT32_MIN, INT32_MAX]; Symbol is int64_t or int32_t, as
// StreamContent holds them): the frequency tables and the
// magnitudes above 2 into `body` (the stream's range coder, after the residual steps), and the rANS words into
// `symbols` (appended; the stream's bytes after the body).
template <typename Symbol>
void encode_table_residuals(RangeEncoder& body, const std::vector<Symbol>& residuals, size_t welded_count,
                            std::vector<uint8_t>& symbols);

}  // namespace segmorph
