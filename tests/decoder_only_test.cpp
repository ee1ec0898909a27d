// The runtime decoder as an engine links it: this test links segmorph::decoder alone (no encoder, no glTF, no Draco;
// tests/CMakeLists.txt) and includes only its public header. The worked examples of spec/bitstream.md (versions 1, 3
// and 4; tests/spec_examples.h) decode through the C API to the frames the spec prints, whole clips and frame by frame,
// and their normals turn.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "segmorph/decoder_c.h"
#include "spec_examples.h"

namespace segmorph {
namespace {

using namespace spec_examples;

std::vector<uint8_t> from_hex(const char* text) {
  std::vector<uint8_t> bytes;
  for (size_t i = 0; text[i] && text[i + 1]; i += 2)
    bytes.push_back(uint8_t(std::stoul(std::string(text + i, 2), nullptr, 16)));
  return bytes;
}

// "frame vertex x y z" lines of V × 3 floats per frame, binary32 bit patterns, as the spec prints them.
std::string printed(const std::vector<float>& frames, size_t vertex_count) {
  std::string text;
  for (size_t i = 0; i < frames.size() / 3; ++i) {
    uint32_t bits[3];
    std::memcpy(bits, &frames[i * 3], sizeof bits);
    char line[64];
    std::snprintf(line, sizeof line, "%zu %zu %08x %08x %08x\n", i / vertex_count, i % vertex_count, unsigned(bits[0]),
                  unsigned(bits[1]), unsigned(bits[2]));
    text += line;
  }
  return text;
}

// Every frame of the stream, clip after clip, by segmorph_decode_clip (and, checked to be the same floats, frame by
// frame by segmorph_decode_frame).
std::vector<float> decoded(const std::vector<uint8_t>& stream, size_t expected_clips) {
  const std::vector<float> base = example_base();
  const std::vector<uint32_t> triangles = example_triangles();
  segmorph_decoder* decoder = segmorph_decoder_create();
  std::vector<float> frames;
  EXPECT_EQ(segmorph_decoder_open(decoder, stream.data(), stream.size(), base.data(), base.size() / 3, triangles.data(),
                                  triangles.size()),
            SEGMORPH_STATUS_OK)
      << segmorph_decoder_message(decoder);
  EXPECT_EQ(segmorph_decoder_clip_count(decoder), expected_clips);
  for (size_t c = 0; c < segmorph_decoder_clip_count(decoder); ++c) {
    std::vector<float> clip(segmorph_decode_clip_bound(decoder, c));
    EXPECT_EQ(segmorph_decode_clip(decoder, c, clip.data(), clip.size()), SEGMORPH_STATUS_OK);
    frames.insert(frames.end(), clip.begin(), clip.end());
  }
  EXPECT_EQ(segmorph_decoder_seek(decoder, 0), SEGMORPH_STATUS_OK);
  std::vector<float> one(base.size()), again;
  while (segmorph_decoder_next_clip(decoder) < segmorph_decoder_clip_count(decoder)) {
    EXPECT_EQ(segmorph_decode_frame(decoder, one.data(), one.size()), SEGMORPH_STATUS_OK);
    again.insert(again.end(), one.begin(), one.end());
  }
  EXPECT_TRUE(again.size() == frames.size() && std::memcmp(again.data(), frames.data(), 4 * frames.size()) == 0);
  // Normals turn with the surface of each frame: unit where the surface has area.
  std::vector<float> normals(base.size(), 0.0f), turned(frames.size());
  for (size_t v = 0; v < base.size() / 3; ++v) normals[v * 3 + 2] = 1.0f;
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), frames.data(), frames.size() / base.size(),
                                          turned.data(), turned.size()),
            SEGMORPH_STATUS_OK);
  for (size_t i = 0; i < turned.size(); i += 3)
    EXPECT_NEAR(turned[i] * turned[i] + turned[i + 1] * turned[i + 1] + turned[i + 2] * turned[i + 2], 1.0, 1e-5);
  segmorph_decoder_destroy(decoder);
  return frames;
}

TEST(DecoderOnly, VersionOneExampleDecodesToTheSpecFrames) {
  const std::vector<float> frames = decoded(from_hex(kExampleHex), 2);
  ASSERT_EQ(frames.size(), 3u * 8 * 3);
  std::vector<float> expected(frames.size());
  std::memcpy(expected.data(), kExampleFrames, sizeof kExampleFrames);
  EXPECT_EQ(printed(frames, 8), printed(expected, 8));
}

TEST(DecoderOnly, VersionThreeExampleDecodesToTheSpecFrames) {
  EXPECT_EQ(printed(decoded(from_hex(kReferenceExampleHex), 1), 8), kReferenceExampleFrames);
}

TEST(DecoderOnly, VersionFourExampleDecodesToTheSpecFrames) {
  EXPECT_EQ(printed(decoded(from_hex(kTransformExampleHex), 2), 8), kTransformExampleFrames);
}

TEST(DecoderOnly, ADamagedExampleIsBadData) {
  std::vector<uint8_t> stream = from_hex(kExampleHex);
  stream.resize(stream.size() - 3);
  const std::vector<float> base = example_base();
  const std::vector<uint32_t> triangles = example_triangles();
  segmorph_decoder* decoder = segmorph_decoder_create();
  segmorph_status status = segmorph_decoder_open(decoder, stream.data(), stream.size(), base.data(), base.size() / 3,
                                                 triangles.data(), triangles.size());
  std::vector<float> clip(1000);
  if (status == SEGMORPH_STATUS_OK) status = segmorph_decode_clip(decoder, 0, clip.data(), clip.size());
  if (status == SEGMORPH_STATUS_OK) status = segmorph_decode_clip(decoder, 1, clip.data(), clip.size());
  EXPECT_EQ(status, SEGMORPH_STATUS_BAD_DATA);
  EXPECT_GT(std::strlen(segmorph_decoder_message(decoder)), 0u);
  segmorph_decoder_destroy(decoder);
}

}  // namespace
}  // namespace segmorph
