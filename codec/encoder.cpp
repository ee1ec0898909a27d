// encode_animation: segmentation, motion, closed-loop prediction, rate control, entropy coding.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "codec.h"
#include "curvature.h"
#include "diffusion.h"
#include "laplacian.h"
#include "metrics.h"
#include "rate_control.h"
#include "reconstruction.h"
#include "refinement.h"
#include "segmentation.h"
#include "stream_format.h"
#include "topology.h"

namespace segmorph {
namespace {

using Clock = std::chrono::steady_clock;
double milliseconds_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Automatic cluster count (chosen by estimated size, docs/codec.md): the largest candidate is the segmentation's
// own count, at most one cluster per kVerticesPerCluster welded vertices and kMaxClusters; the smallest is
// kMinAutomaticClusters. Lossless streams, whose size the residuals dominate, use kLosslessClusters.
constexpr size_t kVerticesPerCluster = 24;
constexpr size_t kMaxClusters = 256;
constexpr size_t kMinAutomaticClusters = 4;
constexpr size_t kLosslessClusters = 24;
// The frames the automatic K is estimated on: windows of kSampleWindow frames every kSampleStride frames (all
// frames when there are at most twice kSampleStride), and the motion refinement iterations of each candidate.
constexpr size_t kSampleWindow = 8;
constexpr size_t kSampleStride = 32;
constexpr int kSampleRefinements = 4;
// Weights are multiples of 2^-8.
constexpr int kWeightBits = 8;
// Motion quantizer steps relative to the mean residual step: translation β q̄, linear β q̄ / (RMS radius).
constexpr double kMotionStepRatio = 0.5;
// Other ratios tried with an error target (which one wins depends on the sequence: docs/codec.md).
constexpr double kMotionStepRatioTrials[] = {0.25, 1.0};
// Lossy steps (residual and motion translation) are at least 2^-kFinestStepBits of the bounding-box diagonal of
// every position of every frame: finer than float positions resolve, they buy nothing, and they would make the
// quantized values outgrow int32 (a --bpvf target far above what the frames need got there; so did a primitive
// whose vertices all sit on one point while it moves, when the scale was the base mesh's diagonal, 0).
// Quantized motion coefficients are clamped to ±kMaxMotionCoefficient, so that frame-to-frame differences fit
// in int32 too.
constexpr int kFinestStepBits = 24;
constexpr double kMaxMotionCoefficient = double(1 << 29);

Status check_input(const std::vector<FrameSequence>& clips, const std::vector<float>& base) {
  if (clips.empty()) return Status(StatusCode::invalid_argument, "no clips to encode");
  const size_t vertex_count = clips[0].vertex_count;
  if (vertex_count == 0) return Status(StatusCode::invalid_argument, "no vertices to encode");
  if (base.size() != vertex_count * 3)
    return Status(StatusCode::invalid_argument, "the base mesh has another vertex count");
  for (const FrameSequence& clip : clips) {
    if (clip.vertex_count != vertex_count || clip.triangles != clips[0].triangles || clip.frame_count == 0 ||
        clip.positions.size() != clip.frame_count * vertex_count * 3)
      return Status(StatusCode::invalid_argument, "clips of one primitive must share vertices and triangles");
    for (float x : clip.positions)
      if (!std::isfinite(x)) return Status(StatusCode::invalid_argument, "a frame has a NaN or infinite position");
  }
  for (float x : base)
    if (!std::isfinite(x)) return Status(StatusCode::invalid_argument, "the base mesh has a NaN or infinite position");
  return Status::Ok();
}

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

// Root mean square distance of the base vertices from their cluster's centroid.
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

// The quantized motion (quantize_motion) and weights of `content`: the weights fitted (Eq. 3, or one-hot without
// blending) to the dequantized motion, as the decoder will have it.
void quantize_motion_and_weights(const AffineMotion& fitted, double linear_step, double translation_step,
                                 const std::vector<float>& base_welded, const Trajectories& frames,
                                 const Clusters& clusters, const VertexAdjacency& adjacency, bool blend,
                                 StreamContent& content) {
  quantize_motion(fitted, linear_step, translation_step, content);
  quantize_weights(
      blend ? fit_cluster_weights(base_welded.data(), frames, clusters, dequantized_motion(content, base_welded),
                                  adjacency.offset, adjacency.neighbour, 2, 4)
            : own_cluster_weights(clusters),
      content);
}

}  // namespace

// ‖A − E(A)‖²_F over the original vertices of every frame (the KG error's denominator).
double frame_spread(const std::vector<FrameSequence>& clips) {
  double spread = 0;
  for (const FrameSequence& clip : clips)
    for (size_t f = 0; f < clip.frame_count; ++f) {
      const float* frame = clip.frame(f);
      double centroid[3] = {0, 0, 0};
      for (size_t v = 0; v < clip.vertex_count; ++v)
        for (int c = 0; c < 3; ++c) centroid[c] += frame[v * 3 + size_t(c)];
      for (double& c : centroid) c /= double(clip.vertex_count);
      for (size_t v = 0; v < clip.vertex_count; ++v)
        for (int c = 0; c < 3; ++c)
          spread += (frame[v * 3 + size_t(c)] - centroid[c]) * (frame[v * 3 + size_t(c)] - centroid[c]);
    }
  return spread;
}

double expected_residual_step(const std::vector<FrameSequence>& clips, double spread, double kg_percent) {
  size_t samples = 0;
  for (const FrameSequence& clip : clips) samples += 3 * clip.vertex_count * clip.frame_count;
  return std::sqrt(12.0 * spread / double(std::max<size_t>(samples, 1))) * kg_percent / 100.0;
}

Status encode_animation(const std::vector<FrameSequence>& clips, const std::vector<float>& base,
                        const CodecSettings& settings, std::vector<uint8_t>& stream, StreamReport* report_out,
                        std::vector<FrameSequence>* reconstruction) {
  SEGMORPH_RETURN_IF_ERROR(check_input(clips, base));
  if (settings.mode != RateMode::lossless && !(settings.target > 0))
    return Status(StatusCode::invalid_argument, "the rate target must be positive");
  StreamReport report;
  const size_t vertex_count = clips[0].vertex_count;
  const WeldedTopology topology = weld_topology(clips, &base);
  const VertexAdjacency adjacency = vertex_adjacency(topology);

  StreamContent content;
  content.flags = (settings.mode == RateMode::lossless ? format::kFlagLossless : 0) |
                  (settings.temporal_residuals ? format::kFlagTemporalResiduals : 0) |
                  (settings.spatial_residuals ? format::kFlagSpatialResiduals : 0) |
                  (settings.table_residuals && settings.mode != RateMode::lossless ? format::kFlagTableResiduals : 0);
  content.vertex_count = uint32_t(vertex_count);
  content.welded_index = topology.welded_index;
  content.welded_count = uint32_t(topology.welded_count());
  for (const FrameSequence& clip : clips) content.clip_frames.push_back(uint32_t(clip.frame_count));
  const size_t welded = content.welded_count, frames_total = content.frame_count();
  if (uint64_t(frames_total) * vertex_count > format::kMaxVertexFrames)
    return Status(StatusCode::invalid_argument, "too many frames × vertices for one stream");

  // Welded trajectories, and the decoder's welded base.
  Trajectories trajectories;
  trajectories.vertex_count = welded;
  trajectories.frame_count = frames_total;
  trajectories.positions.reserve(frames_total * welded * 3);
  for (const FrameSequence& clip : clips)
    for (size_t f = 0; f < clip.frame_count; ++f)
      for (uint32_t v : topology.representative)
        for (int c = 0; c < 3; ++c) trajectories.positions.push_back(clip.frame(f)[v * 3 + size_t(c)]);
  const std::vector<float> base_welded = welded_base(base, content);
  const ResidualTraversal traversal = residual_traversal(content, clips[0].triangles);
  std::vector<uint32_t> multiplicity(welded, 0);
  for (uint32_t w : topology.welded_index) ++multiplicity[w];

  // Segmentation (on the first frame as sampled), refinement, cluster count.
  auto start = Clock::now();
  const std::vector<double> positions = welded_positions(clips[0].frame(0), topology);
  MorseFunction morse;
  SEGMORPH_RETURN_IF_ERROR(diffusion_morse_function(positions, topology, adjacency, DiffusionSettings(), morse));
  MorseBands bands;
  const MorseSettings morse_settings;
  Clusters clusters = morse_segmentation(morse.mu, topology, adjacency, morse_settings, &bands);
  report.e_pi_morse = motion_compensation_error(
      base_welded.data(), trajectories, clusters, fit_affine_motion(base_welded.data(), trajectories, clusters));
  if (settings.curvature_refinement) {
    const MorseBands refined = refine_levels(morse.mu, minimum_curvature(positions, topology), topology, adjacency,
                                             bands, RefinementSettings(), &report.refinement_iterations);
    clusters = clusters_from_levels(morse.mu, topology, adjacency, refined, morse_settings);
  }
  // The scale of the residual steps: from the target error when there is one, else from the motion error.
  const double spread = frame_spread(clips);
  double mean_step = std::sqrt(12.0 * std::max(report.e_pi_morse, 1e-12)) *
                     bounding_box_diagonal(base.data(), vertex_count) * 0.1;
  if (settings.mode == RateMode::error) mean_step = expected_residual_step(clips, spread, settings.target);
  double extent = bounding_box_diagonal(base.data(), vertex_count);
  for (const FrameSequence& clip : clips)
    extent = std::max(extent, bounding_box_diagonal(clip.positions.data(), clip.vertex_count * clip.frame_count));
  const double finest_step = std::max(extent, 1e-30) * std::exp2(-kFinestStepBits);
  mean_step = std::max(mean_step, finest_step);

  // The cost of a candidate segmentation for the automatic K, smaller is better: with an error target, the
  // estimated stream bits at the target distortion; with a rate target, the estimated log distortion at the
  // target size. It is measured on a sample of the frames (windows of kSampleWindow frames every
  // kSampleStride, each coded as a clip of its own) so that the search costs about a quarter of one full pass:
  // the clusters refined by motion (kSampleRefinements iterations), motion quantized as below at the expected
  // step, weights fitted, then the closed-loop residual rate and distortion at two residual steps (the expected
  // one and twice it, on every axis), interpolated in log distortion.
  Trajectories sample;
  sample.vertex_count = welded;
  std::vector<uint32_t> sample_clip_frames;
  {
    const bool sampled = frames_total > 2 * kSampleStride;
    size_t first = 0;  // of the clip, in the trajectories
    for (const FrameSequence& clip : clips) {
      const size_t stride = sampled ? kSampleStride : clip.frame_count;
      for (size_t window = 0; window < clip.frame_count; window += stride) {
        const size_t length = sampled ? std::min(clip.frame_count - window, kSampleWindow) : clip.frame_count;
        const float* from = &trajectories.positions[(first + window) * welded * 3];
        sample.positions.insert(sample.positions.end(), from, from + length * welded * 3);
        sample.frame_count += length;
        sample_clip_frames.push_back(uint32_t(length));
      }
      first += clip.frame_count;
    }
  }
  const double sample_share = double(sample.frame_count) / double(frames_total);
  const double max_distortion = std::pow(settings.target / 100.0, 2) * spread;
  auto candidate_cost = [&](const Clusters& merged, uint8_t flags) {
    const Clusters candidate = refine_by_motion(merged, base_welded.data(), sample, adjacency, kSampleRefinements);
    StreamContent trial = content;
    trial.flags = flags;
    trial.clip_frames = sample_clip_frames;
    trial.cluster_count = uint32_t(candidate.count);
    trial.labels = candidate.label;
    const AffineMotion motion = fit_affine_motion(base_welded.data(), sample, candidate);
    const double motion_step = kMotionStepRatio * mean_step;
    quantize_motion_and_weights(motion, motion_step / cluster_radius(base_welded, motion.centroid, candidate.label),
                                motion_step, base_welded, sample, candidate, adjacency, settings.blend_weights, trial);
    const std::vector<double> trial_predictions = predicted_frames(trial, base_welded);
    const std::vector<double> steps = {mean_step, 2 * mean_step};
    SubbandCurve measured[3];
    measure_subbands(trial, traversal, trial_predictions, sample.positions, multiplicity, {steps, steps, steps},
                     measured);
    std::vector<uint8_t> side;
    write_stream(trial, base, side);
    double distortion[2], bits[2];
    for (int j = 0; j < 2; ++j) {
      distortion[j] =
          std::max(measured[0].distortion[j] + measured[1].distortion[j] + measured[2].distortion[j], 1e-300);
      bits[j] = 8.0 * double(side.size()) + measured[0].bits[j] + measured[1].bits[j] + measured[2].bits[j];
    }
    if (settings.mode == RateMode::error) {
      const double t =
          std::log(sample_share * max_distortion / distortion[0]) / std::log(distortion[1] / distortion[0]);
      return bits[0] + t * (bits[1] - bits[0]);
    }
    const double budget = sample_share * (settings.target * double(vertex_count) * double(frames_total) -
                                          8.0 * double(settings.outside_bytes));
    const double t = (budget - bits[0]) / (bits[1] - bits[0]);
    return std::log(distortion[0]) + t * (std::log(distortion[1]) - std::log(distortion[0]));
  };
  // Temporal and spatial residual prediction (when allowed) are kept when the estimate says they pay: temporal
  // does for slow sequences, not always for fast ones; spatial does at higher rates, not always at low ones,
  // where most residuals quantize to zero (docs/codec.md). The estimate is biased a little against temporal
  // prediction (each sample window starts without a previous frame).
  if (settings.mode == RateMode::lossless) {
    clusters = merge_clusters(clusters, settings.clusters ? settings.clusters : kLosslessClusters, base_welded.data(),
                              trajectories, adjacency);
  } else {
    double best_cost;
    if (settings.clusters) {
      clusters = merge_clusters(clusters, settings.clusters, base_welded.data(), trajectories, adjacency);
      best_cost = candidate_cost(clusters, content.flags);
    } else {
      // Automatic K: more clusters cost motion side information and save residual bits. Candidates from the
      // segmentation's own count down by factors of 2/3, each merged from the segmentation; the search stops
      // at the first candidate that costs more than the one before. Then the geometric means of the best and
      // its tried neighbours: the cost is not smooth in K, and a step of 2/3 missed K worth 7 % (Fox, 6 for 9).
      const size_t largest =
          std::max<size_t>(1, std::min({clusters.count, welded / kVerticesPerCluster, kMaxClusters}));
      Clusters best = merge_clusters(clusters, largest, base_welded.data(), trajectories, adjacency);
      best_cost = candidate_cost(best, content.flags);
      size_t above = 0, below = 0;  // the tried counts next to the best one, 0 for none
      for (size_t k = largest * 2 / 3, previous = best.count; k >= kMinAutomaticClusters; k = k * 2 / 3) {
        Clusters candidate = merge_clusters(clusters, k, base_welded.data(), trajectories, adjacency);
        const double cost = candidate_cost(candidate, content.flags);
        if (!(cost < best_cost)) {
          below = candidate.count;
          break;
        }
        above = previous, previous = candidate.count;
        best = std::move(candidate), best_cost = cost;
      }
      const size_t chosen = best.count;
      for (size_t neighbour : {above, below}) {
        const size_t k = size_t(std::lround(std::sqrt(double(neighbour) * double(chosen))));
        if (neighbour == 0 || k == neighbour || k == chosen || k < kMinAutomaticClusters) continue;
        Clusters candidate = merge_clusters(clusters, k, base_welded.data(), trajectories, adjacency);
        const double cost = candidate_cost(candidate, content.flags);
        if (cost < best_cost) best = std::move(candidate), best_cost = cost;
      }
      clusters = std::move(best);
    }
    for (uint8_t prediction : {format::kFlagTemporalResiduals, format::kFlagSpatialResiduals}) {
      if (!(content.flags & prediction)) continue;
      const uint8_t without = uint8_t(content.flags & ~prediction);
      const double cost = candidate_cost(clusters, without);
      if (cost < best_cost) content.flags = without, best_cost = cost;
    }
  }
  if (settings.motion_refinement) {
    int iterations = 0;
    clusters = refine_by_motion(clusters, base_welded.data(), trajectories, adjacency, 8, &iterations);
    report.refinement_iterations += iterations;
  }
  const AffineMotion fitted = fit_affine_motion(base_welded.data(), trajectories, clusters);
  report.e_pi = motion_compensation_error(base_welded.data(), trajectories, clusters, fitted);
  report.clusters = clusters.count;
  content.cluster_count = uint32_t(clusters.count);
  content.labels = clusters.label;
  report.ms_segmentation = milliseconds_since(start);

  const double radius = cluster_radius(base_welded, fitted.centroid, clusters.label);

  std::vector<double> predictions;
  StepChoice choice;
  SubbandCurve curves[3];
  // Measures more candidate steps of the subbands (those not measured yet; candidates[axis]) and adds them to
  // their curves, all in one walk.
  auto extend = [&](const std::vector<double>(&candidates)[3]) {
    std::vector<double> steps[3];
    for (int axis = 0; axis < 3; ++axis)
      for (double candidate : candidates[axis]) {
        const double step = std::max(candidate, finest_step);
        const std::vector<double>& measured = curves[axis].step;
        if (std::find(measured.begin(), measured.end(), double(float(step))) == measured.end() &&
            std::find(steps[axis].begin(), steps[axis].end(), step) == steps[axis].end())
          steps[axis].push_back(step);
      }
    measure_subbands(content, traversal, predictions, trajectories.positions, multiplicity, steps, curves);
  };
  // Adds to each subband's curve the steps around its current choice (2^(j/4) apart, j = ±1, ±2), after
  // widening the range while a choice sits on its edge (very low or very high targets).
  auto refine = [&](StepChoice& choice_, auto choose_) {
    for (int widen = 0; widen < 6; ++widen) {
      std::vector<double> beyond[3];
      for (int axis = 0; axis < 3; ++axis) {
        const std::vector<double>& measured = curves[axis].step;
        const double chosen = measured[choice_.index[axis]];
        const bool top = chosen == *std::max_element(measured.begin(), measured.end());
        const bool bottom = chosen == *std::min_element(measured.begin(), measured.end());
        if (!top && !bottom) continue;
        for (int j = 1; j <= 4; ++j) beyond[axis].push_back(chosen * std::exp2(top ? j : -j));
      }
      if (beyond[0].empty() && beyond[1].empty() && beyond[2].empty()) break;
      extend(beyond);
      choice_ = choose_();
    }
    std::vector<double> fine[3];
    for (int axis = 0; axis < 3; ++axis)
      for (int j = -2; j <= 2; ++j)
        if (j != 0) fine[axis].push_back(curves[axis].step[choice_.index[axis]] * std::exp2(j / 4.0));
    extend(fine);
    choice_ = choose_();
  };
  // Quantized motion and weights for a motion step (translation step; the linear step is it over the RMS
  // cluster radius), and the predictions they give.
  auto prepare_motion = [&](double motion_step) {
    auto begin = Clock::now();
    motion_step = std::max(motion_step, finest_step);
    quantize_motion_and_weights(fitted, settings.mode == RateMode::lossless ? 1e-6 : motion_step / radius,
                                settings.mode == RateMode::lossless ? 1e-6 * radius : motion_step, base_welded,
                                trajectories, clusters, adjacency, settings.blend_weights, content);
    report.ms_motion += milliseconds_since(begin);
    begin = Clock::now();
    predictions = predicted_frames(content, base_welded);
    report.ms_prediction += milliseconds_since(begin);
  };
  // Bytes of the stream without residuals (header, welding, labels, motion, weights).
  auto side_bytes = [&] {
    content.residuals.clear();
    std::vector<uint8_t> side;
    write_stream(content, base, side);
    return side.size();
  };
  double residual_budget = 0;
  auto choose = [&] {
    return settings.mode == RateMode::error
               ? steps_for_distortion(curves, std::pow(settings.target / 100.0, 2) * spread)
               : steps_for_bits(curves, residual_budget);
  };
  // The residual steps for the current predictions: coarse candidates an octave apart around the expected step
  // (unless the curves already hold measurements for these predictions), then refined.
  auto residual_rate_control = [&](bool fresh) {
    const auto begin = Clock::now();
    if (settings.mode == RateMode::bpvf)
      residual_budget = std::max(0.0, settings.target * double(vertex_count) * double(frames_total) -
                                          8.0 * double(side_bytes() + settings.outside_bytes));
    if (fresh) {
      std::vector<double> coarse[3];
      for (int axis = 0; axis < 3; ++axis) {
        curves[axis] = SubbandCurve();
        for (int j = -2; j <= 2; ++j) coarse[axis].push_back(mean_step * std::exp2(j));
      }
      extend(coarse);
    }
    choice = choose();
    refine(choice, choose);
    for (int axis = 0; axis < 3; ++axis) content.residual_step[axis] = float(curves[axis].step[choice.index[axis]]);
    report.ms_rate_control += milliseconds_since(begin);
  };

  // The motion steps trade side information against prediction quality. They are tied to the residual step:
  // motion step = β × mean residual step. With a rate target, two passes (the second with the first's residual
  // steps) at β = kMotionStepRatio. With an error target the residual step is known in advance; β is chosen
  // among a few values by the estimated total size, each trial measured at the steps around the first's choice
  // and the winner's measurements then refined.
  if (settings.mode == RateMode::lossless) {
    prepare_motion(0);
  } else if (settings.mode == RateMode::bpvf) {
    for (int pass = 0; pass < 2; ++pass) {
      prepare_motion(kMotionStepRatio * mean_step);
      residual_rate_control(true);
      mean_step = (content.residual_step[0] + content.residual_step[1] + content.residual_step[2]) / 3.0;
    }
  } else {
    const double guess = mean_step;
    prepare_motion(kMotionStepRatio * guess);
    residual_rate_control(true);
    const StepChoice first = choice;
    double best_ratio = kMotionStepRatio, best_bytes = double(side_bytes()) + choice.bits / 8;
    SubbandCurve best_curves[3] = {curves[0], curves[1], curves[2]};
    const SubbandCurve first_curves[3] = {curves[0], curves[1], curves[2]};
    for (double ratio : kMotionStepRatioTrials) {
      prepare_motion(ratio * guess);
      const auto begin = Clock::now();
      std::vector<double> near[3];
      for (int axis = 0; axis < 3; ++axis) {
        curves[axis] = SubbandCurve();
        for (int j = -1; j <= 1; ++j)
          near[axis].push_back(first_curves[axis].step[first.index[axis]] * std::exp2(j / 4.0));
      }
      extend(near);
      const StepChoice trial = choose();
      report.ms_rate_control += milliseconds_since(begin);
      const double bytes = double(side_bytes()) + trial.bits / 8;
      if (trial.distortion <= max_distortion && bytes < best_bytes) {
        best_bytes = bytes, best_ratio = ratio;
        for (int axis = 0; axis < 3; ++axis) best_curves[axis] = curves[axis];
      }
    }
    prepare_motion(best_ratio * guess);
    for (int axis = 0; axis < 3; ++axis) curves[axis] = best_curves[axis];
    if (best_ratio == kMotionStepRatio)
      choice = first;  // already refined
    else
      residual_rate_control(false);
    for (int axis = 0; axis < 3; ++axis) content.residual_step[axis] = float(curves[axis].step[choice.index[axis]]);
  }

  // Residual symbols by the decoder's own loop, then the stream.
  const bool lossless = settings.mode == RateMode::lossless;
  std::vector<float> decoded(predictions.size());
  StreamSizes sizes;
  auto encode_residuals = [&] {
    content.residuals.assign(predictions.size(), 0);
    double inverse_step[3];
    for (int axis = 0; axis < 3; ++axis) inverse_step[axis] = 1.0 / double(content.residual_step[axis]);
    ResidualReconstructor reconstructor(content, traversal);
    const size_t row = welded * 3;
    size_t frame = 0;
    for (uint32_t frames_in_clip : content.clip_frames) {
      reconstructor.start_clip();
      for (uint32_t f = 0; f < frames_in_clip; ++f, ++frame) {
        const size_t offset = frame * row;
        reconstructor.frame(
            &predictions[offset],
            [&](size_t i, double p, double r) -> int64_t {
              const float x = trajectories.positions[offset + i];
              if (lossless) return content.residuals[offset + i] = ordered_bits(x) - ordered_bits(float(p + r));
              return content.residuals[offset + i] = quantizer_index((double(x) - p - r) * inverse_step[i % 3]);
            },
            [&](size_t i, float x) { decoded[offset + i] = x; });
      }
    }
    stream.clear();
    write_stream(content, base, stream, &sizes);
  };
  start = Clock::now();
  encode_residuals();
  if (settings.mode == RateMode::bpvf) {
    // The rate estimate is an estimate: correct the residual budget by what the coder really produced until
    // the output lands within 3 % below the target.
    const double target_bits = settings.target * double(vertex_count) * double(frames_total);
    double budget = choice.bits;
    for (int iteration = 0; iteration < 8; ++iteration) {
      const double actual = 8.0 * double(stream.size() + settings.outside_bytes);
      if (actual <= target_bits && actual >= 0.97 * target_bits) break;
      const double residual_actual = 8.0 * double(sizes.residuals);
      const double residual_target = target_bits - (actual - residual_actual);
      if (!(residual_target > 0) || !(residual_actual > 0)) break;
      budget *= residual_target / residual_actual * (actual > target_bits ? 0.995 : 1.0);
      auto choose_budget = [&] { return steps_for_bits(curves, budget); };
      choice = choose_budget();
      refine(choice, choose_budget);
      for (int axis = 0; axis < 3; ++axis) content.residual_step[axis] = float(curves[axis].step[choice.index[axis]]);
      encode_residuals();
    }
  }
  report.ms_entropy = milliseconds_since(start);
  report.bytes_motion = sizes.motion;
  report.bytes_residuals = sizes.residuals;
  report.bytes_total = stream.size();
  for (int axis = 0; axis < 3; ++axis) report.residual_steps[axis] = content.residual_step[axis];

  // The reconstruction, in the original vertex order, and its error.
  std::vector<FrameSequence> restored(clips.size());
  ErrorAccumulator accumulator;
  size_t frame = 0;
  for (size_t c = 0; c < clips.size(); ++c) {
    FrameSequence& clip = restored[c];
    clip.vertex_count = vertex_count;
    clip.frame_count = clips[c].frame_count;
    clip.times = clips[c].times;
    clip.triangles = clips[c].triangles;
    clip.positions.resize(clip.frame_count * vertex_count * 3);
    for (size_t f = 0; f < clip.frame_count; ++f, ++frame)
      for (size_t v = 0; v < vertex_count; ++v)
        for (int a = 0; a < 3; ++a)
          clip.positions[(f * vertex_count + v) * 3 + size_t(a)] =
              decoded[(frame * welded + topology.welded_index[v]) * 3 + size_t(a)];
    accumulator.add(clips[c], clip);
  }
  report.kg_percent = accumulator.result().kg_percent;
  if (reconstruction) *reconstruction = std::move(restored);
  if (report_out) *report_out = report;
  return Status::Ok();
}

}  // namespace segmorph
