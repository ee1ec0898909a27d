// Golden files: small encoded files of each bitstream version (tests/golden/vN/) decode to the frames recorded
// beside them, so that any change to the format, a model or the reconstruction arithmetic is deliberate: it
// needs a new version (spec/README.md, "Version compatibility") and new golden files, and the old ones either
// still decode or are retired with the version.
//
// Each FILE.glb has FILE.frames: one line per animated primitive, "node primitive clips vertices frames
// digest", digest the FNV-1a 64 of the bit patterns of every decoded position, clip by clip. To record them
// after a deliberate change: SEGMORPH_UPDATE_GOLDEN=1 ctest -R Golden (then review the diff).
#include <gtest/gtest.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "compressed.h"
#include "gltf_io.h"
#include "sample.h"
#include "stream_format.h"
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
      std::snprintf(line, sizeof(line), "%d %zu %zu %zu %zu %016" PRIx64 "\n", animated.node, p,
                    node.primitives[p].clips.size(), node.primitives[p].clips.empty() ? size_t(0) : node.primitives[p].clips[0].vertex_count,
                    frames, digest);
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

TEST(Golden, EveryVersionsFilesDecodeToTheirFrames) {
  const std::string directory = std::string(SEGMORPH_GOLDEN_DIR) + "/v" + std::to_string(format::kVersion);
  const std::vector<std::string> files = testing::gltf_files_under(directory);
  ASSERT_FALSE(files.empty()) << "no golden files for bitstream version " << int(format::kVersion) << " in "
                              << directory << ": a new version needs them (see this file's comment)";
  const bool update = std::getenv("SEGMORPH_UPDATE_GOLDEN") != nullptr;
  for (const std::string& file : files) {
    const std::string expected_path = file.substr(0, file.rfind('.')) + ".frames";
    const std::string actual = decoded_frames(file);
    if (update) {
      std::ofstream(expected_path, std::ios::binary) << actual;
      continue;
    }
    EXPECT_EQ(actual, read_file(expected_path)) << file << " no longer decodes to the frames recorded in "
                                                << expected_path;
  }
}

}  // namespace
}  // namespace segmorph
