// The cluster count and residual predictions chosen by estimated size (codec/encode/automatic_clusters.h).
#include <vector>

#include <gtest/gtest.h>

#include "common/stream_format.h"
#include "encode/automatic_clusters.h"
#include "encode_stage.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

using namespace testing;

size_t morse_count(const StageProblem& stage) { return stage.segmentations.front().count; }

TEST(AutomaticClusters, AGivenCountIsMergedTo) {
  CodecSettings settings;
  settings.clusters = 3;
  StageProblem stage(24, settings);
  ASSERT_GT(morse_count(stage), 3u);
  const Clusters clusters = choose_clusters(stage.problem, stage.segmentations, stage.content);
  EXPECT_EQ(clusters.count, 3u);
  EXPECT_EQ(clusters.label.size(), stage.problem.welded);
  for (uint32_t label : clusters.label) EXPECT_LT(label, 3u);
}

TEST(AutomaticClusters, ChoosesACountTheSegmentationHas) {
  StageProblem stage(24, CodecSettings());
  size_t chosen = 99;
  const Clusters clusters = choose_clusters(stage.problem, stage.segmentations, stage.content, &chosen);
  EXPECT_LT(chosen, stage.segmentations.size());
  EXPECT_GE(clusters.count, 1u);
  EXPECT_LE(clusters.count, stage.segmentations[chosen].count);  // merged down, never split
  // The same choice again, and on any number of threads (the segmentations and the candidate counts are tried
  // several at a time on more than one).
  for (size_t threads : {1, 2, 3, 5}) {
    CodecSettings settings;
    settings.threads = threads;
    StageProblem again(24, settings);
    size_t again_chosen = 99;
    const Clusters twice = choose_clusters(again.problem, again.segmentations, again.content, &again_chosen);
    EXPECT_EQ(twice.label, clusters.label) << threads << " threads";
    EXPECT_EQ(again_chosen, chosen) << threads << " threads";
    EXPECT_EQ(again.content.flags, stage.content.flags) << threads << " threads";
  }
}

// The residual predictions are kept only where they pay: the flags after the choice are among those asked for.
TEST(AutomaticClusters, ResidualPredictionsAreOnlyDropped) {
  StageProblem stage(24, CodecSettings());
  const uint32_t asked = stage.content.flags;
  EXPECT_NE(asked & (format::kFlagTemporalResiduals | format::kFlagSpatialResiduals), 0u);
  choose_clusters(stage.problem, stage.segmentations, stage.content);
  EXPECT_EQ(stage.content.flags & ~asked, 0u);
}

}  // namespace
}  // namespace segmorph
