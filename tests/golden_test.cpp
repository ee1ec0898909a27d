// Golden files: small encoded files of each bitstream version the decoder reads (tests/golden/vN/, N from
// format::kOldestVersion to format::kNewestVersion) decode to the frames recorded beside them, so that any change to the
// format, a model or the reconstruction arithmetic is deliberate: it needs a new version (spec/README.md, "Version
// compatibility") and new golden files, and the old ones either still decode or are retired with the version.
//
// Each FILE.glb has FILE.frames: one line per animated primitive, "node primitive clips vertices frames
// digest", digest the FNV-1a 64 of the bit patterns of every decoded position, clip by clip. To record them
// after a deliberate change: SEGMORPH_UPDATE_GOLDEN=1 ctest -R Golden (then review the diff).
//
// Track streams (spec/tracks.md) have their own folder per track stream version, tests/golden/tracks-vN/: each
// FILE.bin has FILE.txt, its layout and every decoded time and value as a binary32 pattern. With
// SEGMORPH_UPDATE_GOLDEN=1 a missing tracks.bin is written from golden_tracks() below and every .txt is recorded.
#include <gtest/gtest.h>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/float_bits.h"
#include "common/stream_format.h"
#include "common/track_format.h"
#include "common/track_set.h"
#include "decode/track_decoder.h"
#include "decoding/decode_file.h"
#include "encode/track_encoder.h"
#include "gltf/load.h"
#include "sampling/sample.h"
#include "test_files.h"

namespace segmorph {
namespace {

// The frames every animated primitive of `path` decodes to, one line each.
std::string decoded_frames(const std::string& path) {
  tinygltf::Model model;
  Scene scene;
  Status status = load_gltf(path, model);
  if (status.ok()) status = decode_compressed_model(model);
  if (status.ok()) status = analyze_scene(model, scene);
  EXPECT_TRUE(status.ok()) << path << ": " << status.message();
  std::ostringstream lines;
  for (const AnimatedNode& animated : scene.animated) {
    SampledNode node;
    status = sample_node(model, scene, animated, SampleSettings(), node);
    EXPECT_TRUE(status.ok()) << path << ": " << status.message();
    for (size_t p = 0; p < node.primitives.size(); ++p) {
      uint64_t digest = 1469598103934665603ull;
      size_t frames = 0;
      for (const FrameSequence& clip : node.primitives[p].clips) {
        frames += clip.frame_count;
        for (float x : clip.positions) {
          uint32_t bits;
          std::memcpy(&bits, &x, 4);
          digest = (digest ^ bits) * 1099511628211ull;
        }
      }
      char line[160];
      std::snprintf(
          line, sizeof(line), "%d %zu %zu %zu %zu %016" PRIx64 "\n", animated.node, p, node.primitives[p].clips.size(),
          node.primitives[p].clips.empty() ? size_t(0) : node.primitives[p].clips[0].vertex_count, frames, digest);
      lines << line;
    }
  }
  return lines.str();
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Every version the decoder reads (format::kOldestVersion to format::kNewestVersion) has its folder of golden files.
TEST(Golden, EveryVersionsFilesDecodeToTheirFrames) {
  static_assert(format::kOldestVersion <= format::kNewestVersion);
  const bool update = std::getenv("SEGMORPH_UPDATE_GOLDEN") != nullptr;
  for (int version = format::kOldestVersion; version <= format::kNewestVersion; ++version) {
    const std::string directory = std::string(SEGMORPH_GOLDEN_DIR) + "/v" + std::to_string(version);
    const std::vector<std::string> files = testing::gltf_files_under(directory);
    EXPECT_FALSE(files.empty()) << "no golden files for bitstream version " << version << " in " << directory
                                << ": a new version needs them (see this file's comment)";
    for (const std::string& file : files) {
      const std::string expected_path = file.substr(0, file.rfind('.')) + ".frames";
      const std::string actual = decoded_frames(file);
      if (update) {
        std::ofstream(expected_path, std::ios::binary) << actual;
        continue;
      }
      EXPECT_EQ(actual, read_file(expected_path))
          << file << " no longer decodes to the frames recorded in " << expected_path;
    }
  }
}

// Each version's folder holds streams of that version: a file of vN/ has a stream whose version byte is N (the
// magic "SGMA", then the version), and none of another version.
TEST(Golden, EveryVersionsFilesHoldStreamsOfThatVersion) {
  for (int version = format::kOldestVersion; version <= format::kNewestVersion; ++version) {
    const std::string directory = std::string(SEGMORPH_GOLDEN_DIR) + "/v" + std::to_string(version);
    for (const std::string& file : testing::gltf_files_under(directory)) {
      const std::string bytes = read_file(file);
      size_t streams = 0;
      for (size_t at = bytes.find("SGMA"); at != std::string::npos && at + 4 < bytes.size();
           at = bytes.find("SGMA", at + 1)) {
        ++streams;
        EXPECT_EQ(int(uint8_t(bytes[at + 4])), version) << file << ": a stream at byte " << at;
      }
      EXPECT_GT(streams, 0u) << file;
    }
  }
}

const char* const kPathNames[] = {"translation", "rotation", "scale", "weights"};

// A track set as its golden .txt shows it: per time array its key count and patterns, per sampler its layout and a
// line of patterns per key.
std::string track_text(const TrackSet& tracks) {
  std::ostringstream text;
  char word[16];
  for (size_t i = 0; i < tracks.times.size(); ++i) {
    text << "times " << i << ": " << tracks.times[i].size() << " keys\n";
    for (size_t k = 0; k < tracks.times[i].size(); ++k) {
      std::snprintf(word, sizeof(word), "%08" PRIx32, float_bits(tracks.times[i][k]));
      text << (k % 8 == 0 ? " " : "") << ' ' << word << (k % 8 == 7 || k + 1 == tracks.times[i].size() ? "\n" : "");
    }
  }
  for (size_t s = 0; s < tracks.samplers.size(); ++s) {
    const TrackSampler& sampler = tracks.samplers[s];
    text << "sampler " << s << ": " << kPathNames[int(sampler.path)] << ", " << sampler.components
         << " components, times " << sampler.times << "\n";
    for (size_t i = 0; i < sampler.values.size(); ++i) {
      std::snprintf(word, sizeof(word), "%08" PRIx32, float_bits(sampler.values[i]));
      text << (i % size_t(sampler.components) == 0 ? " " : "") << ' ' << word
           << ((i + 1) % size_t(sampler.components) == 0 ? "\n" : "");
    }
  }
  return text.str();
}

// The layout of a golden .txt (its "times" and "sampler" lines).
TrackLayout track_text_layout(const std::string& text) {
  TrackLayout layout;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    size_t index, count;
    int components, times;
    char path[16];
    if (std::sscanf(line.c_str(), "times %zu: %zu keys", &index, &count) == 2) layout.time_counts.push_back(count);
    if (std::sscanf(line.c_str(), "sampler %zu: %15[a-z], %d components, times %d", &index, path, &components,
                    &times) == 4)
      for (int p = 0; p < 4; ++p)
        if (std::string(path) == kPathNames[p]) layout.samplers.push_back({times, TrackPath(p), components});
  }
  return layout;
}

// What tracks-v1/tracks.bin was encoded from: every path; an evenly spaced, an uneven and a one-key time array; a
// rotation whose sign flips and that turns fast enough at one key to need an escape.
TrackSet golden_tracks(std::vector<double>& steps) {
  TrackSet tracks;
  std::vector<float> even, uneven;
  for (int k = 0; k < 24; ++k) even.push_back(float(k / 23.0));  // regular: the formula of spec/tracks.md 5.1
  for (int k = 0; k < 10; ++k) uneven.push_back(float(0.1 * k + 0.03 * (k % 3)));
  tracks.times = {even, uneven, {0.5f}};
  TrackSampler translation{TrackPath::translation, 3, 0, {}}, rotation{TrackPath::rotation, 4, 0, {}};
  for (float t : even) {
    translation.values.insert(translation.values.end(), {float(std::sin(3 * t)), 0.25f * t, float(std::cos(t))});
    const double angle = t < 0.5f ? 2.0 * t : 2.0 * t + 2.5;  // a jump of 2.5 radians half-way
    const float sign = t > 0.7f ? -1.0f : 1.0f;
    rotation.values.insert(rotation.values.end(),
                           {sign * float(0.6 * std::sin(angle / 2)), 0.0f, sign * float(0.8 * std::sin(angle / 2)),
                            sign * float(std::cos(angle / 2))});
  }
  TrackSampler scale{TrackPath::scale, 3, 1, {}}, weights{TrackPath::weights, 3, 1, {}};
  for (float t : uneven) {
    scale.values.insert(scale.values.end(), {1.0f + t, 1.0f, float(1 - 0.5 * t * t)});
    weights.values.insert(weights.values.end(), {t, 1.0f - t, float(t * t)});
  }
  TrackSampler still{TrackPath::translation, 3, 2, {0.0f, 1.5f, -2.0f}};
  tracks.samplers = {translation, rotation, scale, weights, still};
  steps = {1e-3, 1e-4, 1e-3, 1.0 / 1024, 1e-3};
  return tracks;
}

TEST(GoldenTracks, EveryVersionsStreamsDecodeToTheirValues) {
  const std::string directory = std::string(SEGMORPH_GOLDEN_DIR) + "/tracks-v" + std::to_string(track_format::kVersion);
  const bool update = std::getenv("SEGMORPH_UPDATE_GOLDEN") != nullptr;
  if (update && !std::filesystem::exists(directory + "/tracks.bin")) {
    std::vector<double> steps;
    std::vector<uint8_t> bytes;
    TrackSet decoded;
    ASSERT_TRUE(encode_tracks(golden_tracks(steps), steps, bytes, decoded).ok());
    std::filesystem::create_directories(directory);
    std::ofstream(directory + "/tracks.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    std::ofstream(directory + "/tracks.txt", std::ios::binary) << track_text(decoded);
  }
  std::vector<std::string> files;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error))
    if (entry.path().extension() == ".bin") files.push_back(entry.path().string());
  ASSERT_FALSE(files.empty()) << "no golden track streams for track stream version " << int(track_format::kVersion)
                              << " in " << directory << ": a new version needs them (see this file's comment)";
  for (const std::string& file : files) {
    const std::string expected_path = file.substr(0, file.rfind('.')) + ".txt";
    const std::string expected = read_file(expected_path), bytes = read_file(file);
    TrackSet decoded;
    const Status status = decode_tracks(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(),
                                        track_text_layout(expected), decoded);
    ASSERT_TRUE(status.ok()) << file << ": " << status.message();
    if (update) {
      std::ofstream(expected_path, std::ios::binary) << track_text(decoded);
      continue;
    }
    EXPECT_EQ(track_text(decoded), expected)
        << file << " no longer decodes to the values recorded in " << expected_path;
  }
}

}  // namespace
}  // namespace segmorph
