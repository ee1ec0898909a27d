#include "encode/frame_references.h"

#include <algorithm>
#include <cmath>

#include "common/parallel.h"
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
                                        uint32_t max_window, double step, size_t threads) {
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
  auto fill = [&](double* row, size_t frame) {
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
  // The score of predicting `now`'s residuals from those of `then` (nullptr: from zeros) on the sampled positions:
  // about the bits of what is left after the temporal and spatial predictions, log2(1 + (e / step)^2).
  auto score = [&](const double* now, const double* then) {
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
  // The coarse score: the squared difference alone, on every coarse_stride-th sampled position, summed in their order.
  // Its values are gathered once a frame into a row of their own (coarse_values); a score from zeros reads a row of
  // zeros (x − 0.0 is x). Four candidates are summed side by side, each its own sum in its own order: the same
  // doubles, without each add waiting on the one before.
  std::vector<size_t> coarse_at;  // into a residual row
  for (size_t s = 0; s < sampled.size(); s += coarse_stride) coarse_at.push_back(size_t(needed_index[sampled[s]]) * 3);
  const size_t coarse_values = coarse_at.size() * 3;
  const std::vector<double> coarse_zeros(coarse_values, 0.0);
  auto gather_coarse = [&](const double* row, double* out) {
    for (size_t c = 0; c < coarse_at.size(); ++c)
      for (size_t a = 0; a < 3; ++a) out[c * 3 + a] = row[coarse_at[c] + a];
  };
  // The coarse scores of `now` against each row of `then` into `scores`.
  auto coarse_scores = [&](const double* now, const std::vector<const double*>& then, std::vector<double>& scores) {
    scores.assign(then.size(), 0.0);
    size_t j = 0;
    for (; j + 4 <= then.size(); j += 4) {
      const double *t0 = then[j], *t1 = then[j + 1], *t2 = then[j + 2], *t3 = then[j + 3];
      double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
      for (size_t i = 0; i < coarse_values; ++i) {
        const double e0 = now[i] - t0[i], e1 = now[i] - t1[i], e2 = now[i] - t2[i], e3 = now[i] - t3[i];
        s0 += e0 * e0, s1 += e1 * e1, s2 += e2 * e2, s3 += e3 * e3;
      }
      scores[j] = s0, scores[j + 1] = s1, scores[j + 2] = s2, scores[j + 3] = s3;
    }
    for (; j < then.size(); ++j) {
      double sum = 0;
      for (size_t i = 0; i < coarse_values; ++i) {
        const double e = now[i] - then[j][i];
        sum += e * e;
      }
      scores[j] = sum;
    }
  };

  // Each frame's choice depends only on the residuals of its window: the frames split into ranges of about equal
  // work (a frame's candidates grow with its index in the clip), each range on a thread with a ring of its own,
  // filled from as far back as its first frame's window reaches. The per-frame scores are summed in frame order
  // afterwards: the same references and totals for every thread count.
  const bool temporal = content.flags & format::kFlagTemporalResiduals;
  std::vector<size_t> clip_index(frame_count);     // each frame's index in its clip
  std::vector<double> cost(frame_count + 1, 0.0);  // cumulative estimated work
  for (size_t c = 0, frame = 0; c < content.clip_frames.size(); ++c)
    for (uint32_t f = 0; f < content.clip_frames[c]; ++f, ++frame) {
      clip_index[frame] = f;
      cost[frame + 1] = cost[frame] + 1 + double(std::min<size_t>(max_window, f));
    }
  const size_t ranges = std::min(thread_count(threads), frame_count);
  std::vector<size_t> range_begin(ranges + 1, frame_count);
  for (size_t r = 0, frame = 0; r < ranges; ++r) {
    while (frame < frame_count && cost[frame] < cost[frame_count] * double(r) / double(ranges)) ++frame;
    range_begin[r] = frame;
  }
  std::vector<double> implied_scores(frame_count, 0.0), best_scores(frame_count, 0.0);
  parallel_items(ranges, ranges, [&](size_t r) {
    const size_t begin = range_begin[r], end = range_begin[r + 1];
    if (begin == end) return;
    std::vector<double> residuals(ring * needed.size() * 3), coarse_ring(ring * coarse_values);
    auto row = [&](size_t frame) { return &residuals[(frame % ring) * needed.size() * 3]; };
    auto coarse_row = [&](size_t frame) { return &coarse_ring[(frame % ring) * coarse_values]; };
    auto fill_both = [&](size_t frame) {
      fill(row(frame), frame);
      gather_coarse(row(frame), coarse_row(frame));
    };
    const size_t reach = std::min(clip_index[begin], ring - 1);  // the earlier frames the first one's window reads
    for (size_t frame = begin - reach; frame < begin; ++frame) fill_both(frame);
    std::vector<const double*> candidates;
    std::vector<double> scores;
    for (size_t frame = begin; frame < end; ++frame) {
      fill_both(frame);  // every frame, the clip's first too: later frames may reference it
      const size_t f = clip_index[frame];
      if (f == 0) continue;
      auto back_row = [&](size_t back) { return back > 0 ? row(frame - back) : nullptr; };
      const size_t implied = temporal ? 1 : 0;  // versions 1 and 2
      const size_t window = std::min<size_t>(max_window, f);
      std::vector<std::pair<double, size_t>> coarse;
      // Without temporal residuals (the cluster search measured that the previous frame does not pay), only the frames
      // further back are candidates.
      candidates.clear();
      for (size_t back = 0; back <= window; ++back)
        if (back != implied && (temporal || back != 1)) {
          coarse.emplace_back(0.0, back);
          candidates.push_back(back > 0 ? coarse_row(frame - back) : coarse_zeros.data());
        }
      coarse_scores(coarse_row(frame), candidates, scores);
      for (size_t i = 0; i < coarse.size(); ++i) coarse[i].first = scores[i];
      std::sort(coarse.begin(), coarse.end());
      const double implied_score = score(row(frame), back_row(implied));
      size_t best = implied;
      double best_score = implied_score;
      for (size_t i = 0; i < std::min(kFinalists, coarse.size()); ++i) {
        const double candidate = score(row(frame), back_row(coarse[i].second));
        if (candidate < best_score) best_score = candidate, best = coarse[i].second;
      }
      if (!(best_score <= kReferenceGain * implied_score)) best = implied, best_score = implied_score;
      implied_scores[frame] = implied_score, best_scores[frame] = best_score;
      chosen.references[frame] = uint32_t(best);
    }
  });
  const size_t implied = temporal ? 1 : 0;
  double total_implied = 0, total_best = 0;
  for (size_t frame = 0; frame < frame_count; ++frame) {
    if (clip_index[frame] == 0) continue;
    total_implied += implied_scores[frame], total_best += best_scores[frame];
    chosen.window = std::max(chosen.window, chosen.references[frame]);
    chosen.needed = chosen.needed || chosen.references[frame] != implied;
  }
  // Worth a try only when the estimate promises much: the rate control then measures whether they pay.
  chosen.needed = chosen.needed && total_best <= kPromisingShare * total_implied;
  return chosen;
}

}  // namespace segmorph
