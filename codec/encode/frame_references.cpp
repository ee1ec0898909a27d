#include "encode/frame_references.h"

#include <algorithm>
#include <cmath>

#include "common/stream_format.h"

namespace segmorph {
namespace {

// A frame other than the previous one becomes the reference only when it leaves at most this share of the
// previous frame's score (a smaller gain is not worth breaking the chain of previous frames, which the residual
// code's contexts follow).
constexpr double kReferenceGain = 0.5;
// The references are proposed only when, on the whole sequence, they leave at most this share of the estimated
// bits: the rate control then measures whether they pay, which costs a second step search when they do not.
constexpr double kPromisingShare = 0.9;
// Sampled positions: the squared difference of every candidate distance on kCoarseSample of them, then the score
// of the best kFinalists and of the implied reference on kSample (with their earlier neighbours, for the spatial
// prediction).
constexpr size_t kCoarseSample = 256;
constexpr size_t kSample = 512;
constexpr size_t kFinalists = 2;

// The positions the scores read: every stride-th of the traversal (sampled), and those whose residuals their scores
// read, with spatial residuals their earlier neighbours too (needed; needed_index: each position's place there, or
// UINT32_MAX).
struct ScoredPositions {
  std::vector<uint32_t> sampled, needed_index, needed;
};

ScoredPositions scored_positions(const ResidualTraversal& traversal, size_t welded, bool spatial) {
  ScoredPositions out;
  out.needed_index.assign(welded, UINT32_MAX);
  auto need = [&](uint32_t position) {
    if (out.needed_index[position] == UINT32_MAX)
      out.needed_index[position] = uint32_t(out.needed.size()), out.needed.push_back(position);
  };
  const size_t stride = std::max<size_t>(1, welded / kSample);
  for (size_t position = 0; position < welded; position += stride) {
    out.sampled.push_back(uint32_t(position));
    need(uint32_t(position));
    if (spatial)
      for (uint32_t j = traversal.earlier_offset[position]; j < traversal.earlier_offset[position + 1]; ++j)
        need(traversal.earlier[j]);
  }
  return out;
}

}  // namespace

uint32_t largest_reference_window(size_t vertices) {
  const uint64_t window = format::kMaxReferenceWindowVertices / std::max<uint64_t>(vertices, 1);
  return uint32_t(std::clamp<uint64_t>(window, 1, format::kMaxReferenceDistance));
}

FrameReferences choose_frame_references(const StreamContent& content, const ResidualTraversal& traversal,
                                        const std::vector<float>& base_welded, const std::vector<float>& targets,
                                        uint32_t max_window, double step) {
  FrameReferences chosen;
  const double inverse_step_squared = 1 / (step * step);
  const size_t welded = content.welded_count, frame_count = content.frame_count();
  chosen.references.assign(frame_count, 0);
  const bool spatial = content.flags & format::kFlagSpatialResiduals;
  const ScoredPositions positions = scored_positions(traversal, welded, spatial);
  const std::vector<uint32_t>& sampled = positions.sampled;
  const std::vector<uint32_t>& needed_index = positions.needed_index;
  const std::vector<uint32_t>& needed = positions.needed;
  const size_t coarse_stride = std::max<size_t>(1, sampled.size() / kCoarseSample);

  // Open-loop residuals of the needed positions, frame by frame, the last max_window + 1 frames in a ring.
  const AffineMotion motion = dequantized_motion(content, base_welded);
  const ClusterWeights weights = dequantized_weights(content);
  const size_t longest = *std::max_element(content.clip_frames.begin(), content.clip_frames.end());
  const size_t ring = std::min<size_t>(max_window, longest) + 1;
  std::vector<double> residuals(ring * needed.size() * 3);
  auto residual_row = [&](size_t frame) { return &residuals[(frame % ring) * needed.size() * 3]; };
  auto fill = [&](size_t frame) {
    double* row = residual_row(frame);
    for (size_t n = 0; n < needed.size(); ++n) {
      const uint32_t v = traversal.order[needed[n]];
      double predicted[3] = {0, 0, 0};
      for (uint32_t i = weights.offset[v]; i < weights.offset[v + 1]; ++i) {
        const uint32_t k = weights.cluster[i];
        const double* t = motion.transform(frame, k);
        double x[3];
        for (int a = 0; a < 3; ++a) x[a] = double(base_welded[v * 3 + size_t(a)]) - motion.centroid[k * 3 + size_t(a)];
        for (int r = 0; r < 3; ++r)
          predicted[r] +=
              weights.weight[i] * (t[r * 4] * x[0] + t[r * 4 + 1] * x[1] + t[r * 4 + 2] * x[2] + t[r * 4 + 3]);
      }
      for (int a = 0; a < 3; ++a)
        row[n * 3 + size_t(a)] = double(targets[(frame * welded + v) * 3 + size_t(a)]) - predicted[a];
    }
  };
  // The score of predicting `frame`'s residuals from those of `frame` − back (0: from zeros) on the sampled
  // positions: about the bits of what is left after the temporal and spatial predictions, log2(1 + (e / step)^2).
  auto score = [&](size_t frame, size_t back) {
    const double* now = residual_row(frame);
    const double* then = back > 0 ? residual_row(frame - back) : nullptr;
    auto difference = [&](uint32_t position, int a) {
      const size_t at = size_t(needed_index[position]) * 3 + size_t(a);
      return then ? now[at] - then[at] : now[at];
    };
    double sum = 0;
    for (const uint32_t position : sampled) {
      const uint32_t begin = traversal.earlier_offset[position], end = traversal.earlier_offset[position + 1];
      for (int a = 0; a < 3; ++a) {
        double e = difference(position, a);
        if (spatial && end > begin) {
          double mean = 0;
          for (uint32_t j = begin; j < end; ++j) mean += difference(traversal.earlier[j], a);
          e -= mean / double(end - begin);
        }
        sum += std::log2(1 + e * e * inverse_step_squared);
      }
    }
    return sum;
  };

  // The coarse score: the squared difference alone, on every coarse_stride-th sampled position.
  auto coarse_score = [&](size_t frame, size_t back) {
    const double* now = residual_row(frame);
    const double* then = back > 0 ? residual_row(frame - back) : nullptr;
    double sum = 0;
    for (size_t s = 0; s < sampled.size(); s += coarse_stride) {
      const size_t at = size_t(needed_index[sampled[s]]) * 3;
      for (size_t a = 0; a < 3; ++a) {
        const double e = then ? now[at + a] - then[at + a] : now[at + a];
        sum += e * e;
      }
    }
    return sum;
  };

  const bool temporal = content.flags & format::kFlagTemporalResiduals;
  double total_implied = 0, total_best = 0;
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames)
    for (uint32_t f = 0; f < frames; ++f, ++frame) {
      fill(frame);  // every frame, the clip's first too: later frames may reference it
      if (f == 0) continue;
      const size_t implied = temporal ? 1 : 0;  // versions 1 and 2
      const size_t window = std::min<size_t>(max_window, f);
      std::vector<std::pair<double, size_t>> coarse;
      // Without temporal residuals (the cluster search measured that the previous frame does not pay), only the frames
      // further back are candidates.
      for (size_t back = 0; back <= window; ++back)
        if (back != implied && (temporal || back != 1)) coarse.emplace_back(coarse_score(frame, back), back);
      std::sort(coarse.begin(), coarse.end());
      const double implied_score = score(frame, implied);
      size_t best = implied;
      double best_score = implied_score;
      for (size_t i = 0; i < std::min(kFinalists, coarse.size()); ++i) {
        const double candidate = score(frame, coarse[i].second);
        if (candidate < best_score) best_score = candidate, best = coarse[i].second;
      }
      if (!(best_score <= kReferenceGain * implied_score)) best = implied, best_score = implied_score;
      total_implied += implied_score, total_best += best_score;
      chosen.references[frame] = uint32_t(best);
      chosen.window = std::max(chosen.window, uint32_t(best));
      chosen.needed = chosen.needed || best != implied;
    }
  // Worth a try only when the estimate promises much: the rate control then measures whether they pay.
  chosen.needed = chosen.needed && total_best <= kPromisingShare * total_implied;
  return chosen;
}

}  // namespace segmorph
