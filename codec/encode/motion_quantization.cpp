#include "encode/motion_quantization.h"

#include <algorithm>
#include <cmath>

#include "common/reconstruction.h"
#include "common/stream_format.h"

namespace segmorph {
namespace {

// Weights are multiples of 2^-8.
constexpr int kWeightBits = 8;
// Quantized motion coefficients are clamped to ±kMaxMotionCoefficient, so that frame-to-frame differences fit in
// int32 (the encoder's steps are never finer than 2^-24 of the sequence's extent either: encoder.cpp).
constexpr double kMaxMotionCoefficient = double(1 << 29);

// A motion coefficient in quantizer steps, rounded and clamped (a fit that is not finite quantizes to 0).
int32_t quantized_coefficient(double steps) {
  if (!std::isfinite(steps)) return 0;
  return int32_t(std::llround(std::clamp(steps, -kMaxMotionCoefficient, kMaxMotionCoefficient)));
}

void quantize_motion(const AffineMotion& fitted, double linear_step, double translation_step, StreamContent& content) {
  content.linear_step = float(linear_step);
  content.translation_step = float(translation_step);
  const double linear = content.linear_step, translation = content.translation_step;
  content.motion.resize(fitted.transforms.size());
  for (size_t f = 0; f < fitted.frame_count; ++f)
    for (size_t k = 0; k < fitted.cluster_count; ++k) {
      const double* t = fitted.transform(f, k);
      int32_t* q = &content.motion[(f * fitted.cluster_count + k) * 12];
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
          q[r * 3 + c] = quantized_coefficient((t[r * 4 + c] - (r == c ? 1.0 : 0.0)) / linear);
        q[9 + r] = quantized_coefficient((t[r * 4 + 3] - fitted.centroid[k * 3 + size_t(r)]) / translation);
      }
    }
}

}  // namespace

double cluster_radius(const std::vector<float>& base_welded, const std::vector<double>& centroid,
                      const std::vector<uint32_t>& labels) {
  double sum = 0;
  for (size_t w = 0; w < labels.size(); ++w)
    for (int c = 0; c < 3; ++c) {
      const double d = base_welded[w * 3 + size_t(c)] - centroid[labels[w] * 3 + size_t(c)];
      sum += d * d;
    }
  return std::sqrt(sum / double(std::max<size_t>(labels.size(), 1))) + 1e-30;
}

namespace {

void quantize_weights(const ClusterWeights& weights, StreamContent& content) {
  content.weight_bits = kWeightBits;
  const double scale = double(1 << kWeightBits);
  content.weight_offset.assign(1, 0);
  content.weight_cluster.clear();
  content.weight_value.clear();
  for (size_t w = 0; w < content.welded_count; ++w) {
    // The extra clusters with the largest weights, at most kMaxExtraWeights, rounded; zeros dropped.
    std::vector<std::pair<double, uint32_t>> extra;
    for (uint32_t i = weights.offset[w]; i < weights.offset[w + 1]; ++i)
      if (weights.cluster[i] != content.labels[w]) extra.push_back({weights.weight[i], weights.cluster[i]});
    std::sort(extra.begin(), extra.end(),
              [](const auto& a, const auto& b) { return std::fabs(a.first) > std::fabs(b.first); });
    extra.resize(std::min<size_t>(extra.size(), format::kMaxExtraWeights));
    std::sort(extra.begin(), extra.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
    for (const auto& [weight, cluster] : extra) {
      const int32_t value = int32_t(std::llround(weight * scale));
      if (value == 0) continue;
      content.weight_cluster.push_back(cluster);
      content.weight_value.push_back(std::clamp(value, -(1 << 20), 1 << 20));
    }
    content.weight_offset.push_back(uint32_t(content.weight_cluster.size()));
  }
}

}  // namespace

void quantize_motion_and_weights(const AffineMotion& fitted, double linear_step, double translation_step,
                                 const std::vector<float>& base_welded, const Trajectories& frames,
                                 const Clusters& clusters, const VertexAdjacency& adjacency, bool blend,
                                 StreamContent& content, size_t threads) {
  quantize_motion(fitted, linear_step, translation_step, content);
  quantize_weights(
      blend ? fit_cluster_weights(base_welded.data(), frames, clusters, dequantized_motion(content, base_welded),
                                  adjacency.offset, adjacency.neighbour, 2, 4, threads)
            : own_cluster_weights(clusters),
      content);
}

}  // namespace segmorph
