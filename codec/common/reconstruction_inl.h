// Template definitions of reconstruction.h.
#pragma once

#include <type_traits>

// The residual loop's per-vertex step is called from three places in two_frames(), which GCC then leaves as calls;
// inlined, the symbol and output lambdas inline with it.
#if defined(__GNUC__)
#define SEGMORPH_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define SEGMORPH_ALWAYS_INLINE inline
#endif

namespace segmorph {

// Calls f(lossless, temporal, spatial) with the flags as std::integral_constant values, so that the loops f
// instantiates carry no tests of them.
template <typename F>
void ResidualReconstructor::with_flags(F f) const {
  auto by_prediction = [&](auto lossless) {
    if (temporal_ && spatial_)
      f(lossless, std::true_type(), std::true_type());
    else if (temporal_)
      f(lossless, std::true_type(), std::false_type());
    else if (spatial_)
      f(lossless, std::false_type(), std::true_type());
    else
      f(lossless, std::false_type(), std::false_type());
  };
  if (lossless_)
    by_prediction(std::true_type());
  else
    by_prediction(std::false_type());
}

template <bool kLossless, bool kTemporal, bool kSpatial, typename Symbol, typename Output>
SEGMORPH_ALWAYS_INLINE void ResidualReconstructor::vertex(size_t position, const double* predictions, Symbol& symbol,
                                                          Output& output, const double* reference, double* current,
                                                          double* change) const {
  const uint32_t v = traversal_.order[position];
  const uint32_t begin = traversal_.earlier_offset[position], end = traversal_.earlier_offset[position + 1];
  double sum[3] = {0, 0, 0};
  if (kSpatial)
    for (uint32_t j = begin; j < end; ++j) {
      const double* c = &change[size_t(traversal_.earlier[j]) * 3];
      sum[0] += c[0], sum[1] += c[1], sum[2] += c[2];
    }
  for (size_t axis = 0; axis < 3; ++axis) {
    const size_t at = position * 3 + axis, i = size_t(v) * 3 + axis;
    const double p = predictions[i];
    double r = kTemporal ? reference[at] : 0.0;
    if (kSpatial && end > begin) r += sum[axis] * inverse_count_[position];
    const int64_t k = symbol(i, p, r);
    float x;
    if (kLossless) {
      x = from_ordered_bits(ordered_bits(float(p + r)) + k);
      current[at] = double(x) - p;
    } else {
      current[at] = r + double(k) * steps_[axis];
      x = float(p + current[at]);
    }
    change[at] = kTemporal ? current[at] - reference[at] : current[at];
    output(i, x);
  }
}

template <typename Symbol, typename Output>
void ResidualReconstructor::frame(size_t frame, const double* predictions, Symbol symbol, Output output) {
  const double* from = reference(frame, frame_in_clip_);
  double* current = slot(frame_in_clip_);
  with_flags([&](auto lossless, auto temporal, auto spatial) {
    for (size_t position = 0; position < traversal_.order.size(); ++position)
      vertex<decltype(lossless)::value, decltype(temporal)::value, decltype(spatial)::value>(
          position, predictions, symbol, output, from, current, change_.data());
  });
  ++frame_in_clip_;
}

template <typename SymbolA, typename OutputA, typename SymbolB, typename OutputB>
void ResidualReconstructor::two_frames(size_t frame, const double* predictions_a, SymbolA symbol_a, OutputA output_a,
                                       const double* predictions_b, SymbolB symbol_b, OutputB output_b) {
  // The second frame runs one vertex behind the first: a vertex needs only its own residual in its reference (the
  // first frame, whose vertex is done by then, or an earlier frame) and its earlier neighbours' in its own frame.
  const double* reference_a = reference(frame, frame_in_clip_);
  double* current_a = slot(frame_in_clip_);
  const double* reference_b = reference(frame + 1, frame_in_clip_ + 1);
  double* current_b = slot(frame_in_clip_ + 1);
  const size_t count = traversal_.order.size();
  with_flags([&](auto lossless, auto temporal, auto spatial) {
    constexpr bool kLossless = decltype(lossless)::value, kTemporal = decltype(temporal)::value,
                   kSpatial = decltype(spatial)::value;
    for (size_t position = 0; position < count; ++position) {
      vertex<kLossless, kTemporal, kSpatial>(position, predictions_a, symbol_a, output_a, reference_a, current_a,
                                             change_.data());
      if (position > 0)
        vertex<kLossless, kTemporal, kSpatial>(position - 1, predictions_b, symbol_b, output_b, reference_b, current_b,
                                               second_change_.data());
    }
    if (count > 0)
      vertex<kLossless, kTemporal, kSpatial>(count - 1, predictions_b, symbol_b, output_b, reference_b, current_b,
                                             second_change_.data());
  });
  frame_in_clip_ += 2;
}

}  // namespace segmorph
