#include "common/reconstruction.h"

#include <algorithm>
#include <cassert>
#include <queue>

#include "common/stream_format.h"
#include "common/topology.h"

namespace segmorph {

ResidualTraversal residual_traversal(const StreamContent& content, const std::vector<uint32_t>& triangles) {
  WeldedTopology topology;
  topology.representative.resize(content.welded_count);  // only its size is used: W
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const uint32_t a = content.welded_index[triangles[t]], b = content.welded_index[triangles[t + 1]],
                   c = content.welded_index[triangles[t + 2]];
    if (a != b && b != c && a != c) topology.triangles.insert(topology.triangles.end(), {a, b, c});
  }
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  ResidualTraversal traversal;
  std::vector<uint32_t> position(content.welded_count, UINT32_MAX);
  for (uint32_t start = 0; start < content.welded_count; ++start) {
    if (position[start] != UINT32_MAX) continue;
    std::queue<uint32_t> queue;
    queue.push(start);
    position[start] = uint32_t(traversal.order.size());
    traversal.order.push_back(start);
    while (!queue.empty()) {
      const uint32_t u = queue.front();
      queue.pop();
      for (uint32_t i = adjacency.offset[u]; i < adjacency.offset[u + 1]; ++i) {
        const uint32_t w = adjacency.neighbour[i];
        if (position[w] != UINT32_MAX) continue;
        position[w] = uint32_t(traversal.order.size());
        traversal.order.push_back(w);
        queue.push(w);
      }
    }
  }
  traversal.earlier_offset.assign(1, 0);
  for (uint32_t v : traversal.order) {
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i)
      if (position[adjacency.neighbour[i]] < position[v]) traversal.earlier.push_back(position[adjacency.neighbour[i]]);
    traversal.earlier_offset.push_back(uint32_t(traversal.earlier.size()));
  }
  traversal.position = std::move(position);
  return traversal;
}

std::vector<float> welded_base(const std::vector<float>& base, const StreamContent& content) {
  std::vector<float> welded(size_t(content.welded_count) * 3);
  std::vector<bool> done(content.welded_count, false);
  for (size_t v = 0; v < content.welded_index.size(); ++v) {
    const uint32_t w = content.welded_index[v];
    if (done[w]) continue;
    done[w] = true;
    for (int c = 0; c < 3; ++c) welded[w * 3 + size_t(c)] = base[v * 3 + size_t(c)];
  }
  return welded;
}

AffineMotion dequantized_centroids(const StreamContent& content, const std::vector<float>& welded) {
  Clusters clusters;
  clusters.count = content.cluster_count;
  clusters.label = content.labels;
  AffineMotion motion;
  motion.cluster_count = content.cluster_count;
  motion.frame_count = content.frame_count();
  motion.centroid = cluster_centroids(welded.data(), clusters);
  return motion;
}

AffineMotion dequantized_motion(const StreamContent& content, const std::vector<float>& welded) {
  AffineMotion motion = dequantized_centroids(content, welded);
  motion.transforms.resize(content.motion.size());
  const double linear = content.linear_step, translation = content.translation_step;
  for (size_t f = 0; f < motion.frame_count; ++f)
    for (size_t k = 0; k < motion.cluster_count; ++k)
      dequantize_transform(&content.motion[(f * motion.cluster_count + k) * 12], &motion.centroid[k * 3], linear,
                           translation, motion.transform(f, k));
  return motion;
}

ClusterWeights dequantized_weights(const StreamContent& content) {
  ClusterWeights weights;
  weights.offset.assign(1, 0);
  const double unit = 1.0 / double(uint32_t(1) << content.weight_bits);
  for (size_t w = 0; w < content.welded_count; ++w) {
    // The own cluster first, with what the extra clusters leave of 1.
    int64_t extra_sum = 0;
    for (uint32_t i = content.weight_offset[w]; i < content.weight_offset[w + 1]; ++i)
      extra_sum += content.weight_value[i];
    weights.cluster.push_back(content.labels[w]);
    weights.weight.push_back(double((int64_t(1) << content.weight_bits) - extra_sum) * unit);
    for (uint32_t i = content.weight_offset[w]; i < content.weight_offset[w + 1]; ++i) {
      weights.cluster.push_back(content.weight_cluster[i]);
      weights.weight.push_back(double(content.weight_value[i]) * unit);
    }
    weights.offset.push_back(uint32_t(weights.cluster.size()));
  }
  return weights;
}

std::vector<double> predicted_frames(const StreamContent& content, const std::vector<float>& welded) {
  const AffineMotion motion = dequantized_motion(content, welded);
  const ClusterWeights weights = dequantized_weights(content);
  const size_t row = size_t(content.welded_count) * 3;
  std::vector<double> predictions(content.frame_count() * row);
  const FramePredictor predictor(welded.data(), motion, weights);
  for (size_t f = 0; f < content.frame_count(); ++f) predictor.predict(f, &predictions[f * row]);
  return predictions;
}

ResidualReconstructor::ResidualReconstructor(const StreamContent& content, const ResidualTraversal& traversal)
    : content_(content),
      traversal_(traversal),
      lossless_(content.flags & format::kFlagLossless),
      temporal_(content.flags & format::kFlagTemporalResiduals),
      spatial_(content.flags & format::kFlagSpatialResiduals),
      steps_{double(content.residual_step[0]), double(content.residual_step[1]), double(content.residual_step[2])},
      history_(size_t(reference_window(content)) + 2),
      zeros_(traversal.order.size() * 3, 0.0),
      change_(traversal.order.size() * 3, 0.0),
      second_change_(traversal.order.size() * 3, 0.0),
      inverse_count_(traversal.order.size(), 0.0) {
  for (size_t position = 0; position < inverse_count_.size(); ++position) {
    const uint32_t n = traversal.earlier_offset[position + 1] - traversal.earlier_offset[position];
    if (n > 0) inverse_count_[position] = 1.0 / double(n);
  }
}

void ResidualReconstructor::start_clip() { frame_in_clip_ = 0; }

double* ResidualReconstructor::slot(size_t in_clip) {
  // Sized as frames are reconstructed, not up front: a stream's window costs memory only for frames it really has.
  std::vector<double>& frame = history_[in_clip % history_.size()];
  if (frame.empty()) frame.resize(zeros_.size());
  return frame.data();
}

const double* ResidualReconstructor::reference(size_t frame, size_t in_clip) const {
  const uint32_t back = frame_reference(content_, frame, in_clip);
  assert(back <= in_clip && back <= history_.size() - 2);
  return back == 0 ? zeros_.data() : history_[(in_clip - back) % history_.size()].data();
}

}  // namespace segmorph
