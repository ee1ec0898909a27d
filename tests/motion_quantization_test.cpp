// The motion and the weights as a stream holds them (codec/encode/motion_quantization.h): the fitted motion
// quantized within half a step, and per vertex a few blend weights in multiples of 2^-weight_bits that predict the
// frames better than the vertex's own cluster alone.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/prediction.h"
#include "common/reconstruction.h"
#include "encode/motion.h"
#include "encode/motion_quantization.h"
#include "encode_stage.h"

namespace segmorph {
namespace {

using namespace testing;

struct Quantized {
  AffineMotion fitted;
  StreamContent content;
};

// The bending sphere's clusters and fitted motion, quantized at a translation step of `step` (the linear step the
// same displacement at the clusters' radius).
Quantized quantize(StageProblem& stage, double step, bool blend) {
  const Clusters clusters = choose_clusters(stage.problem, stage.segmentations, stage.content);
  Quantized q{fit_affine_motion(stage.problem.base_welded.data(), stage.problem.trajectories, clusters, 1),
              stage.content};
  q.content.cluster_count = uint32_t(clusters.count);
  q.content.labels = clusters.label;
  const double radius = cluster_radius(stage.problem.base_welded, q.fitted.centroid, clusters.label);
  quantize_motion_and_weights(q.fitted, step / radius, step, stage.problem.base_welded, stage.problem.trajectories,
                              clusters, stage.problem.adjacency, blend, q.content);
  return q;
}

// Σ over frames and welded vertices of the squared distance between the prediction and the trajectory.
double prediction_error(const StageProblem& stage, const StreamContent& content) {
  const AffineMotion motion = dequantized_motion(content, stage.problem.base_welded);
  const ClusterWeights weights = dequantized_weights(content);
  const Trajectories& frames = stage.problem.trajectories;
  std::vector<double> predicted(frames.vertex_count * 3);
  double error = 0;
  for (size_t f = 0; f < frames.frame_count; ++f) {
    predict_frame(stage.problem.base_welded.data(), motion, weights, f, predicted.data());
    for (size_t i = 0; i < predicted.size(); ++i) error += std::pow(predicted[i] - frames.frame(f)[i], 2);
  }
  return error;
}

TEST(MotionQuantization, MotionIsWithinHalfAStep) {
  StageProblem stage(24, CodecSettings());
  const Quantized q = quantize(stage, 1e-3, true);
  const AffineMotion motion = dequantized_motion(q.content, stage.problem.base_welded);
  ASSERT_EQ(motion.transforms.size(), q.fitted.transforms.size());
  const double linear = q.content.linear_step, translation = q.content.translation_step;
  ASSERT_GT(linear, 0);
  double largest_linear = 0, largest_translation = 0;
  for (size_t i = 0; i < motion.transforms.size(); ++i) {
    const double error = std::abs(motion.transforms[i] - q.fitted.transforms[i]);
    if (i % 4 == 3)  // [L | t] row-major: every fourth entry is t's
      largest_translation = std::max(largest_translation, error);
    else
      largest_linear = std::max(largest_linear, error);
  }
  EXPECT_LE(largest_linear, linear / 2 * (1 + 1e-9));
  EXPECT_LE(largest_translation, translation / 2 * (1 + 1e-9) + 1e-12);
  EXPECT_GT(largest_linear, linear / 8);  // the steps are the ones given, not finer
}

TEST(MotionQuantization, WithoutBlendingEachVertexFollowsItsCluster) {
  StageProblem stage(24, CodecSettings());
  const Quantized q = quantize(stage, 1e-3, false);
  const ClusterWeights weights = dequantized_weights(q.content);
  ASSERT_EQ(weights.offset.size(), stage.problem.welded + 1);
  for (size_t w = 0; w < stage.problem.welded; ++w) {
    ASSERT_EQ(weights.offset[w + 1] - weights.offset[w], 1u) << w;
    EXPECT_EQ(weights.cluster[weights.offset[w]], q.content.labels[w]);
    EXPECT_EQ(weights.weight[weights.offset[w]], 1.0);
  }
}

TEST(MotionQuantization, BlendWeightsAreFewSumToOneAndPredictBetter) {
  StageProblem stage(24, CodecSettings());
  const Quantized blended = quantize(stage, 1e-3, true), one_hot = quantize(stage, 1e-3, false);
  const ClusterWeights weights = dequantized_weights(blended.content);
  const double unit = std::ldexp(1.0, -blended.content.weight_bits);
  size_t vertices_blended = 0;
  for (size_t w = 0; w < stage.problem.welded; ++w) {
    const uint32_t count = weights.offset[w + 1] - weights.offset[w];
    EXPECT_GE(count, 1u);
    EXPECT_LE(count, 4u);
    vertices_blended += count > 1;
    double sum = 0;
    for (uint32_t i = weights.offset[w]; i < weights.offset[w + 1]; ++i) {
      sum += weights.weight[i];
      EXPECT_EQ(std::fmod(weights.weight[i], unit), 0.0) << "a multiple of 2^-weight_bits";
    }
    EXPECT_DOUBLE_EQ(sum, 1.0);
  }
  EXPECT_GT(vertices_blended, 0u);
  EXPECT_LT(prediction_error(stage, blended.content), prediction_error(stage, one_hot.content));
}

}  // namespace
}  // namespace segmorph
