// The pipeline's inputs (include/segmorph/segmorph.h, "inputs"): what kind a name is, reading any of them with the
// sampling that plays it, what they weigh as delivered, and verify's gate and blame as data.
#include <sys/stat.h>

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "segmorph/segmorph.h"
#include "test_files.h"

namespace segmorph {
namespace {

using testing::temporary_path;

std::string flag(const std::string& file) { return std::string(SEGMORPH_SAMPLES_DIR) + "/WavingFlag/" + file; }

size_t size_of(const std::string& path) {
  struct stat info {};
  return stat(path.c_str(), &info) == 0 ? size_t(info.st_size) : 0;
}

TEST(Inputs, KindsByName) {
  EXPECT_EQ(input_kind(Input{flag("flag.glb"), "", false}), InputKind::gltf);
  EXPECT_EQ(input_kind(Input{"-", "", false}), InputKind::gltf);
  EXPECT_EQ(input_kind(Input{flag("obj_sequence"), "", false}), InputKind::obj_sequence);    // a folder
  EXPECT_EQ(input_kind(Input{"frames/walk_%04d.obj", "", false}), InputKind::obj_sequence);  // a pattern
  EXPECT_EQ(input_kind(Input{"100%_done.glb", "", false}), InputKind::gltf);  // a % in a glTF's name
  EXPECT_EQ(input_kind(Input{flag("flag.obj"), flag("flag.pc2"), false}), InputKind::point_cache);
}

TEST(Inputs, RefusesWhatIsNotAnAnimationAlone) {
  for (const std::string& path : {flag("flag.obj"), flag("flag.pc2"), flag("flag.mdd")}) {
    Model model;
    SampleSettings sampling;
    const Status status = load_input(Input{path, "", false}, SampleSettings(), model, sampling);
    EXPECT_EQ(status.code(), StatusCode::invalid_argument) << path;
    const char* expected = path.back() == 'j' ? "an .obj alone is one frame" : "a point cache moves a base mesh";
    EXPECT_NE(status.message().find(expected), std::string::npos)
        << status.message();
  }
}

// Without caches (decode), any name is read as a glTF.
TEST(Inputs, WithoutCachesEveryInputIsAGltf) {
  for (const std::string& path : {flag("flag.obj"), flag("obj_sequence")}) {
    Model model;
    SampleSettings sampling;
    const Status status = load_input(Input{path, "", false, false}, SampleSettings(), model, sampling);
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find("not a glTF"), std::string::npos) << status.message();
  }
}

TEST(Inputs, GltfIsSampledAsRequestedAndSaysWhatItReads) {
  Model model;
  SampleSettings requested, sampling;
  requested.fps = 12;
  std::vector<std::string> lines;
  ASSERT_TRUE(load_input(Input{flag("flag.glb"), "", false}, requested, model, sampling,
                         [&](const std::string& line) { lines.push_back(line); })
                  .ok());
  EXPECT_EQ(sampling.fps, 12);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "reading " + flag("flag.glb"));
  InfoReport info_report;
  ASSERT_TRUE(info(model, sampling, info_report).ok());
  EXPECT_EQ(info_report.primitives.size(), 1u);
}

// A cache plays at its own frames; an MDD cache (which holds each frame's time) is resampled at a requested rate, a
// PC2 cache's requested rate is the rate of its frame numbers.
TEST(Inputs, CachesAreSampledAtTheirOwnFramesUnlessAnMddIsResampled) {
  for (const char* cache : {"flag.pc2", "flag.mdd"}) {
    SCOPED_TRACE(cache);
    for (double fps : {0.0, 48.0}) {
      Model model;
      SampleSettings requested, sampling;
      requested.fps = fps;
      CacheReport report;
      ASSERT_TRUE(load_input(Input{flag("flag.obj"), flag(cache), true}, requested, model, sampling, {}, &report).ok());
      EXPECT_EQ(report.own_times, std::string(cache) == "flag.mdd");
      const bool resampled = report.own_times && fps > 0;
      EXPECT_EQ(sampling.fps, resampled ? fps : report.sampling.fps) << fps;
      InfoReport info_report;
      ASSERT_TRUE(info(model, sampling, info_report).ok());
      ASSERT_EQ(info_report.primitives.size(), 1u);
      // The PC2's frame numbers at 48 fps: the same 24 frames in half the time; the MDD resampled at 48 fps: twice
      // the frames (47 over its 23 intervals).
      EXPECT_EQ(info_report.primitives[0].clips[0].frames, resampled ? 47u : 24u) << fps;
    }
  }
}

TEST(Inputs, BytesAsDelivered) {
  Model gltf;
  SampleSettings sampling;
  const std::string simple = std::string(SEGMORPH_SAMPLES_DIR) + "/SimpleMorph/SimpleMorph.gltf";
  ASSERT_TRUE(load_input(Input{simple, "", false}, SampleSettings(), gltf, sampling).ok());
  const std::string folder = std::string(SEGMORPH_SAMPLES_DIR) + "/SimpleMorph/";
  EXPECT_EQ(input_bytes(Input{simple, "", false}, gltf),
            size_of(simple) + size_of(folder + "simpleMorphAnimation.bin") +
                size_of(folder + "simpleMorphGeometry.bin"));

  Model cache;
  const Input cached{flag("flag.obj"), flag("flag.mdd"), true};
  ASSERT_TRUE(load_input(cached, SampleSettings(), cache, sampling).ok());
  EXPECT_EQ(input_bytes(cached, cache), size_of(flag("flag.obj")) + size_of(flag("flag.mdd")));
  Model sequence;
  const Input frames{flag("obj_sequence"), "", false};
  ASSERT_TRUE(load_input(frames, SampleSettings(), sequence, sampling).ok());
  EXPECT_EQ(input_bytes(frames, sequence), sequence.glb_size());  // the glTF it reads as

  // What a save wrote: a .gltf and its .bin.
  const std::string saved = temporary_path("saved.gltf");
  ASSERT_TRUE(gltf.save(saved).ok());
  const size_t bin = size_of(saved.substr(0, saved.size() - 5) + ".bin");
  EXPECT_GT(bin, 0u);
  EXPECT_EQ(saved_bytes(saved, gltf), size_of(saved) + bin);
  EXPECT_EQ(saved_bytes("-", gltf), gltf.glb_size());
  EXPECT_EQ(saved_bytes(temporary_path("never_written.glb"), gltf), 0u);
}

TEST(Inputs, VerifyGateTakesTheErrorBoundFirst) {
  VerifyReport report;
  report.vertex_frames = 1000;
  report.kg_percent = 0.2;
  report.primitives.resize(2);
  report.primitives[0].kg_percent = 0.1;
  report.primitives[1].kg_percent = 0.2;
  EXPECT_EQ(report.worst(), &report.primitives[1]);
  const size_t bytes = 1000;  // 8 bpvf
  EXPECT_EQ(exceeded_bound(report, bytes, VerifyBounds{}), VerifyBound::none);
  EXPECT_EQ(exceeded_bound(report, bytes, VerifyBounds{0.2, 8}), VerifyBound::none);  // at the bounds is within
  EXPECT_EQ(exceeded_bound(report, bytes, VerifyBounds{0.1, -1}), VerifyBound::max_error);
  EXPECT_EQ(exceeded_bound(report, bytes, VerifyBounds{-1, 7.9}), VerifyBound::max_bpvf);
  EXPECT_EQ(exceeded_bound(report, bytes, VerifyBounds{0.1, 7.9}), VerifyBound::max_error);
  EXPECT_EQ(VerifyReport().worst(), nullptr);
}

// When verify fails, the report says which model the error is about.
TEST(Inputs, VerifySaysWhichModelFailed) {
  Model animated, empty;  // empty: nothing animated
  ASSERT_TRUE(Model::load(flag("flag.glb"), animated).ok());
  VerifyReport report;
  EXPECT_EQ(verify(empty, animated, SampleSettings(), report).code(), StatusCode::nothing_to_do);
  EXPECT_EQ(report.failed_model, 0);
  EXPECT_EQ(verify(animated, empty, SampleSettings(), report).code(), StatusCode::nothing_to_do);
  EXPECT_EQ(report.failed_model, 1);
  EXPECT_TRUE(verify(animated, animated, SampleSettings(), report).ok());
  EXPECT_EQ(report.failed_model, -1);
}

}  // namespace
}  // namespace segmorph
