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
  // change: what a later neighbour's spatial prediction reads of each reconstructed residual (its difference
  // from the previous frame's with temporal residuals on), computed once per vertex; the same values, summed in
  // the same order, as predicted_residual's.
  std::vector<double> previous(welded * 3, 0.0), current(welded * 3, 0.0), change(welded * 3, 0.0);
  const double steps[3] = {double(content.residual_step[0]), double(content.residual_step[1]),
                           double(content.residual_step[2])};
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames) {
    std::fill(previous.begin(), previous.end(), 0.0);
    for (uint32_t f = 0; f < frames; ++f, ++frame) {
      const size_t frame_offset = frame * welded * 3;
      for (uint32_t v : traversal.order) {
        const uint32_t begin = traversal.earlier_offset[v], end = traversal.earlier_offset[v + 1];
        double sum[3] = {0, 0, 0};
        if (spatial)
          for (uint32_t j = begin; j < end; ++j) {
            const double* c = &change[size_t(traversal.earlier[j]) * 3];
            sum[0] += c[0], sum[1] += c[1], sum[2] += c[2];
          }
        for (size_t axis = 0; axis < 3; ++axis) {
          const size_t i = size_t(v) * 3 + axis;
          const size_t index = frame_offset + i;
          const double p = predictions[index];
          double r = temporal ? previous[i] : 0.0;
          if (spatial && end > begin) r += sum[axis] / double(end - begin);
          const int64_t k = symbol(index, p, r);
          float x;
          if (lossless) {
            x = from_ordered_bits(ordered_bits(float(p + r)) + k);
            current[i] = double(x) - p;
          } else {
            current[i] = r + double(k) * steps[axis];
            x = float(p + current[i]);
          }
          change[i] = temporal ? current[i] - previous[i] : current[i];
          output(index, x);
        }
      }
      previous.swap(current);
    }
  }
}

}  // namespace segmorph
