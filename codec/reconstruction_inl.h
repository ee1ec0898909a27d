// Template definitions of reconstruction.h.
#pragma once

#include "stream_format.h"

namespace segmorph {

template <typename Symbol, typename Output>
void residual_loop(const StreamContent& content, const std::vector<double>& predictions, Symbol symbol, Output output) {
  const size_t welded = content.welded_count;
  const bool lossless = content.flags & format::kFlagLossless;
  const bool temporal = content.flags & format::kFlagTemporalResiduals;
  std::vector<double> previous(welded * 3, 0.0);
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames) {
    std::fill(previous.begin(), previous.end(), 0.0);
    for (uint32_t f = 0; f < frames; ++f, ++frame)
      for (size_t i = 0; i < welded * 3; ++i) {
        const size_t index = frame * welded * 3 + i;
        const double p = predictions[index];
        const double r = temporal ? previous[i] : 0.0;
        const int64_t k = symbol(index, p, r);
        float x;
        if (lossless) {
          x = from_ordered_bits(ordered_bits(float(p + r)) + k);
          previous[i] = double(x) - p;
        } else {
          const double residual = r + double(k) * double(content.residual_step[i % 3]);
          x = float(p + residual);
          previous[i] = residual;
        }
        output(index, x);
      }
  }
}

}  // namespace segmorph
