// The pipeline API (include/segmorph/segmorph.h) as a C++ asset pipeline uses it: load, info, bake, encode with a
// target, decode, verify, save; errors as a Status.
#include <gtest/gtest.h>

#include <filesystem>

#include "segmorph/segmorph.h"
#include "test_files.h"

namespace segmorph {
namespace {

std::string sample(const std::string& relative) { return std::string(SEGMORPH_SAMPLES_DIR) + "/" + relative; }

TEST(Pipeline, EncodeDecodeAndVerifyAFile) {
  Model original;
  ASSERT_TRUE(Model::load(sample("AnimatedMorphCube/AnimatedMorphCube.glb"), original).ok());
  InfoReport facts;
  ASSERT_TRUE(info(original, SampleSettings(), facts).ok());
  ASSERT_EQ(facts.primitives.size(), 1u);
  EXPECT_EQ(facts.primitives[0].vertices, 24u);
  EXPECT_EQ(facts.primitives[0].clips.at(0).frames, 127u);

  EncodeSettings settings;
  settings.target = 0.5;
  settings.targets = EncodeSettings::Targets::bake;
  Model encoded;
  EncodeReport report;
  std::vector<std::string> progress;
  const Status status =
      encode(original, settings, encoded, &report, [&](const std::string& line) { progress.push_back(line); });
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(report.streams.size(), 1u);
  EXPECT_GT(report.animation_bytes, 0u);
  EXPECT_EQ(report.vertex_frames, 24.0 * 127);
  EXPECT_FALSE(progress.empty());
  EXPECT_LT(encoded.glb_size(), original.glb_size());

  VerifyReport measured;
  ASSERT_TRUE(verify(original, encoded, SampleSettings(), measured).ok());
  EXPECT_LE(measured.kg_percent, 0.5);
  EXPECT_GT(measured.kg_percent, 0);
  EXPECT_EQ(measured.animation_bytes, report.animation_bytes);

  // Saved and read back, then decoded to standard glTF: the same animation.
  const std::string path = testing::temporary_path("pipeline_cube.glb");
  ASSERT_TRUE(encoded.save(path).ok());
  Model read;
  ASSERT_TRUE(Model::load(path, read).ok());
  EXPECT_EQ(file_bytes(path, read), std::filesystem::file_size(path));
  DecodeReport decoded;
  std::vector<DecodedFrames> frames;
  ASSERT_TRUE(decode(read, &decoded, &frames).ok());
  EXPECT_EQ(decoded.primitives, 1u);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].clips.at(0).frame_count, 127u);
  VerifyReport again;
  ASSERT_TRUE(verify(original, read, SampleSettings(), again).ok());
  EXPECT_DOUBLE_EQ(again.kg_percent, measured.kg_percent);
}

TEST(Pipeline, BakeWritesMorphTargets) {
  Model model;
  ASSERT_TRUE(Model::load(sample("RiggedSimple/RiggedSimple.glb"), model).ok());
  BakeReport report;
  ASSERT_TRUE(bake(model, SampleSettings(), &report).ok());
  EXPECT_EQ(report.nodes, 1u);
  EXPECT_EQ(report.frames, 50u);
  Model original;
  ASSERT_TRUE(Model::load(sample("RiggedSimple/RiggedSimple.glb"), original).ok());
  VerifyReport measured;
  ASSERT_TRUE(verify(original, model, SampleSettings(), measured).ok());
  EXPECT_LT(measured.kg_percent, 1e-4);
}

TEST(Pipeline, ErrorsAreStatuses) {
  Model model;
  const Status missing = Model::load(testing::temporary_path("no such file.glb"), model);
  EXPECT_FALSE(missing.ok());
  EXPECT_FALSE(missing.message().empty());
  // A rate below what the rest of the file takes alone cannot be met.
  ASSERT_TRUE(Model::load(sample("Fox/Fox.glb"), model).ok());
  EncodeSettings settings;
  settings.mode = RateMode::bpvf;
  settings.target = 0.01;
  Model out;
  const Status low = encode(model, settings, out);
  EXPECT_EQ(low.code(), StatusCode::invalid_argument);
  EXPECT_NE(low.message().find("--bpvf"), std::string::npos) << low.message();
  // Nothing to decode in a file that is not encoded.
  DecodeReport report;
  ASSERT_TRUE(decode(model, &report).ok());
  EXPECT_EQ(report.primitives, 0u);
  EXPECT_TRUE(has_gltf_extension("x.GLB"));
  EXPECT_FALSE(has_gltf_extension("x.obj"));
}

}  // namespace
}  // namespace segmorph
