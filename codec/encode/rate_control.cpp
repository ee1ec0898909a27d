#include "encode/rate_control.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <thread>

#include "common/parallel.h"
#include "common/reconstruction.h"
#include "common/stream_format.h"
#include "common/vertex_gather.h"
#include "encode/frame_references.h"
#include "encode/motion_quantization.h"
#include "encode/rate_distortion.h"
#include "encode/rate_target.h"
#include "encode/stream_writer.h"

namespace segmorph {
namespace {

// Frame references (stream version 3) are kept only when they promise at least 1 % fewer bytes (or, with a rate
// target, 1 % less distortion).
constexpr double kReferenceMinGain = 0.99;

// Other motion step ratios tried with an error target (which one wins depends on the sequence: docs/codec.md).
constexpr double kMotionStepRatioTrials[] = {0.25, 1.0};

// The candidate steps (raised to the finest step) that `curves` has not measured yet, each once.
void unmeasured_steps(const std::vector<double> (&candidates)[3], const SubbandCurve (&curves)[3], double finest_step,
                      std::vector<double> (&steps)[3]) {
  for (int axis = 0; axis < 3; ++axis)
    for (double candidate : candidates[axis]) {
      const double step = std::max(candidate, finest_step);
      const std::vector<double>& measured = curves[axis].step;
      if (std::find(measured.begin(), measured.end(), double(float(step))) == measured.end() &&
          std::find(steps[axis].begin(), steps[axis].end(), step) == steps[axis].end())
        steps[axis].push_back(step);
    }
}

class RateControlDriver {
 public:
  RateControlDriver(const EncodeProblem& problem, const Clusters& clusters, const AffineMotion& fitted,
                    StreamContent& content, StreamReport& report)
      : p_(problem),
        settings_(problem.settings),
        clusters_(clusters),
        fitted_(fitted),
        radius_(cluster_radius(problem.base_welded, fitted.centroid, clusters.label)),
        content_(content),
        report_(report) {}

  // The motion and residual steps, as the target mode asks.
  void choose_steps();
  // The residual symbols for the chosen steps and the stream (with a rate target, re-encoded until it lands on it).
  void encode(std::vector<uint8_t>& stream, std::vector<FrameSequence>& restored,
              const std::function<void(const StreamContent&)>& beside);

 private:
  void extend(const std::vector<double> (&candidates)[3]);
  template <typename Choose>
  void refine_steps(StepChoice& choice, Choose choose);
  void prepare_motion(double motion_step);
  void quantize_motion(double motion_step, StreamContent& content, size_t threads) const;
  void choose_references();
  void drop_references();
  void choose_motion_coding(StreamContent& content, size_t threads) const;
  double estimated_cost();
  bool keep_references();
  bool references_rejected();
  size_t side_bytes();
  size_t side_bytes_of(const StreamContent& content) const;
  void clear_residuals() {
    content_.residuals.clear();
    content_.narrow_residuals.clear();
  }
  StepChoice choose();
  void residual_rate_control(bool fresh);
  void choose_motion_step_ratio();
  void encode_residuals(std::vector<uint8_t>& stream, std::vector<FrameSequence>& restored);
  void set_residual_steps() {
    for (int axis = 0; axis < 3; ++axis) content_.residual_step[axis] = float(curves_[axis].step[choice_.index[axis]]);
  }

  const EncodeProblem& p_;
  const CodecSettings& settings_;
  const Clusters& clusters_;
  const AffineMotion& fitted_;
  const double radius_;  // RMS cluster radius: the linear step is the translation step over it
  StreamContent& content_;
  StreamReport& report_;
  double mean_step_ = 0;
  std::unique_ptr<FramePredictions> predictions_;  // of the current motion
  StepChoice choice_;
  SubbandCurve curves_[3];
  double residual_budget_ = 0;
  StreamSizes sizes_;
  bool references_chosen_ = false, references_checked_ = false;
  uint8_t flags_without_references_ = 0;
  MeasureBuffers buffers_;
};

// Measures more candidate steps of the subbands (those not measured yet; candidates[axis]) and adds them to their
// curves, all in one walk.
void RateControlDriver::extend(const std::vector<double> (&candidates)[3]) {
  std::vector<double> steps[3];
  unmeasured_steps(candidates, curves_, p_.finest_step, steps);
  const std::string stage =
      "rate control: measuring " + std::to_string(steps[0].size() + steps[1].size() + steps[2].size()) + " steps";
  report_progress(settings_, stage, 0);
  measure_subbands(content_, p_.traversal, *predictions_, p_.trajectories.positions, p_.multiplicity, steps, curves_,
                   settings_.threads, [&](double fraction) { report_progress(settings_, stage, fraction); }, &buffers_);
}

// Adds to each subband's curve the steps around its current choice (2^(j/4) apart, j = ±1, ±2), after widening the
// range while a choice sits on its edge (very low or very high targets); then chooses again.
template <typename Choose>
void RateControlDriver::refine_steps(StepChoice& choice, Choose choose) {
  for (int widen = 0; widen < 6; ++widen) {
    std::vector<double> beyond[3];
    for (int axis = 0; axis < 3; ++axis) {
      const std::vector<double>& measured = curves_[axis].step;
      const double chosen = measured[choice.index[axis]];
      const bool top = chosen == *std::max_element(measured.begin(), measured.end());
      const bool bottom = chosen == *std::min_element(measured.begin(), measured.end());
      if (!top && !bottom) continue;
      for (int j = 1; j <= 4; ++j) beyond[axis].push_back(chosen * std::exp2(top ? j : -j));
    }
    if (beyond[0].empty() && beyond[1].empty() && beyond[2].empty()) break;
    extend(beyond);
    choice = choose();
  }
  std::vector<double> fine[3];
  for (int axis = 0; axis < 3; ++axis)
    for (int j = -2; j <= 2; ++j)
      if (j != 0) fine[axis].push_back(curves_[axis].step[choice.index[axis]] * std::exp2(j / 4.0));
  extend(fine);
  choice = choose();
}

// Quantized motion and weights for a motion step (translation step; the linear step is it over the RMS cluster
// radius), and the predictions they give.
void RateControlDriver::prepare_motion(double motion_step) {
  auto begin = EncodeClock::now();
  report_progress(settings_, "rate control: quantizing the motion");
  const size_t threads = thread_count(settings_.threads);
  quantize_motion(motion_step, content_, threads);
  if (!references_chosen_) choose_references();
  choose_motion_coding(content_, threads);
  report_.ms_motion += milliseconds_since(begin);
  begin = EncodeClock::now();
  predictions_ = std::make_unique<FramePredictions>(content_, p_.base_welded);
  report_.ms_prediction += milliseconds_since(begin);
}

// The quantized motion and weights of a motion step, into `content`.
void RateControlDriver::quantize_motion(double motion_step, StreamContent& content, size_t threads) const {
  motion_step = std::max(motion_step, p_.finest_step);
  const bool lossless = settings_.mode == RateMode::lossless;
  quantize_motion_and_weights(fitted_, lossless ? 1e-6 : motion_step / radius_, lossless ? 1e-6 * radius_ : motion_step,
                              p_.base_welded, p_.trajectories, clusters_, p_.adjacency, settings_.blend_weights,
                              content, threads);
}

// Each frame's reference, once, on the first quantized motion (the motion step trials change it little): version 3's
// references when some frame gains by one (choose_frame_references's estimate, checked by keep_references() or, for
// lossless streams, by encode()), else the stream stays version 1 or 2.
void RateControlDriver::choose_references() {
  references_chosen_ = true;
  flags_without_references_ = content_.flags;
  if (!settings_.frame_references || !settings_.temporal_residuals) return;
  report_progress(settings_, "rate control: choosing each frame's reference");
  FrameReferences chosen =
      choose_frame_references(content_, p_.traversal, p_.base_welded, p_.trajectories.positions,
                              largest_reference_window(p_.vertex_count), mean_step_, settings_.threads);
  if (!chosen.needed) return;
  content_.flags |= format::kFlagFrameReferences | format::kFlagTemporalResiduals;
  content_.reference_window = chosen.window;
  content_.references = std::move(chosen.references);
}

void RateControlDriver::drop_references() {
  const uint8_t temporal = format::kFlagTemporalResiduals;
  content_.flags = uint8_t((content_.flags & ~(format::kFlagFrameReferences | temporal)) |
                           (flags_without_references_ & temporal));
  content_.reference_window = 0;
  content_.references.clear();
  choose_motion_coding(content_, thread_count(settings_.threads));
}

// The motion's coding of `content` (whose residuals it clears), whichever of version 3's takes fewest bytes: the
// plain differences, in contexts, or in contexts and predicted linearly; then the weights' coding, plain or in
// contexts (ties to the plainer, which more decoders read). The two are separate sections of the head: each is chosen
// on its own.
void RateControlDriver::choose_motion_coding(StreamContent& content, size_t threads) const {
  const uint8_t contexts = format::kFlagMotionContexts, linear = format::kFlagLinearMotion;
  const uint8_t weights = format::kFlagWeightContexts;
  content.flags &= uint8_t(~(contexts | linear | weights));
  if (!settings_.motion_contexts && !settings_.weight_contexts) return;
  // The motion's options written side by side, each from a copy of the content with its flags.
  std::vector<uint8_t> options = {content.flags};
  if (settings_.motion_contexts)
    for (uint8_t option : {contexts, uint8_t(contexts | linear)}) options.push_back(uint8_t(content.flags | option));
  std::vector<size_t> bytes(options.size());
  content.residuals.clear();
  content.narrow_residuals.clear();
  parallel_items(options.size(), threads, [&](size_t i) {
    StreamContent trial = content;
    trial.flags = options[i];
    bytes[i] = side_bytes_of(trial);
  });
  size_t best = bytes[0];
  uint8_t best_flags = options[0];
  for (size_t i = 1; i < options.size(); ++i)
    if (bytes[i] < best) best = bytes[i], best_flags = options[i];
  content.flags = best_flags;
  if (!settings_.weight_contexts || content.weight_cluster.empty()) return;
  content.flags |= weights;
  if (side_bytes_of(content) >= best) content.flags = best_flags;
}

// What the current curves promise: with an error target the stream's estimated bytes, with a rate target the
// distortion within its budget (smaller is better).
double RateControlDriver::estimated_cost() {
  if (settings_.mode == RateMode::bpvf)
    residual_budget_ = std::max(0.0, settings_.target * double(p_.vertex_count) * double(p_.frames_total) -
                                         8.0 * double(side_bytes() + settings_.outside_bytes));
  const StepChoice choice = choose();
  return settings_.mode == RateMode::error ? double(side_bytes()) + choice.bits / 8 : choice.distortion;
}

// Whether the references stay: they do if they promise a stream at least kReferenceMinGain smaller than without them,
// both measured at the steps around the ones chosen with them. An earlier frame that
// predicts a frame better breaks the chain of previous frames, which the motion's deltas and the residual code's
// contexts follow, and on short or small sequences that can cost more than it saves. Returns with the references
// dropped when they go.
bool RateControlDriver::keep_references() {
  const auto begin = EncodeClock::now();
  // Both measured at the same steps: those around the ones chosen with the references.
  std::vector<double> near[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double chosen = curves_[axis].step[choice_.index[axis]];
    for (int j = -1; j <= 1; ++j) near[axis].push_back(chosen * std::exp2(j / 4.0));
  }
  auto cost_near = [&] {
    for (SubbandCurve& curve : curves_) curve = SubbandCurve();
    extend(near);
    return estimated_cost();
  };
  const uint8_t kept_flags = content_.flags;
  const uint32_t kept_window = content_.reference_window;
  std::vector<uint32_t> kept_references = content_.references;
  const SubbandCurve with_curves[3] = {curves_[0], curves_[1], curves_[2]};
  const StepChoice with_choice = choice_;
  const double with_budget = residual_budget_;
  const double with = cost_near();
  drop_references();
  const double without = cost_near();
  report_.ms_rate_control += milliseconds_since(begin);
  if (!(with <= kReferenceMinGain * without)) return false;
  content_.flags = kept_flags, content_.reference_window = kept_window;
  content_.references = std::move(kept_references);
  for (int axis = 0; axis < 3; ++axis) curves_[axis] = with_curves[axis];
  choice_ = with_choice, residual_budget_ = with_budget;
  set_residual_steps();
  return true;
}

// Bytes of the stream without residuals (header, welding, labels, motion, weights).
size_t RateControlDriver::side_bytes() {
  clear_residuals();
  return side_bytes_of(content_);
}

// Bytes of the stream of `content`, whose residuals are cleared.
size_t RateControlDriver::side_bytes_of(const StreamContent& content) const {
  std::vector<uint8_t> side;
  write_stream(content, p_.base, side);
  return side.size();
}

StepChoice RateControlDriver::choose() {
  return settings_.mode == RateMode::error ? steps_for_distortion(curves_, p_.max_distortion())
                                           : steps_for_bits(curves_, residual_budget_);
}

// The residual steps for the current predictions: coarse candidates an octave apart around the expected step (unless
// the curves already hold measurements for these predictions), then refined.
void RateControlDriver::residual_rate_control(bool fresh) {
  const auto begin = EncodeClock::now();
  if (settings_.mode == RateMode::bpvf)
    residual_budget_ = std::max(0.0, settings_.target * double(p_.vertex_count) * double(p_.frames_total) -
                                         8.0 * double(side_bytes() + settings_.outside_bytes));
  if (fresh) {
    std::vector<double> coarse[3];
    for (int axis = 0; axis < 3; ++axis) {
      curves_[axis] = SubbandCurve();
      for (int j = -2; j <= 2; ++j) coarse[axis].push_back(mean_step_ * std::exp2(j));
    }
    extend(coarse);
  }
  choice_ = choose();
  refine_steps(choice_, [this] { return choose(); });
  set_residual_steps();
  report_.ms_rate_control += milliseconds_since(begin);
}

// With an error target the residual step is known in advance; the motion step ratio β is chosen among a few values by
// the estimated total size, each trial measured at the steps around the first's choice and the winner's measurements
// then refined.
void RateControlDriver::choose_motion_step_ratio() {
  const double guess = mean_step_;
  prepare_motion(kMotionStepRatio * guess);
  residual_rate_control(true);
  if (references_rejected()) {
    choose_motion_step_ratio();  // again, without them
    return;
  }
  const StepChoice first = choice_;
  double best_bytes = double(side_bytes()) + choice_.bits / 8;
  // The other ratios' motion, each quantized and coded from a copy of the first's content (whose references it keeps),
  // and measured at the steps around the first's choice: the trials side by side, each on its share of the threads
  // (neither a trial's motion nor its walk's curves depend on how many threads it has). The first's content and
  // predictions stay as they are, for when it wins.
  struct Trial {
    StreamContent content;
    std::unique_ptr<FramePredictions> predictions;
    size_t side_bytes = 0;
    SubbandCurve curves[3];
  };
  constexpr size_t kTrials = std::size(kMotionStepRatioTrials);
  std::vector<Trial> trials(kTrials);
  const auto begin = EncodeClock::now();
  std::vector<double> around[3], near[3];
  for (int axis = 0; axis < 3; ++axis)
    for (int j = -1; j <= 1; ++j) around[axis].push_back(curves_[axis].step[first.index[axis]] * std::exp2(j / 4.0));
  unmeasured_steps(around, {}, p_.finest_step, near);
  const std::string stage = "rate control: trying " + std::to_string(kTrials) + " motion steps";
  report_progress(settings_, stage, 0);
  const size_t threads = thread_count(settings_.threads), share = std::max<size_t>(threads / kTrials, 1);
  // The fraction told is the trials' mean, from the calling thread only, whichever trials it walks itself.
  const std::thread::id caller = std::this_thread::get_id();
  std::array<std::atomic<double>, kTrials> walked;
  for (std::atomic<double>& fraction : walked) fraction.store(0, std::memory_order_relaxed);
  parallel_items(kTrials, threads, [&](size_t t) {
    Trial& trial = trials[t];
    trial.content = content_;
    quantize_motion(kMotionStepRatioTrials[t] * guess, trial.content, share);
    choose_motion_coding(trial.content, share);
    trial.side_bytes = side_bytes_of(trial.content);
    trial.predictions = std::make_unique<FramePredictions>(trial.content, p_.base_welded);
    const bool calling = std::this_thread::get_id() == caller;
    const std::function<void(double)> progress = [&, t, calling](double fraction) {
      walked[t].store(fraction, std::memory_order_relaxed);
      if (!calling) return;
      double sum = 0;
      for (const std::atomic<double>& each : walked) sum += each.load(std::memory_order_relaxed);
      report_progress(settings_, stage, sum / kTrials);
    };
    measure_subbands(trial.content, p_.traversal, *trial.predictions, p_.trajectories.positions, p_.multiplicity, near,
                     trial.curves, share, progress);
  });
  report_progress(settings_, stage, 1);
  report_.ms_rate_control += milliseconds_since(begin);  // the trials' motion and predictions included
  size_t best = kTrials;  // kTrials: the first
  for (size_t t = 0; t < kTrials; ++t) {
    const StepChoice trial = steps_for_distortion(trials[t].curves, p_.max_distortion());
    const double bytes = double(trials[t].side_bytes) + trial.bits / 8;
    if (trial.distortion <= p_.max_distortion() && bytes < best_bytes)
      best_bytes = bytes, best = t;
  }
  if (best == kTrials) {
    choice_ = first;  // already refined
  } else {
    content_ = std::move(trials[best].content);
    predictions_ = std::move(trials[best].predictions);
    for (int axis = 0; axis < 3; ++axis) curves_[axis] = std::move(trials[best].curves[axis]);
    residual_rate_control(false);
  }
  set_residual_steps();
}

// The motion steps trade side information against prediction quality. They are tied to the residual step: motion step
// = β × mean residual step. With a rate target, two passes (the second with the first's residual steps) at
// β = kMotionStepRatio; with an error target, choose_motion_step_ratio.
// The steps, with the frame references choose_references() proposes (measured by keep_references() after the first
// rate control, and when they do not pay, the steps chosen again without them, as if they had never been proposed;
// lossless streams: encode() decides).
void RateControlDriver::choose_steps() {
  mean_step_ = p_.mean_step;
  if (settings_.mode == RateMode::lossless) {
    prepare_motion(0);
  } else if (settings_.mode == RateMode::bpvf) {
    for (int pass = 0; pass < 2; ++pass) {
      prepare_motion(kMotionStepRatio * mean_step_);
      residual_rate_control(true);
      if (references_rejected()) {
        choose_steps();  // again, without them
        return;
      }
      mean_step_ = (content_.residual_step[0] + content_.residual_step[1] + content_.residual_step[2]) / 3.0;
    }
  } else {
    choose_motion_step_ratio();
  }
}

// After the first rate control with proposed references: whether they were measured not to pay (and dropped).
bool RateControlDriver::references_rejected() {
  if (!(content_.flags & format::kFlagFrameReferences) || references_checked_) return false;
  references_checked_ = true;
  return !keep_references();
}

// Residual symbols by the decoder's own loop, then the stream; `restored` receives the reconstruction, each frame
// gathered into the clips' vertex order as it is made.
void RateControlDriver::encode_residuals(std::vector<uint8_t>& stream, std::vector<FrameSequence>& restored) {
  const bool lossless = settings_.mode == RateMode::lossless;
  const std::vector<float>& targets = p_.trajectories.positions;
  const size_t row = p_.welded * 3;
  // Lossy indices kept in 32 bits (clamped there: the finest step keeps them far inside, kFinestStepBits).
  std::vector<int64_t>& wide = content_.residuals;
  std::vector<int32_t>& narrow = content_.narrow_residuals;
  wide.clear(), narrow.clear();
  if (lossless)
    wide.resize(p_.frames_total * row);
  else
    narrow.resize(p_.frames_total * row);
  std::vector<double> predicted(2 * row);
  std::vector<float> decoded(2 * row);
  const VertexGather to_vertices(p_.topology.welded_index);
  double inverse_step[3];
  for (int axis = 0; axis < 3; ++axis) inverse_step[axis] = 1.0 / double(content_.residual_step[axis]);
  // Frame `frame`'s symbols from its targets, and where its reconstruction goes (s: 0 or 1, its place in a pair).
  auto symbol = [&](size_t frame) {
    const size_t offset = frame * row;
    return [&, offset](size_t i, double p, double r) -> int64_t {
      const float x = targets[offset + i];
      if (lossless) return wide[offset + i] = ordered_bits(x) - ordered_bits(float(p + r));
      const int64_t k = quantizer_index((double(x) - p - r) * inverse_step[i % 3]);
      return narrow[offset + i] = int32_t(std::clamp<int64_t>(k, INT32_MIN + 1, INT32_MAX));
    };
  };
  auto output = [&](size_t s) {
    float* to = &decoded[s * row];
    return [to](size_t i, float x) { to[i] = x; };
  };
  // Two frames of a clip at a time where two are left, as the decoder reconstructs them (the same values).
  ResidualReconstructor reconstructor(content_, p_.traversal);
  size_t frame = 0;
  for (size_t c = 0; c < content_.clip_frames.size(); ++c) {
    reconstructor.start_clip();
    for (uint32_t f = 0; f < content_.clip_frames[c];) {
      const uint32_t count = content_.clip_frames[c] - f >= 2 ? 2 : 1;
      for (uint32_t s = 0; s < count; ++s) predictions_->predict(frame + s, &predicted[s * row]);
      if (count == 2)
        reconstructor.two_frames(frame, &predicted[0], symbol(frame), output(0), &predicted[row], symbol(frame + 1),
                                 output(1));
      else
        reconstructor.frame(frame, &predicted[0], symbol(frame), output(0));
      for (uint32_t s = 0; s < count; ++s, ++f, ++frame) {
        to_vertices.gather(&decoded[s * row], restored[c].frame(f));
        report_progress(settings_, "coding the residuals", double(frame + 1) / double(p_.frames_total));
      }
    }
  }
  report_progress(settings_, "writing the stream");
  stream.clear();
  write_stream(content_, p_.base, stream, &sizes_);
}

void RateControlDriver::encode(std::vector<uint8_t>& stream, std::vector<FrameSequence>& restored,
                               const std::function<void(const StreamContent&)>& beside) {
  const auto start = EncodeClock::now();
  if (beside) {
    const StreamContent chosen = content_;
    parallel_items(2, thread_count(settings_.threads), [&](size_t item) {
      if (item == 0)
        encode_residuals(stream, restored);
      else
        beside(chosen);
    });
  } else {
    encode_residuals(stream, restored);
  }
  if (settings_.mode == RateMode::lossless && (content_.flags & format::kFlagFrameReferences)) {
    // A lossless stream has no rate control to estimate by: it is written with and without the references, and the
    // smaller kept (both reconstruct the frames exactly).
    std::vector<uint8_t> with = stream;
    const StreamSizes with_sizes = sizes_;
    drop_references();
    encode_residuals(stream, restored);
    if (with.size() < stream.size()) stream = std::move(with), sizes_ = with_sizes;
  }
  if (settings_.mode == RateMode::bpvf) {
    // The rate estimate is an estimate: correct the residual budget by what the coder really produced until the
    // output lands within 3 % below the target.
    const double target_bits = settings_.target * double(p_.vertex_count) * double(p_.frames_total);
    double budget = choice_.bits;
    for (int iteration = 0; iteration < 8; ++iteration) {
      const double actual = 8.0 * double(stream.size() + settings_.outside_bytes);
      if (actual <= target_bits && actual >= kBpvfLandingLow * target_bits) break;
      const double residual_actual = 8.0 * double(sizes_.residuals);
      const double residual_target = target_bits - (actual - residual_actual);
      if (!(residual_target > 0) || !(residual_actual > 0)) break;
      budget *= residual_target / residual_actual * (actual > target_bits ? 0.995 : 1.0);
      auto choose_budget = [&] { return steps_for_bits(curves_, budget); };
      choice_ = choose_budget();
      refine_steps(choice_, choose_budget);
      set_residual_steps();
      encode_residuals(stream, restored);
    }
  }
  report_.ms_entropy = milliseconds_since(start);
  report_.bytes_motion = sizes_.motion;
  report_.bytes_residuals = sizes_.residuals;
  report_.bytes_total = stream.size();
  for (int axis = 0; axis < 3; ++axis) report_.residual_steps[axis] = content_.residual_step[axis];
}

}  // namespace

void code_stream(const EncodeProblem& problem, const Clusters& clusters, const AffineMotion& fitted,
                 StreamContent& content, StreamReport& report, std::vector<uint8_t>& stream,
                 std::vector<FrameSequence>& restored,
                 const std::function<void(const StreamContent& chosen)>& beside) {
  RateControlDriver driver(problem, clusters, fitted, content, report);
  driver.choose_steps();
  driver.encode(stream, restored, beside);
}

}  // namespace segmorph
