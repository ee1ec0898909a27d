// The version-4 transform coding of the residuals (codec/encode/transform_coding.h): temporal bases and coefficients
// that meet a squared-error budget, checked on the decoder's frames.
#include <algorithm>
#include <memory>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/stream_format.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "encode/metrics.h"
#include "encode/motion.h"
#include "encode/rate_control.h"
#include "encode/transform_coding.h"
#include "encode_stage.h"

namespace segmorph {
namespace {

using namespace testing;

// The residual loop's content and the squared error of its frames, as encode_animation has them before it tries
// the transform.
struct LoopStream {
  StreamContent content;
  double squared = 0;
  size_t bytes = 0;
};

LoopStream residual_loop(StageProblem& stage) {
  const Clusters clusters = choose_clusters(stage.problem, stage.segmentations, stage.content);
  const AffineMotion fitted = fit_affine_motion(stage.problem.base_welded.data(), stage.problem.trajectories,
                                                clusters, 1);
  stage.content.cluster_count = uint32_t(clusters.count);
  stage.content.labels = clusters.label;
  std::vector<FrameSequence> restored = stage.clips;  // the clips' shape
  std::vector<uint8_t> stream;
  code_stream(stage.problem, clusters, fitted, stage.content, stage.report, stream, restored);
  return LoopStream{stage.content, squared_error(stage.clips, restored), stream.size()};
}

// The stream's frames, decoded, and their squared error.
double decoded_error(const StageProblem& stage, const std::vector<uint8_t>& stream) {
  std::vector<FrameSequence> frames;
  EXPECT_TRUE(decode_animation(stream.data(), stream.size(), stage.base, stage.clips[0].triangles, frames).ok());
  EXPECT_EQ(frames.size(), stage.clips.size());
  return frames.size() == stage.clips.size() ? squared_error(stage.clips, frames) : INFINITY;
}

TEST(TransformCoding, MeetsTheBudgetOnTheDecodersFrames) {
  StageProblem stage(48, CodecSettings());
  const LoopStream loop = residual_loop(stage);
  ASSERT_GT(loop.squared, 0);
  std::vector<uint8_t> stream;
  StreamSizes sizes;
  ASSERT_TRUE(try_transform_stream(stage.problem, loop.content, loop.squared, stream, sizes));
  ASSERT_GT(stream.size(), 4u);
  EXPECT_EQ(int(stream[4]), 4);  // the head's version byte (spec/bitstream.md)
  EXPECT_LE(decoded_error(stage, stream), loop.squared);
  EXPECT_LE(sizes.motion + sizes.residuals, stream.size());

  // A tighter budget: still met, with more bytes.
  std::vector<uint8_t> tighter;
  ASSERT_TRUE(try_transform_stream(stage.problem, loop.content, loop.squared / 16, tighter, sizes));
  EXPECT_LE(decoded_error(stage, tighter), loop.squared / 16);
  EXPECT_GT(tighter.size(), stream.size());
}

// The bending sphere's frames moved along 40 temporal signals that every vertex shares, each with loadings of its
// own: at a tight budget the choice takes more of the stream basis's vectors than the quarter of its eigenproblem
// (96 frames: 24 vectors) it is first found with, so the basis is found again whole, and the budget still met.
constexpr size_t kFrames = 96, kSignals = 40;

FrameSequence signals_clip() {
  FrameSequence clip = bending_clip(kFrames, 0.6, 0.0);
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  std::vector<double> loading(clip.vertex_count * 3 * kSignals), wave(kSignals * kFrames);
  for (double& x : loading) x = normal(random);
  for (double& x : wave) x = normal(random);
  for (size_t f = 0; f < kFrames; ++f)
    for (size_t i = 0; i < clip.vertex_count * 3; ++i) {
      double offset = 0;
      for (size_t s = 0; s < kSignals; ++s) offset += loading[i * kSignals + s] * wave[s * kFrames + f];
      clip.positions[f * clip.vertex_count * 3 + i] += float(0.01 * offset);
    }
  return clip;
}

TEST(TransformCoding, FindsTheStreamBasisAgainWhenAChoiceReachesItsCap) {
  CodecSettings settings;
  settings.clusters = 16;
  StageProblem stage(signals_clip(), settings);
  const LoopStream loop = residual_loop(stage);
  ASSERT_GT(loop.squared, 0);
  const double budget = loop.squared / 4;
  std::vector<uint8_t> stream;
  StreamSizes sizes;
  ASSERT_TRUE(try_transform_stream(stage.problem, loop.content, budget, stream, sizes));
  EXPECT_LE(decoded_error(stage, stream), budget);
  StreamContent content;
  ASSERT_TRUE(read_stream(stream.data(), stream.size(), stage.base, content).ok());
  EXPECT_GT(content.stream_basis.step.size(), kFrames / 4);
}

// The prelude made beside the residual loop's coding (code_stream's `beside`, as encode_animation makes it) gives
// each budget's stream the same bytes as none, once handed to several tries; also where the uncapped stream basis
// is found again from it (the signals' clip). On two threads, as the encoder makes it: the residual coding and the
// prelude side by side, and the stream basis's eigenproblem on a thread of its own.
TEST(TransformCoding, APreludeGivesTheSameStreamsAsNone) {
  for (bool signals : {false, true}) {
    SCOPED_TRACE(signals);
    CodecSettings settings;
    settings.clusters = signals ? 16 : 0;
    settings.threads = 2;
    StageProblem stage = signals ? StageProblem(signals_clip(), settings) : StageProblem(48, settings);
    const Clusters chosen = choose_clusters(stage.problem, stage.segmentations, stage.content);
    const AffineMotion fitted =
        fit_affine_motion(stage.problem.base_welded.data(), stage.problem.trajectories, chosen, 1);
    stage.content.cluster_count = uint32_t(chosen.count);
    stage.content.labels = chosen.label;
    std::vector<FrameSequence> restored = stage.clips;
    std::vector<uint8_t> loop_stream;
    std::shared_ptr<const TransformPrelude> prelude;
    int calls = 0;
    code_stream(stage.problem, chosen, fitted, stage.content, stage.report, loop_stream, restored,
                [&](const StreamContent& steps_chosen) {
                  ++calls;
                  prelude = transform_prelude(stage.problem, steps_chosen, true);
                });
    ASSERT_EQ(calls, 1);
    ASSERT_NE(prelude, nullptr);
    const double squared = squared_error(stage.clips, restored);
    size_t most_stream_vectors = 0;
    for (double budget : {squared, squared / 16, squared / 256}) {
      SCOPED_TRACE(budget);
      std::vector<uint8_t> with, without;
      StreamSizes sizes;
      const bool made_with = try_transform_stream(stage.problem, stage.content, budget, with, sizes, prelude.get());
      const bool made_without = try_transform_stream(stage.problem, stage.content, budget, without, sizes);
      EXPECT_EQ(made_with, made_without);
      EXPECT_TRUE(made_with || budget < squared);
      EXPECT_EQ(with, without);
      StreamContent content;
      if (made_with && read_stream(with.data(), with.size(), stage.base, content).ok())
        most_stream_vectors = std::max(most_stream_vectors, content.stream_basis.step.size());
    }
    if (signals) {
      EXPECT_GT(most_stream_vectors, kFrames / 4);  // beyond the cap: the uncapped basis was found
    }
  }
}

TEST(TransformCoding, SaysWhenNoStreamMeetsTheBudget) {
  StageProblem stage(48, CodecSettings());
  const LoopStream loop = residual_loop(stage);
  std::vector<uint8_t> stream;
  StreamSizes sizes;
  EXPECT_FALSE(try_transform_stream(stage.problem, loop.content, 0, stream, sizes));
}

}  // namespace
}  // namespace segmorph
