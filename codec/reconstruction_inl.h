// Template definitions of reconstruction.h.
#pragma once

#include "stream_format.h"

namespace segmorph {

template <typename Symbol, typename Output>
void residual_loop(const StreamContent& content, const ResidualTraversal& traversal,
                   const std::vector<double>& predictions, Symbol symbol, Output output) {
  const size_t welded = content.welded_count;
  const bool lossless = content.flags & format::kFlagLossless;
  const bool temporal = content.flags & format::kFlagTemporalResiduals;
  const bool spatial = content.flags & format::kFlagSpatialResiduals;
  std::vector<double> previous(welded * 3, 0.0), current(welded * 3, 0.0);
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames) {
    std::fill(previous.begin(), previous.end(), 0.0);
    for (uint32_t f = 0; f < frames; ++f, ++frame) {
      for (uint32_t v : traversal.order)
        for (size_t axis = 0; axis < 3; ++axis) {
          const size_t i = size_t(v) * 3 + axis;
          const size_t index = frame * welded * 3 + i;
          const double p = predictions[index];
          const double r = predicted_residual(traversal, v, axis, 3, current.data(), previous.data(), temporal, spatial);
          const int64_t k = symbol(index, p, r);
          float x;
          if (lossless) {
            x = from_ordered_bits(ordered_bits(float(p + r)) + k);
            current[i] = double(x) - p;
          } else {
            current[i] = r + double(k) * double(content.residual_step[axis]);
            x = float(p + current[i]);
          }
          output(index, x);
        }
      previous.swap(current);
    }
  }
}

}  // namespace segmorph
