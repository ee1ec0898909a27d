// The pipeline API (include/segmorph/segmorph.h) as a C++ asset pipeline uses it: load, info, bake, encode with a
// target, decode, verify, save; errors as a Status.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "segmorph/segmorph.h"
#include "test_files.h"

namespace segmorph {
namespace {

std::string sample(const std::string& relative) { return std::string(SEGMORPH_SAMPLES_DIR) + "/" + relative; }

// The bytes of `path` (a file the test wrote).
std::string bytes_of(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

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

  // Encoding a model it may consume (the tool's form: a large input is not held twice) gives the same file and
  // leaves the input empty.
  Model consumed = original, moved_encode;
  ASSERT_TRUE(encode(std::move(consumed), settings, moved_encode).ok());
  EXPECT_EQ(moved_encode.glb_size(), encoded.glb_size());
  const std::string moved_path = testing::temporary_path("pipeline_cube_moved.glb");
  ASSERT_TRUE(moved_encode.save(moved_path).ok());
  EXPECT_EQ(bytes_of(moved_path), bytes_of(path));
  EXPECT_EQ(consumed.glb_size(), Model().glb_size()) << "the input is left empty";
}


// The encode is the same bytes at every thread count: lossy (with its rate control's measurements split over
// threads), at a bpvf target, and lossless, on two bundled morph files and a skinned one (its kept skin's search
// measures on threads); at an error target on the cow and RobotExpressive when ../shared is present.
TEST(Pipeline, EncodesAreTheSameBytesForEveryThreadCount) {
  std::vector<std::string> files = {sample("AnimatedMorphCube/AnimatedMorphCube.glb"),
                                    sample("WavingFlag/flag.glb"), sample("Fox/Fox.glb")};
  // From ../shared, at an error target only: the cow (long), RobotExpressive (kept skins, measured on many nodes).
  const std::string shared = SEGMORPH_SHARED_SAMPLES_DIR;
  const std::vector<std::string> long_ones = {shared + "/sequences/Cow_pcow/cow.glb",
                                              shared + "/gltf/RobotExpressive/RobotExpressive.glb"};
  for (const std::string& file : long_ones)
    if (std::filesystem::exists(file)) files.push_back(file);
    else std::printf("../shared/samples is absent: %s is not encoded\n", file.c_str());
  for (const std::string& file : files) {
    Model original;
    ASSERT_TRUE(Model::load(file, original).ok()) << file;
    const bool long_one = std::find(long_ones.begin(), long_ones.end(), file) != long_ones.end();
    for (RateMode mode : {RateMode::error, RateMode::bpvf, RateMode::lossless}) {
      if (long_one && mode != RateMode::error) continue;
      std::string first;
      for (size_t threads : {1, 2, 4}) {
        SCOPED_TRACE(file + ", mode " + std::to_string(int(mode)) + ", " + std::to_string(threads) + " threads");
        EncodeSettings settings;
        settings.mode = mode;
        settings.target = mode == RateMode::bpvf ? 20 : 0.15;
        settings.targets = EncodeSettings::Targets::bake;
        settings.threads = threads;
        Model encoded;
        ASSERT_TRUE(encode(original, settings, encoded).ok());
        const std::string path = testing::temporary_path("threads.glb");
        ASSERT_TRUE(encoded.save(path).ok());
        const std::string bytes = bytes_of(path);
        if (threads == 1) first = bytes;
        else EXPECT_TRUE(bytes == first) << "the encode differs from the one-thread encode";
      }
    }
  }
}

// --targets auto encodes a file twice (morph targets kept, then baked); its kept skins are the same in both, so the
// second encode takes the tracks' distance the first's search settled on when that stays within the goal on every
// frame: one measurement instead of a search. RobotExpressive (kept targets and kept skins), when ../shared is present.
TEST(Pipeline, TheSecondTargetsVariantStartsFromTheFirstsTrackDistance) {
  const std::string file = std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/gltf/RobotExpressive/RobotExpressive.glb";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "../shared/samples is absent: " << file << " is not encoded";
  Model original;
  ASSERT_TRUE(Model::load(file, original).ok());
  EncodeSettings settings;  // an error target, --targets auto
  ASSERT_EQ(settings.targets, EncodeSettings::Targets::automatic);
  std::vector<std::string> first, second;  // the kept skins' measurements of each encode
  bool again = false;
  const Progress progress = [&](const std::string& line) {
    if (line.find("encoding again with the morph targets baked") != std::string::npos) again = true;
    if (line.find("kept skins: tracks within") != std::string::npos) (again ? second : first).push_back(line);
  };
  Model encoded;
  EncodeReport report;
  ASSERT_TRUE(encode(original, settings, encoded, &report, progress).ok());
  ASSERT_TRUE(again);
  ASSERT_GT(first.size(), 1u);
  ASSERT_EQ(second.size(), 1u);
  // "kept skins: tracks within D: KG K % (every frame, measurement 1)", D as the first's last measurement has it.
  const std::string settled = first.back().substr(0, first.back().find(": KG"));
  EXPECT_EQ(second[0].substr(0, second[0].find(": KG")), settled);
  EXPECT_NE(first.back().find("every frame"), std::string::npos);
  EXPECT_NE(second[0].find("every frame, measurement 1"), std::string::npos);
  EXPECT_LE(report.kg_percent, settings.target);
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
