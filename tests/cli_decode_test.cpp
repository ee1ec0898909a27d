// segmorph decode: round trips through encode and decode, --frames, and damaged encoded files.
#include <gtest/gtest.h>

#include "accessor.h"
#include "cli_run.h"
#include "gltf/load.h"

using namespace cli_testing;

TEST(Cli, EncodeDecodeAndVerify) {
  const std::string directory = output_directory("encode");
  const std::string input = sample("Fox/Fox.glb");
  Result result = run("encode -q " + input + " -o " + directory + "/fox.glb --error 0.5 --skins bake --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_GT(json_number(result.out, "clusters"), 0);
  EXPECT_GT(json_number(result.out, "e_pi"), 0);
  EXPECT_LT(json_number(result.out, "e_pi"), 0.01);
  EXPECT_GT(json_number(result.out, "bpvf"), 0);
  EXPECT_FALSE(std::isnan(json_number(result.out, "rate_control")));
  // Three times smaller than the input at least (the input's frames as skin; the output carries the texture too).
  EXPECT_LT(fs::file_size(directory + "/fox.glb") * 2, fs::file_size(input));

  result = run("verify -q " + input + " " + directory + "/fox.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const double kg = json_number(result.out, "kg_percent");
  EXPECT_LE(kg, 0.5);
  EXPECT_GT(kg, 0.1);
  EXPECT_EQ(json_number(result.out, "vertices"), 1728);
  EXPECT_GT(json_number(result.out, "bpvf_animation"), 0);

  result = run("decode -q " + directory + "/fox.glb -o " + directory + "/fox-decoded.glb");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run("verify -q " + input + " " + directory + "/fox-decoded.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_DOUBLE_EQ(json_number(result.out, "kg_percent"), kg);  // the decoded file plays the decoder's frames
  EXPECT_EQ(json_number(result.out, "bpvf_animation"), 0);      // standard glTF: no stream left

  // Decoding a file that is not encoded says so.
  result = run("decode -q " + input + " -o " + directory + "/not.glb");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.err.find("not encoded"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(directory + "/not.glb"));
}

// decode --threads: the same file and frames for any number of threads (the chicken's version-4 stream of 400 frames,
// where ../shared has it; else the bending flag's), and a count out of range is refused.
TEST(Cli, DecodeThreadsGiveTheSameOutput) {
  const std::string directory = output_directory("decode_threads");
  const std::string shared = std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/sequences/ChickenCrossing/chicken.glb";
  const std::string input = fs::exists(shared) ? shared : sample("WavingFlag/flag.glb");
  Result result = run("encode -q " + input + " -o " + directory + "/encoded.glb --gpu-playable");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  std::string glb[3], frames[3];
  const char* threads[3] = {"1", "3", "0"};
  for (int i = 0; i < 3; ++i) {
    const std::string stem = directory + "/decoded" + std::to_string(i);
    result = run("decode -q " + directory + "/encoded.glb -o " + stem + ".glb --frames " + stem + ".bin --threads " +
                 threads[i]);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    glb[i] = read_text(stem + ".glb"), frames[i] = read_text(stem + ".bin");
  }
  EXPECT_GT(frames[0].size(), 0u);
  for (int i = 1; i < 3; ++i) {
    EXPECT_TRUE(glb[i] == glb[0]) << "--threads " << threads[i];
    EXPECT_TRUE(frames[i] == frames[0]) << "--threads " << threads[i];
  }
  result = run("decode -q " + directory + "/encoded.glb -o " + directory + "/x.glb --threads 2000");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--threads"), std::string::npos) << result.err;
}

// decode --frames writes what the streams decode to, as raw floats: for a primitive that plays clips, its frames, whose
// first is the decoded file's base and each other the base plus its target (within an ulp of the larger of the two,
// spec/README.md); for kept
// targets, their displacements, which are the decoded file's target accessors exactly.
TEST(Cli, DecodeFramesWritesWhatTheStreamsDecodeTo) {
  const std::string directory = output_directory("decode_frames");
  const std::string input = sample("AnimatedMorphCube/AnimatedMorphCube.glb");
  for (const char* targets : {"bake", "keep"}) {
    SCOPED_TRACE(targets);
    const std::string encoded = directory + "/cube.glb", decoded = directory + "/decoded.glb";
    const std::string frames = directory + "/frames.bin", only = directory + "/only.bin";
    ASSERT_EQ(run("encode -q " + input + " -o " + encoded + " --targets " + targets).exit_code, 0);
    Result result = run("decode -q " + encoded + " -o " + decoded + " --frames " + frames);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    result = run("decode -q " + encoded + " --frames " + only);  // without -o: the frames alone
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string bytes = read_text(frames);
    EXPECT_EQ(bytes, read_text(only));
    std::vector<float> values(bytes.size() / 4);
    std::memcpy(values.data(), bytes.data(), values.size() * 4);

    tinygltf::Model model;
    ASSERT_TRUE(segmorph::load_gltf(decoded, model).ok());
    ASSERT_EQ(model.meshes.size(), 1u);
    const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
    std::vector<float> base;
    ASSERT_TRUE(segmorph::read_floats(model, primitive.attributes.at("POSITION"), "base", base).ok());
    const bool kept = std::string(targets) == "keep";
    // The cube's 2 kept targets, or its 127 frames (the base, then one target each).
    const size_t frame_count = kept ? 2 : 127;
    ASSERT_EQ(primitive.targets.size(), kept ? 2u : 126u);
    ASSERT_EQ(values.size(), frame_count * base.size());
    if (!kept) {
      EXPECT_EQ(std::memcmp(values.data(), base.data(), base.size() * 4), 0) << "frame 0 is the base";
    }
    for (size_t t = 0; t < primitive.targets.size(); ++t) {
      std::vector<float> delta;
      ASSERT_TRUE(segmorph::read_floats(model, primitive.targets[t].at("POSITION"), "target", delta).ok());
      const float* frame = &values[(kept ? t : t + 1) * base.size()];
      for (size_t i = 0; i < base.size(); ++i) {
        if (kept) {
          ASSERT_EQ(std::memcmp(&frame[i], &delta[i], 4), 0) << "target " << t << " float " << i;
        } else {
          const float played = base[i] + delta[i], larger = std::max(std::fabs(base[i]), std::fabs(frame[i]));
          ASSERT_LE(std::fabs(played - frame[i]), std::nextafter(larger, INFINITY) - larger)
              << "frame " << t + 1 << " float " << i;
        }
      }
    }
  }
  EXPECT_EQ(run("encode -q " + input + " -o " + directory + "/x.glb --frames " + directory + "/x.bin").exit_code, 2);
  EXPECT_EQ(run("decode -q " + input + " --frames " + directory + "/x.bin").exit_code, 1);  // not encoded
  EXPECT_FALSE(fs::exists(directory + "/x.bin"));
}

TEST(Cli, CorruptedEncodedFilesFailCleanlyOrDecode) {
  const std::string directory = output_directory("corrupt_encoded");
  ASSERT_EQ(run("encode -q " + sample("RiggedSimple/RiggedSimple.glb") + " -o " + directory + "/encoded.glb").exit_code,
            0);
  const std::string original = read_text(directory + "/encoded.glb");
  std::mt19937 random(99);
  for (int trial = 0; trial < 60; ++trial) {
    std::string bytes = original;
    // Damage the binary chunk (past the JSON), where the Draco and animation streams are.
    const size_t from = bytes.size() / 3;
    for (int c = 0; c < 1 + int(random() % 6); ++c)
      bytes[from + random() % (bytes.size() - from)] = char(random() % 256);
    if (trial % 6 == 0) bytes.resize(from + random() % (bytes.size() - from));
    write_text(directory + "/input.glb", bytes);
    fs::remove(directory + "/out.glb");
    const Result result = run("decode -q " + directory + "/input.glb -o " + directory + "/out.glb");
    SCOPED_TRACE("trial " + std::to_string(trial));
    ASSERT_TRUE(result.exit_code == 0 || result.exit_code == 1) << result.exit_code << " " << result.err;
    if (result.exit_code == 1) {
      EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
      EXPECT_FALSE(fs::exists(directory + "/out.glb"));
    }
  }
}

// A coded animation that disagrees with its stream, or whose stream is damaged, is refused in one line.
TEST(Cli, DamagedTrackStreamsAreRefused) {
  const std::string directory = output_directory("damaged_tracks");
  const std::string encoded = directory + "/fox.gltf";
  ASSERT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + encoded).exit_code, 0);
  const std::string json = read_text(encoded);
  const size_t list = json.find("\"samplers\": [");
  ASSERT_NE(list, std::string::npos);

  std::string bad = json;
  bad.replace(list, 13, "\"samplers\": [99, ");
  write_text(encoded, bad);
  expect_clean_failure(encoded, "a coded sampler does not exist", "decode");

  // The stream's view, its bytes flipped in the .bin: the view named just before the list.
  const size_t view_key = json.rfind("\"bufferView\": ", list);
  ASSERT_NE(view_key, std::string::npos);
  const int view = std::stoi(json.substr(view_key + 14));
  tinygltf::Model model;
  write_text(encoded, json);
  ASSERT_TRUE(segmorph::load_gltf(encoded, model).ok());
  const tinygltf::BufferView& stream = model.bufferViews[size_t(view)];
  std::string bin = read_text(directory + "/fox.bin");
  for (size_t i = 4; i < stream.byteLength; i += 3) bin[stream.byteOffset + i] = char(bin[stream.byteOffset + i] ^ 0x5a);
  write_text(directory + "/fox.bin", bin);
  expect_clean_failure(encoded, "animation", "decode");
}
