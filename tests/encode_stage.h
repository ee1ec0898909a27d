// An encode problem set up as encode_animation sets it up (codec/encode/encode_problem.h), for the tests of the
// encoder's stages that come after it: automatic clusters, rate control, transform coding.
#pragma once

#include <vector>

#include <gtest/gtest.h>

#include "encode/automatic_clusters.h"
#include "encode/encode_problem.h"
#include "test_meshes.h"

namespace segmorph {
namespace testing {

struct StageProblem {
  std::vector<FrameSequence> clips;
  std::vector<float> base;
  CodecSettings settings;
  EncodeProblem problem{clips, base, settings};
  StreamContent content;
  std::vector<Clusters> segmentations;
  StreamReport report;

  // The bending sphere (642 vertices, `frames` frames): welded, segmented, its steps scaled.
  StageProblem(size_t frames, const CodecSettings& with) : StageProblem(bending_clip(frames, 0.6, 0.0), with) {}
  // Any clip, set up alike.
  StageProblem(const FrameSequence& clip, const CodecSettings& with) : clips{clip}, settings(with) {
    base = quantized_base(clips[0]);
    EXPECT_TRUE(set_up_problem(problem, content).ok());
    EXPECT_TRUE(segment_first_frame(problem, segmentations, report).ok());
    set_step_scales(problem, report.e_pi_morse);
  }
  StageProblem(const StageProblem&) = delete;  // problem refers to the members
};

}  // namespace testing
}  // namespace segmorph
