#include "encode/metrics.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace segmorph {

void bounding_box(const float* positions, size_t vertex_count, float low[3], float high[3]) {
  for (int c = 0; c < 3; ++c) low[c] = high[c] = positions[c];
  for (size_t v = 1; v < vertex_count; ++v)
    for (int c = 0; c < 3; ++c) {
      low[c] = std::min(low[c], positions[v * 3 + size_t(c)]);
      high[c] = std::max(high[c], positions[v * 3 + size_t(c)]);
    }
}

double bounding_box_diagonal_squared(const float* positions, size_t vertex_count) {
  if (vertex_count == 0) return 0;
  float low[3], high[3];
  bounding_box(positions, vertex_count, low, high);
  double squared = 0;
  for (int c = 0; c < 3; ++c) squared += (double(high[c]) - low[c]) * (double(high[c]) - low[c]);
  return squared;
}

double bounding_box_diagonal(const float* positions, size_t vertex_count) {
  return std::sqrt(bounding_box_diagonal_squared(positions, vertex_count));
}

void add_frame_spread(const float* frame, size_t vertex_count, double& spread) {
  double centroid[3] = {0, 0, 0};
  for (size_t v = 0; v < vertex_count; ++v)
    for (int c = 0; c < 3; ++c) centroid[c] += frame[v * 3 + size_t(c)];
  for (double& c : centroid) c /= double(std::max<size_t>(vertex_count, 1));
  for (size_t v = 0; v < vertex_count; ++v)
    for (int c = 0; c < 3; ++c) {
      const double s = double(frame[v * 3 + size_t(c)]) - centroid[c];
      spread += s * s;
    }
}

double squared_error(const std::vector<FrameSequence>& original, const std::vector<FrameSequence>& decoded) {
  double error = 0;
  for (size_t c = 0; c < decoded.size(); ++c)
    add_squared_error(original[c].positions.data(), decoded[c].positions.data(), decoded[c].positions.size(), error);
  return error;
}

void ErrorAccumulator::add(const FrameSequence& original, const FrameSequence& decoded) {
  assert(original.vertex_count == decoded.vertex_count && original.frame_count == decoded.frame_count);
  const size_t vertex_count = original.vertex_count;
  if (diagonal_ < 0 && original.frame_count > 0) diagonal_ = bounding_box_diagonal(original.frame(0), vertex_count);
  vertices_ = vertex_count;
  frames_ += original.frame_count;
  for (size_t f = 0; f < original.frame_count; ++f) {
    const float* a = original.frame(f);
    const float* b = decoded.frame(f);
    add_frame_spread(a, vertex_count, spread_squared_);
    double frame_error = 0;
    for (size_t v = 0; v < vertex_count; ++v) {
      double distance_squared = 0;
      for (int c = 0; c < 3; ++c) {
        const double d = double(a[v * 3 + size_t(c)]) - double(b[v * 3 + size_t(c)]);
        distance_squared += d * d;
      }
      frame_error += distance_squared;
      max_error_ = std::max(max_error_, std::sqrt(distance_squared));
    }
    error_squared_ += frame_error;
    rmse_sum_ += std::sqrt(frame_error / double(std::max<size_t>(vertex_count, 1)));
  }
}

ErrorMetrics ErrorAccumulator::result() const {
  ErrorMetrics metrics;
  metrics.vertices = vertices_;
  metrics.frames = frames_;
  metrics.kg_percent = spread_squared_ > 0 ? 100.0 * std::sqrt(error_squared_ / spread_squared_) : 0.0;
  const double diagonal = diagonal_ > 0 ? diagonal_ : 1.0;
  metrics.rmse_over_diagonal = frames_ ? rmse_sum_ / double(frames_) / diagonal : 0.0;
  metrics.max_error = max_error_;
  metrics.max_error_over_diagonal = max_error_ / diagonal;
  return metrics;
}

}  // namespace segmorph
