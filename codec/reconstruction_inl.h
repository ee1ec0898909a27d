// Template definitions of reconstruction.h.
#pragma once

namespace segmorph {

template <typename Symbol, typename Output>
void ResidualReconstructor::frame(const double* predictions, Symbol symbol, Output output) {
  // The flags as compile-time constants, so that the loop carries no tests of them.
  if (lossless_) {
    if (temporal_ && spatial_)
      frame_with<true, true, true>(predictions, symbol, output);
    else if (temporal_)
      frame_with<true, true, false>(predictions, symbol, output);
    else if (spatial_)
      frame_with<true, false, true>(predictions, symbol, output);
    else
      frame_with<true, false, false>(predictions, symbol, output);
  } else {
    if (temporal_ && spatial_)
      frame_with<false, true, true>(predictions, symbol, output);
    else if (temporal_)
      frame_with<false, true, false>(predictions, symbol, output);
    else if (spatial_)
      frame_with<false, false, true>(predictions, symbol, output);
    else
      frame_with<false, false, false>(predictions, symbol, output);
  }
}

template <bool kLossless, bool kTemporal, bool kSpatial, typename Symbol, typename Output>
void ResidualReconstructor::frame_with(const double* predictions, Symbol symbol, Output output) {
  const size_t welded = traversal_.order.size();
  for (size_t position = 0; position < welded; ++position) {
    const uint32_t v = traversal_.order[position];
    const uint32_t begin = traversal_.earlier_offset[position], end = traversal_.earlier_offset[position + 1];
    double sum[3] = {0, 0, 0};
    if (kSpatial)
      for (uint32_t j = begin; j < end; ++j) {
        const double* c = &change_[size_t(traversal_.earlier[j]) * 3];
        sum[0] += c[0], sum[1] += c[1], sum[2] += c[2];
      }
    for (size_t axis = 0; axis < 3; ++axis) {
      const size_t at = position * 3 + axis, i = size_t(v) * 3 + axis;
      const double p = predictions[i];
      double r = kTemporal ? previous_[at] : 0.0;
      if (kSpatial && end > begin) r += sum[axis] * (1.0 / double(end - begin));
      const int64_t k = symbol(i, p, r);
      float x;
      if (kLossless) {
        x = from_ordered_bits(ordered_bits(float(p + r)) + k);
        current_[at] = double(x) - p;
      } else {
        current_[at] = r + double(k) * steps_[axis];
        x = float(p + current_[at]);
      }
      change_[at] = kTemporal ? current_[at] - previous_[at] : current_[at];
      output(i, x);
    }
  }
  previous_.swap(current_);
}

}  // namespace segmorph
