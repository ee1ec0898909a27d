// encode_animation: the stages in order (segmentation and its refinement, the cluster count, motion, the rate-control
// driver that codes the stream, the reconstruction); the stages' own files do the work.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "common/parallel.h"
#include "common/reconstruction.h"
#include "common/stream_format.h"
#include "common/topology.h"
#include "decode/frame_decoder.h"
#include "encode/automatic_clusters.h"
#include "encode/encode_problem.h"
#include "encode/encoder.h"
#include "encode/metrics.h"
#include "encode/rate_control.h"
#include "encode/rate_distortion.h"
#include "encode/segmentation/curvature.h"
#include "encode/segmentation/diffusion.h"
#include "encode/segmentation/laplacian.h"
#include "encode/segmentation/refinement.h"
#include "encode/segmentation/segmentation.h"
#include "encode/transform_coding.h"

namespace segmorph {
namespace {

// Lossy steps (residual and motion translation) are at least 2^-kFinestStepBits of the bounding-box diagonal of
// every position of every frame: finer than float positions resolve, they buy nothing, and they would make the
// quantized values outgrow int32 (a --bpvf target far above what the frames need got there; so did a primitive
// whose vertices all sit on one point while it moves, when the scale was the base mesh's diagonal, 0).
// Quantized motion coefficients are clamped too (motion_quantization.cpp).
constexpr int kFinestStepBits = 24;

// The transform's prelude (transform_prelude) is made beside the residual loop's coding, with more than one thread,
// when its rows take at most this many bytes; beyond, after it, as the transform's first step: the residual symbols
// (as large as the frames) are freed by then, and the two would otherwise be held at once.
constexpr uint64_t kPreludeBytes = uint64_t(256) << 20;

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

}  // namespace

// ‖A − E(A)‖²_F over the original vertices of every frame (the KG error's denominator, as ErrorAccumulator sums it).
double frame_spread(const std::vector<FrameSequence>& clips) {
  double spread = 0;
  for (const FrameSequence& clip : clips)
    for (size_t f = 0; f < clip.frame_count; ++f) add_frame_spread(clip.frame(f), clip.vertex_count, spread);
  return spread;
}

double expected_residual_step(const std::vector<FrameSequence>& clips, double spread, double kg_percent) {
  size_t samples = 0;
  for (const FrameSequence& clip : clips) samples += 3 * clip.vertex_count * clip.frame_count;
  return std::sqrt(12.0 * spread / double(std::max<size_t>(samples, 1))) * kg_percent / 100.0;
}

Status set_up_problem(EncodeProblem& p, StreamContent& content) {
  const CodecSettings& settings = p.settings;
  p.vertex_count = p.clips[0].vertex_count;
  p.topology = weld_topology(p.clips, &p.base);
  p.adjacency = vertex_adjacency(p.topology);
  content.flags = (settings.mode == RateMode::lossless ? format::kFlagLossless : 0) |
                  (settings.temporal_residuals ? format::kFlagTemporalResiduals : 0) |
                  (settings.spatial_residuals ? format::kFlagSpatialResiduals : 0) |
                  (settings.table_residuals && settings.mode != RateMode::lossless ? format::kFlagTableResiduals : 0);
  content.vertex_count = uint32_t(p.vertex_count);
  content.welded_index = p.topology.welded_index;
  content.welded_count = uint32_t(p.topology.welded_count());
  for (const FrameSequence& clip : p.clips) content.clip_frames.push_back(uint32_t(clip.frame_count));
  p.welded = content.welded_count, p.frames_total = content.frame_count();
  if (uint64_t(p.frames_total) * p.vertex_count > format::kMaxVertexFrames)
    return Status(StatusCode::invalid_argument, "too many frames × vertices for one stream");
  // Welded trajectories, and the decoder's welded base.
  p.trajectories.vertex_count = p.welded;
  p.trajectories.frame_count = p.frames_total;
  p.trajectories.positions.reserve(p.frames_total * p.welded * 3);
  for (const FrameSequence& clip : p.clips)
    for (size_t f = 0; f < clip.frame_count; ++f)
      for (uint32_t v : p.topology.representative)
        for (int c = 0; c < 3; ++c) p.trajectories.positions.push_back(clip.frame(f)[v * 3 + size_t(c)]);
  p.base_welded = welded_base(p.base, content);
  p.traversal = residual_traversal(content, p.clips[0].triangles);
  p.multiplicity.assign(p.welded, 0);
  for (uint32_t w : p.topology.welded_index) ++p.multiplicity[w];
  return Status::Ok();
}

Status segment_first_frame(const EncodeProblem& p, std::vector<Clusters>& segmentations, StreamReport& report) {
  const std::vector<double> positions = welded_positions(p.clips[0].frame(0), p.topology);
  report_progress(p.settings, "segmentation: heat diffusion (" + std::to_string(p.welded) + " vertices)");
  DiffusionSettings diffusion;
  diffusion.progress = [&](const std::string& step) { report_progress(p.settings, "segmentation: " + step); };
  diffusion.threads = p.settings.threads;
  MorseFunction morse;
  SEGMORPH_RETURN_IF_ERROR(diffusion_morse_function(positions, p.topology, p.adjacency, diffusion, morse));
  MorseBands bands;
  const MorseSettings morse_settings;
  report_progress(p.settings, "segmentation: Morse levels");
  segmentations.assign(1, morse_segmentation(morse.mu, p.topology, p.adjacency, morse_settings, &bands));
  report.e_pi_morse = motion_compensation_error(
      p.base_welded.data(), p.trajectories, segmentations[0],
      fit_affine_motion(p.base_welded.data(), p.trajectories, segmentations[0], p.settings.threads));
  if (p.settings.curvature_refinement) {
    report_progress(p.settings, "segmentation: concavity refinement");
    RefinementSettings refinement;
    if (p.settings.refinement_level_curves) refinement.profile = ConcavityProfile::level_curves;
    const MorseBands refined = refine_levels(positions, morse.mu, minimum_curvature(positions, p.topology), p.topology,
                                             p.adjacency, bands, refinement, &report.curvature_refinement_passes);
    Clusters clusters = clusters_from_levels(morse.mu, p.topology, p.adjacency, refined, morse_settings);
    if (!p.settings.choose_segmentation)
      segmentations.assign(1, std::move(clusters));
    else if (clusters.label != segmentations[0].label)  // levels left where they were: nothing to choose between
      segmentations.push_back(std::move(clusters));
    report.curvature_refined = true;
  }
  return Status::Ok();
}

void set_step_scales(EncodeProblem& p, double e_pi_morse) {
  p.spread = frame_spread(p.clips);
  p.mean_step =
      std::sqrt(12.0 * std::max(e_pi_morse, 1e-12)) * bounding_box_diagonal(p.base.data(), p.vertex_count) * 0.1;
  if (p.settings.mode == RateMode::error) p.mean_step = expected_residual_step(p.clips, p.spread, p.settings.target);
  double extent = bounding_box_diagonal(p.base.data(), p.vertex_count);
  for (const FrameSequence& clip : p.clips)
    extent = std::max(extent, bounding_box_diagonal(clip.positions.data(), clip.vertex_count * clip.frame_count));
  p.finest_step = std::max(extent, 1e-30) * std::exp2(-kFinestStepBits);
  p.mean_step = std::max(p.mean_step, p.finest_step);
}

namespace {

// Clips shaped as the input's (frame times, triangles, positions sized) for the decoder's frames.
std::vector<FrameSequence> shaped_like(const std::vector<FrameSequence>& clips) {
  std::vector<FrameSequence> shaped(clips.size());
  for (size_t c = 0; c < clips.size(); ++c) {
    shaped[c].vertex_count = clips[c].vertex_count;
    shaped[c].frame_count = clips[c].frame_count;
    shaped[c].times = clips[c].times;
    shaped[c].triangles = clips[c].triangles;
    shaped[c].positions.resize(clips[c].positions.size());
  }
  return shaped;
}

// Version 4: the residual loop's stream replaced by the transform section's where that is smaller at no more squared
// error (transform_coding.h), or with gpu_playable always (failing where there is none). Takes the content over.
// `prelude`: transform_prelude's of the content, if made; released once the tries are done.
Status try_transform(const EncodeProblem& problem, StreamContent&& content,
                     std::shared_ptr<const TransformPrelude> prelude, std::vector<uint8_t>& stream,
                     std::vector<FrameSequence>& restored, StreamReport& report) {
  const auto start = EncodeClock::now();
  report_progress(problem.settings, "transform residuals");
  std::vector<uint8_t> candidate;
  StreamSizes sizes;
  const bool required = problem.settings.gpu_playable;
  const double budget = squared_error(problem.clips, restored);
  bool made;
  if (!required) {
    made = try_transform_stream(problem, std::move(content), budget, candidate, sizes, prelude.get());
  } else {
    // transform_content drops the residual symbols (as large as the frames): without them, copies are small.
    content.residuals = std::vector<int64_t>();
    content.narrow_residuals = std::vector<int32_t>();
    // First as without the setting (a primitive that gets version 4 anyway gets the same stream); else at the error
    // target (the residual loop may have come closer to the frames, or to zero error), then tighter: a stream of
    // almost no residuals can be shorter than the format allows for its vertex frames (kMaxVertexFramesPerByte).
    if (prelude == nullptr)  // made once for every try below
      prelude = transform_prelude(problem, content, thread_count(problem.settings.threads) > 1);
    made = try_transform_stream(problem, content, budget, candidate, sizes, prelude.get());
    const double target = frame_spread(problem.clips) * std::pow(problem.settings.target / 100.0, 2);
    for (int tighter = 0; !made && tighter < 5; ++tighter)
      made = try_transform_stream(problem, content, std::max(budget, target) * std::pow(1.0 / 16, tighter), candidate,
                                  sizes, prelude.get());
  }
  prelude.reset();
  if (required && !made)
    return Status(StatusCode::unsupported,
                  "no GPU-playable (version-4) stream reaches the error target within the format's limits (2048 "
                  "frames, its bases' entries and coefficients); without the GPU-playable setting this primitive "
                  "gets stream version 3");
  if (made && (required || candidate.size() < stream.size())) {
    // Its frames replace the residual loop's: the decoder's, decoded where the residual loop's were, in place.
    const Status decoded = decode_animation_into(candidate.data(), candidate.size(), problem.base,
                                                 problem.clips[0].triangles, restored, problem.settings.threads);
    if (!decoded.ok())
      return Status(StatusCode::internal,
                    "the version-4 stream the encoder measured does not decode: " + decoded.message());
    stream = std::move(candidate);
    report.bytes_motion = sizes.motion;
    report.bytes_residuals = sizes.residuals;
    report.bytes_total = stream.size();
    ErrorAccumulator accumulator;
    for (size_t c = 0; c < restored.size(); ++c) accumulator.add(problem.clips[c], restored[c]);
    report.kg_percent = accumulator.result().kg_percent;
    for (double& step : report.residual_steps) step = 0;
  }
  report.ms_entropy += milliseconds_since(start);
  return Status::Ok();
}

}  // namespace

Status encode_animation(const std::vector<FrameSequence>& clips, const std::vector<float>& base,
                        const CodecSettings& settings, std::vector<uint8_t>& stream, StreamReport* report_out,
                        std::vector<FrameSequence>* reconstruction) {
  SEGMORPH_RETURN_IF_ERROR(check_input(clips, base));
  if (settings.mode != RateMode::lossless && !(settings.target > 0))
    return Status(StatusCode::invalid_argument, "the rate target must be positive");
  if (settings.gpu_playable &&
      (!settings.transform_residuals || settings.mode != RateMode::error || settings.table_residuals))
    return Status(StatusCode::invalid_argument,
                  "a GPU-playable stream (version 4) needs an error target, transform residuals and no table code");
  if (settings.transform_sample_rows < 3)
    return Status(StatusCode::invalid_argument, "transform_sample_rows must be at least 3 (one vertex)");
  StreamReport report;
  EncodeProblem problem(clips, base, settings);
  StreamContent content;
  SEGMORPH_RETURN_IF_ERROR(set_up_problem(problem, content));

  // Segmentation, refinement, cluster count (and the residual predictions that pay).
  const auto start = EncodeClock::now();
  std::vector<Clusters> segmentations;
  SEGMORPH_RETURN_IF_ERROR(segment_first_frame(problem, segmentations, report));
  set_step_scales(problem, report.e_pi_morse);
  size_t chosen = 0;
  Clusters clusters = choose_clusters(problem, segmentations, content, &chosen);
  // The refined clusters are the last segmentation, when there is one.
  report.curvature_refined = report.curvature_refined && chosen + 1 == segmentations.size();
  AffineMotion fitted;
  if (settings.motion_refinement) {
    report_progress(settings, "motion refinement");
    clusters = refine_by_motion(clusters, problem.base_welded.data(), problem.trajectories, problem.adjacency, 8,
                                &report.motion_refinement_iterations, settings.threads, &fitted);
  } else {
    report_progress(settings, "motion fit");
    fitted = fit_affine_motion(problem.base_welded.data(), problem.trajectories, clusters, settings.threads);
  }
  report.e_pi = motion_compensation_error(problem.base_welded.data(), problem.trajectories, clusters, fitted);
  report.clusters = clusters.count;
  content.cluster_count = uint32_t(clusters.count);
  content.labels = clusters.label;
  report.ms_segmentation = milliseconds_since(start);

  // Motion and residual steps, residual symbols, the stream; the decoder's frames and their KG error.
  // The transform's budget is the residual loop's error, but what it first finds depends on the motion alone: that is
  // made while the residual loop codes its symbols (unless its rows would take more than kPreludeBytes).
  std::vector<FrameSequence> restored = shaped_like(clips);
  const bool transform = settings.transform_residuals && settings.mode == RateMode::error && !settings.table_residuals;
  std::shared_ptr<const TransformPrelude> prelude;
  std::function<void(const StreamContent&)> beside;
  if (transform && thread_count(settings.threads) > 1 &&
      uint64_t(problem.welded) * 3 * problem.frames_total * sizeof(float) <= kPreludeBytes)
    beside = [&](const StreamContent& steps_chosen) { prelude = transform_prelude(problem, steps_chosen, true); };
  code_stream(problem, clusters, fitted, content, report, stream, restored, beside);
  ErrorAccumulator accumulator;
  for (size_t c = 0; c < clips.size(); ++c) accumulator.add(clips[c], restored[c]);
  report.kg_percent = accumulator.result().kg_percent;
  if (transform)
    SEGMORPH_RETURN_IF_ERROR(try_transform(problem, std::move(content), std::move(prelude), stream, restored, report));
  content = StreamContent();  // its residual symbols are as large as the frames
  if (reconstruction) *reconstruction = std::move(restored);
  if (report_out) *report_out = report;
  return Status::Ok();
}

}  // namespace segmorph
