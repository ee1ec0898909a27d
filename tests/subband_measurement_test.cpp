// The rate control's measurement of the residual subbands (measure_subbands, codec/encode/rate_distortion.h) against
// the residual loop it stands for: at each candidate step, the distortion the decoder's loop (ResidualReconstructor)
// gives that axis, and the bits of its symbols by the measurement's definition (their entropy given the magnitude
// class of the same coordinate's symbol in the frame before, plus the price of learning each context's symbols).
// The same curves on every thread count, and with or without AVX2.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "common/reconstruction.h"
#include "common/stream_format.h"
#include "encode/motion.h"
#include "encode/motion_quantization.h"
#include "encode/rate_distortion.h"
#include "encode_stage.h"

namespace segmorph {
namespace {

using namespace testing;

// The bending sphere's clusters and motion, quantized at the expected step, with the flags given.
StreamContent quantized(StageProblem& stage, uint8_t flags) {
  const Clusters clusters = choose_clusters(stage.problem, stage.segmentations, stage.content);
  const AffineMotion fitted = fit_affine_motion(stage.problem.base_welded.data(), stage.problem.trajectories, clusters, 1);
  StreamContent content = stage.content;
  content.flags = flags;
  content.cluster_count = uint32_t(clusters.count);
  content.labels = clusters.label;
  const double step = kMotionStepRatio * stage.problem.mean_step;
  quantize_motion_and_weights(fitted, step / cluster_radius(stage.problem.base_welded, fitted.centroid, clusters.label),
                              step, stage.problem.base_welded, stage.problem.trajectories, clusters,
                              stage.problem.adjacency, true, content);
  return content;
}

struct Measured {
  double distortion[3] = {0, 0, 0};
  double bits[3] = {0, 0, 0};
};

// The residual loop at `step` on every axis, run as the decoder runs it: each axis's distortion (its squared errors
// weighted by the vertices' multiplicity) and bits, by the definition the measurement estimates them with.
Measured residual_loop(const StageProblem& stage, StreamContent content, double step) {
  const EncodeProblem& p = stage.problem;
  for (float& s : content.residual_step) s = float(step);
  const FramePredictions predictions(content, p.base_welded);
  ResidualReconstructor reconstructor(content, p.traversal);
  std::map<std::pair<int, int64_t>, uint64_t> counts[3];  // per axis: (context, symbol) -> count
  double large_bits[3] = {0, 0, 0};
  Measured out;
  std::vector<double> predicted(p.welded * 3);
  std::vector<int64_t> previous(p.welded * 3, 0), current(p.welded * 3, 0);
  const double q = double(float(step));
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames) {
    reconstructor.start_clip();
    std::fill(previous.begin(), previous.end(), 0);
    for (uint32_t f = 0; f < frames; ++f, ++frame) {
      predictions.predict(frame, predicted.data());
      const float* target = &p.trajectories.positions[frame * p.welded * 3];
      reconstructor.frame(
          frame, predicted.data(),
          [&](size_t i, double prediction, double r) -> int64_t {
            const int64_t k = quantizer_index((double(target[i]) - prediction - r) * (1.0 / q));
            const int context = int(std::min<int64_t>(std::llabs(previous[i]), 2));
            if (std::llabs(k) <= 512)
              ++counts[i % 3][{context, k}];
            else
              large_bits[i % 3] += 2 * std::log2(double(std::llabs(k))) + 2;
            return current[i] = k;
          },
          [&](size_t i, float x) {
            const double error = double(x) - double(target[i]);
            out.distortion[i % 3] += double(p.multiplicity[i / 3]) * error * error;
          });
      previous.swap(current);
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    double total[3] = {0, 0, 0};
    for (const auto& [key, count] : counts[axis]) total[key.first] += double(count);
    out.bits[axis] = large_bits[axis];
    for (const auto& [key, count] : counts[axis])
      out.bits[axis] += -double(count) * std::log2(double(count) / total[key.first]) +
                        0.5 * std::log2(1 + total[key.first]);
  }
  return out;
}

// Steps a quarter octave apart around the expected one: `per_axis` on each axis, shifted between axes.
void candidate_steps(const StageProblem& stage, size_t per_axis, std::vector<double> (&steps)[3]) {
  for (int axis = 0; axis < 3; ++axis)
    for (size_t j = 0; j < per_axis; ++j)
      steps[axis].push_back(stage.problem.mean_step * std::exp2((double(j) - double(per_axis) / 2 + axis) / 4.0));
}

// With temporal and spatial prediction, without either: each lane's distortion is the loop's at its step, to the
// last bit, and its bits the definition's (summed in another order). 3 lanes a range and 9 in all use the unrolled
// walks, 6 steps an axis (18 lanes) the general one.
TEST(SubbandMeasurement, EachLaneIsTheResidualLoopAtItsStep) {
  StageProblem stage(24, CodecSettings());
  const uint8_t both = format::kFlagTemporalResiduals | format::kFlagSpatialResiduals;
  for (uint8_t flags : {both, uint8_t(0), uint8_t(format::kFlagSpatialResiduals)})
    for (size_t per_axis : {3, 6}) {
      const StreamContent content = quantized(stage, flags);
      const FramePredictions predictions(content, stage.problem.base_welded);
      std::vector<double> steps[3];
      candidate_steps(stage, per_axis, steps);
      SubbandCurve curves[3];
      measure_subbands(content, stage.problem.traversal, predictions, stage.problem.trajectories.positions,
                       stage.problem.multiplicity, steps, curves, 1);
      for (int axis = 0; axis < 3; ++axis) {
        ASSERT_EQ(curves[axis].step.size(), per_axis);
        for (size_t j = 0; j < per_axis; ++j) {
          const Measured loop = residual_loop(stage, content, steps[axis][j]);
          const std::string where = "flags " + std::to_string(flags) + ", axis " + std::to_string(axis) +
                                    ", step " + std::to_string(j) + " of " + std::to_string(per_axis);
          EXPECT_EQ(curves[axis].step[j], double(float(steps[axis][j]))) << where;
          EXPECT_EQ(curves[axis].distortion[j], loop.distortion[axis]) << where;
          EXPECT_NEAR(curves[axis].bits[j], loop.bits[axis], 1e-9 * loop.bits[axis]) << where;
          EXPECT_GT(loop.bits[axis], 0) << where;
        }
      }
    }
}

// Curves bit for bit the same on 1, 2 and 3 threads (other lane ranges, other unrolled walks) and with the baseline
// instructions only.
TEST(SubbandMeasurement, TheSameCurvesOnEveryThreadCountAndInstructionSet) {
  StageProblem stage(24, CodecSettings());
  const StreamContent content = quantized(stage, format::kFlagTemporalResiduals | format::kFlagSpatialResiduals);
  const FramePredictions predictions(content, stage.problem.base_welded);
  for (size_t per_axis : {1, 5, 7}) {
    std::vector<double> steps[3];
    candidate_steps(stage, per_axis, steps);
    auto measure = [&](size_t threads, bool allow_avx2) {
      std::vector<SubbandCurve> curves(3);
      SubbandCurve out[3];
      measure_subbands(content, stage.problem.traversal, predictions, stage.problem.trajectories.positions,
                       stage.problem.multiplicity, steps, out, threads, {}, nullptr, allow_avx2);
      for (int axis = 0; axis < 3; ++axis) curves[size_t(axis)] = out[axis];
      return curves;
    };
    const std::vector<SubbandCurve> reference = measure(1, false);
    for (const auto& [threads, allow_avx2] : {std::pair(1, true), std::pair(2, true), std::pair(3, false)}) {
      const std::vector<SubbandCurve> other = measure(size_t(threads), allow_avx2);
      for (size_t axis = 0; axis < 3; ++axis) {
        EXPECT_EQ(other[axis].step, reference[axis].step) << per_axis << " steps an axis, " << threads << " threads";
        EXPECT_EQ(other[axis].distortion, reference[axis].distortion)
            << per_axis << " steps an axis, " << threads << " threads, AVX2 " << allow_avx2;
        EXPECT_EQ(other[axis].bits, reference[axis].bits)
            << per_axis << " steps an axis, " << threads << " threads, AVX2 " << allow_avx2;
      }
    }
  }
}

}  // namespace
}  // namespace segmorph
