#include "encode/automatic_clusters.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <memory>
#include <string>

#include "common/parallel.h"
#include "common/stream_format.h"
#include "encode/motion_quantization.h"
#include "encode/rate_distortion.h"
#include "encode/segmentation/refinement.h"
#include "encode/segmentation/segmentation.h"
#include "encode/stream_writer.h"

namespace segmorph {
namespace {

// The largest candidate is the segmentation's own count, at most one cluster per kVerticesPerCluster welded vertices
// and kMaxClusters; the smallest is kMinAutomaticClusters. Lossless streams, whose size the residuals dominate, use
// kLosslessClusters.
constexpr size_t kVerticesPerCluster = 24;
constexpr size_t kMaxClusters = 256;
constexpr size_t kMinAutomaticClusters = 4;
// The most candidates tried at once (each holds its own trial stream and predictions): the search mostly stops a few
// candidates in, so more would mostly try counts it never reaches.
constexpr size_t kCandidatesAtOnce = 2;
constexpr size_t kLosslessClusters = 24;
// The frames the automatic K is estimated on: windows of kSampleWindow frames every kSampleStride frames (all frames
// when there are at most twice kSampleStride), and the motion refinement iterations of each candidate.
constexpr size_t kSampleWindow = 8;
constexpr size_t kSampleStride = 32;
constexpr int kSampleRefinements = 4;

// The frames candidates are costed on: windows of the trajectories, each coded as a clip of its own.
struct Sample {
  Trajectories frames;
  std::vector<uint32_t> clip_frames;
  double share = 0;  // of all the frames
};

Sample sample_frames(const EncodeProblem& problem) {
  Sample sample;
  sample.frames.vertex_count = problem.welded;
  const size_t welded = problem.welded;
  const bool sampled = problem.frames_total > 2 * kSampleStride;
  size_t first = 0;  // of the clip, in the trajectories
  for (const FrameSequence& clip : problem.clips) {
    const size_t stride = sampled ? kSampleStride : clip.frame_count;
    for (size_t window = 0; window < clip.frame_count; window += stride) {
      const size_t length = sampled ? std::min(clip.frame_count - window, kSampleWindow) : clip.frame_count;
      const float* from = &problem.trajectories.positions[(first + window) * welded * 3];
      sample.frames.positions.insert(sample.frames.positions.end(), from, from + length * welded * 3);
      sample.frames.frame_count += length;
      sample.clip_frames.push_back(uint32_t(length));
    }
    first += clip.frame_count;
  }
  sample.share = double(sample.frames.frame_count) / double(problem.frames_total);
  return sample;
}

// The cost of a candidate segmentation, smaller is better: with an error target, the estimated stream bits at the
// target distortion; with a rate target, the estimated log distortion at the target size. It is measured on a sample
// of the frames so that the search costs about a quarter of one full pass: the clusters refined by motion
// (kSampleRefinements iterations), motion quantized at the expected step, weights fitted (prepare: what the residual
// predictions do not change), then the closed-loop residual rate and distortion at two residual steps (the expected
// one and twice it, on every axis), interpolated in log distortion (cost: for the residual predictions `flags` allow).
class CandidateCost {
 public:
  CandidateCost(const EncodeProblem& problem, const StreamContent& content)
      : problem_(problem), content_(content), sample_(sample_frames(problem)) {}

  struct Prepared {
    StreamContent trial;  // its motion and weights quantized; its flags set by cost()
    std::unique_ptr<FramePredictions> predictions;
  };

  // On `threads` threads (the same estimate for every count); `report`: whether to report progress (one caller at
  // a time may).
  std::shared_ptr<Prepared> prepare(const Clusters& merged, size_t threads, bool report) const {
    const EncodeProblem& p = problem_;
    if (report) report_progress(p.settings, "cluster count: trying " + std::to_string(merged.count) + " clusters");
    AffineMotion motion;
    const Clusters candidate = refine_by_motion(merged, p.base_welded.data(), sample_.frames, p.adjacency,
                                                kSampleRefinements, nullptr, threads, &motion);
    auto prepared = std::make_shared<Prepared>();
    StreamContent& trial = prepared->trial;
    trial = content_;
    trial.clip_frames = sample_.clip_frames;
    trial.cluster_count = uint32_t(candidate.count);
    trial.labels = candidate.label;
    const double motion_step = kMotionStepRatio * p.mean_step;
    quantize_motion_and_weights(motion, motion_step / cluster_radius(p.base_welded, motion.centroid, candidate.label),
                                motion_step, p.base_welded, sample_.frames, candidate, p.adjacency,
                                p.settings.blend_weights, trial);
    prepared->predictions = std::make_unique<FramePredictions>(trial, p.base_welded);
    return prepared;
  }

  double cost(Prepared& prepared, uint8_t flags, size_t threads) const {
    const EncodeProblem& p = problem_;
    StreamContent& trial = prepared.trial;
    trial.flags = flags;
    const std::vector<double> steps = {p.mean_step, 2 * p.mean_step};
    SubbandCurve measured[3];
    measure_subbands(trial, p.traversal, *prepared.predictions, sample_.frames.positions, p.multiplicity,
                     {steps, steps, steps}, measured, threads);
    std::vector<uint8_t> side;
    write_stream(trial, p.base, side);
    double distortion[2], bits[2];
    for (int j = 0; j < 2; ++j) {
      distortion[j] =
          std::max(measured[0].distortion[j] + measured[1].distortion[j] + measured[2].distortion[j], 1e-300);
      bits[j] = 8.0 * double(side.size()) + measured[0].bits[j] + measured[1].bits[j] + measured[2].bits[j];
    }
    if (p.settings.mode == RateMode::error) {
      const double t =
          std::log(sample_.share * p.max_distortion() / distortion[0]) / std::log(distortion[1] / distortion[0]);
      return bits[0] + t * (bits[1] - bits[0]);
    }
    const double budget = sample_.share * (p.settings.target * double(p.vertex_count) * double(p.frames_total) -
                                           8.0 * double(p.settings.outside_bytes));
    const double t = (budget - bits[0]) / (bits[1] - bits[0]);
    return std::log(distortion[0]) + t * (std::log(distortion[1]) - std::log(distortion[0]));
  }

 private:
  const EncodeProblem& problem_;
  const StreamContent& content_;
  const Sample sample_;
};

// Candidates of the counts `counts` (merged from the segmentation) and their costs, on up to `threads` threads: a
// candidate a thread, each with its share of the threads (a cost is the same for every thread count), the first
// reporting progress when `report`.
struct Tried {
  Clusters clusters;
  double cost = 0;
  std::shared_ptr<CandidateCost::Prepared> prepared;  // for the costs of other residual predictions
};
Tried try_count(const CandidateCost& cost_of, Clusters merged, uint8_t flags, size_t threads, bool report) {
  Tried tried;
  tried.clusters = std::move(merged);
  tried.prepared = cost_of.prepare(tried.clusters, threads, report);
  tried.cost = cost_of.cost(*tried.prepared, flags, threads);
  return tried;
}
std::vector<Tried> try_counts(const ClusterMerges& merges, const CandidateCost& cost_of,
                              const std::vector<size_t>& counts, uint8_t flags, size_t threads, bool report) {
  std::vector<Tried> tried(counts.size());
  const size_t each = std::max<size_t>(1, threads / std::max<size_t>(counts.size(), 1));
  parallel_items(counts.size(), threads, [&](size_t i) {
    tried[i] = try_count(cost_of, merges.at(counts[i]), flags, each, report && i == 0);
  });
  return tried;
}

// Automatic K: more clusters cost motion side information and save residual bits. Candidates from the
// segmentation's own count down by factors of 2/3, each merged from the segmentation; the search stops at the first
// candidate that costs more than the one before. Then the geometric means of the best and its tried neighbours: the
// cost is not smooth in K, and a step of 2/3 missed K worth 7 % (Fox, 6 for 9). Returns the chosen candidate with its
// cost and what that was measured on. With several threads the search tries up to kCandidatesAtOnce counts at once, ahead of the one that stops it
// (what it chooses does not change: the costs are taken in order, those past the stop left unused).
Tried automatic_count(const EncodeProblem& problem, const Clusters& morse, const CandidateCost& cost_of,
                      uint8_t flags, size_t threads, bool report) {
  // Every count is merged from the segmentation, the smaller ones by more of the same merges.
  const ClusterMerges merges(morse, problem.base_welded.data(), problem.trajectories, problem.adjacency);
  const size_t largest =
      std::max<size_t>(1, std::min({morse.count, problem.welded / kVerticesPerCluster, kMaxClusters}));
  std::vector<size_t> counts = {largest};  // the counts the search goes down through
  for (size_t k = largest * 2 / 3; k >= kMinAutomaticClusters; k = k * 2 / 3) counts.push_back(k);
  std::vector<Tried> tried;
  auto cost_at = [&](size_t i) -> Tried& {  // tries counts[i] and the ones after it that the threads allow
    if (i >= tried.size()) {
      const size_t end = std::min({counts.size(), i + std::max<size_t>(threads, 1), i + kCandidatesAtOnce});
      std::vector<Tried> batch = try_counts(
          merges, cost_of, {counts.begin() + std::ptrdiff_t(i), counts.begin() + std::ptrdiff_t(end)}, flags, threads,
          report);
      for (Tried& t : batch) tried.push_back(std::move(t));
    }
    return tried[i];
  };
  Tried best = std::move(cost_at(0));
  size_t above = 0, below = 0;  // the tried counts next to the best one, 0 for none
  for (size_t i = 1, previous = best.clusters.count; i < counts.size(); ++i) {
    Tried& candidate = cost_at(i);
    if (!(candidate.cost < best.cost)) {
      below = candidate.clusters.count;
      break;
    }
    above = previous, previous = candidate.clusters.count;
    best = std::move(candidate);
  }
  tried.clear();  // what the others were measured on (best has been moved out)
  const size_t chosen = best.clusters.count;
  std::vector<size_t> between;  // the geometric means tried, in the order of {above, below}
  for (size_t neighbour : {above, below}) {
    const size_t k = size_t(std::lround(std::sqrt(double(neighbour) * double(chosen))));
    if (neighbour == 0 || k == neighbour || k == chosen || k < kMinAutomaticClusters) continue;
    between.push_back(k);
  }
  for (Tried& candidate : try_counts(merges, cost_of, between, flags, threads, report))
    if (candidate.cost < best.cost) best = std::move(candidate);
  return best;
}

}  // namespace

Clusters choose_clusters(const EncodeProblem& problem, const std::vector<Clusters>& segmentations,
                         StreamContent& content, size_t* chosen) {
  const CodecSettings& settings = problem.settings;
  auto merged = [&](const Clusters& morse, size_t k) {
    return merge_clusters(morse, k, problem.base_welded.data(), problem.trajectories, problem.adjacency);
  };
  assert(!segmentations.empty());
  if (chosen) *chosen = segmentations.size() - 1;
  if (settings.mode == RateMode::lossless)
    return merged(segmentations.back(), settings.clusters ? settings.clusters : kLosslessClusters);
  const CandidateCost cost_of(problem, content);
  // Each segmentation's best candidate and its cost, the segmentations on threads of their own (the threads shared
  // out among them; each estimate is the same for every thread count), the first one reporting progress.
  const size_t count = segmentations.size(), threads = thread_count(settings.threads);
  const size_t each = std::max<size_t>(1, threads / count);
  std::vector<Tried> candidates(count);
  parallel_items(count, threads, [&](size_t item) {
    const size_t s = count - 1 - item;  // the last (refined) one first
    candidates[s] = settings.clusters
                        ? try_count(cost_of, merged(segmentations[s], settings.clusters), content.flags, each, item == 0)
                        : automatic_count(problem, segmentations[s], cost_of, content.flags, each, item == 0);
  });
  // The last (refined) segmentation first: an earlier one replaces it only when estimated strictly cheaper (a tie, or
  // a cost that is not a number on a mesh of a few vertices, keeps the refined one).
  Tried best;
  for (size_t s = count; s-- > 0;)
    if (s + 1 == count || candidates[s].cost < best.cost) {
      best = std::move(candidates[s]);
      if (chosen) *chosen = s;
    }
  candidates.clear();
  // Temporal and spatial residual prediction (when allowed) are kept when the estimate says they pay: temporal does
  // for slow sequences, not always for fast ones; spatial does at higher rates, not always at low ones, where most
  // residuals quantize to zero (docs/codec.md). The estimate is biased a little against temporal prediction (each
  // sample window starts without a previous frame).
  // Measured on the chosen candidate as prepared (its refinement and motion do not depend on them).
  for (uint8_t prediction : {format::kFlagTemporalResiduals, format::kFlagSpatialResiduals}) {
    if (!(content.flags & prediction)) continue;
    const uint8_t without = uint8_t(content.flags & ~prediction);
    const double cost = cost_of.cost(*best.prepared, without, threads);
    if (cost < best.cost) content.flags = without, best.cost = cost;
  }
  return std::move(best.clusters);
}

}  // namespace segmorph
