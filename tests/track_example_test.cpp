// The worked example of spec/tracks.md (section 10): the reference encoder writes exactly the appendix's bytes for
// its input, the reference decoder reads them back as the appendix's times and values, and the appendix's text shows
// these bytes and these values (so that the specification cannot drift from the code).
//
// When the track stream changes (a model, a field, an encoder decision), kExampleHex changes: the failure message
// prints the new bytes; paste them here and into spec/tracks.md (10.2, and the walk-through of 10.3).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "common/track_set.h"
#include "decode/track_decoder.h"
#include "encode/track_encoder.h"
#include "test_files.h"

namespace segmorph {
namespace {

using testing::hex;

constexpr char kExampleHex[] = "53474d5401042e126400022c9610048e697f06bdb6551efcf23b5b7cdcd8cae5af9907599670ee";

TrackSet example_input() {
  TrackSet tracks;
  tracks.times = {{0.0f, 0.5f, 1.0f}};
  tracks.samplers = {
      {TrackPath::translation, 3, 0, {1.0f, 2.0f, 0.0f, 1.5f, 2.0f, -0.25f, 2.0f, 1.5f, -0.5f}},
      // About z by 0°, 60° and 120°; the third key with the other sign.
      {TrackPath::rotation,
       4,
       0,
       {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.5f, 0.8660254f, -0.0f, -0.0f, -0.8660254f, -0.5f}},
  };
  return tracks;
}

const std::vector<double> kExampleSteps = {0.01, 0x1p-10};

// Section 10.4: the times, then each sampler's values, as binary32 patterns.
const std::vector<uint32_t> kExampleTimes = {0x00000000, 0x3f000000, 0x3f800000};
const std::vector<std::vector<uint32_t>> kExampleValues = {
    {0x3f7f0000, 0x40002000, 0x00000000, 0x3fc08000, 0x40002000, 0xbe820000, 0x40002000, 0x3fc08000, 0xbeff0000},
    {0x00000000, 0x00000000, 0x00000000, 0x3f800000, 0x00000000, 0x00000000, 0x3efff579, 0x3f5db6e1, 0x00000000,
     0x00000000, 0x3f5db6e1, 0x3efff579},
};

std::vector<uint32_t> patterns(const std::vector<float>& values) {
  std::vector<uint32_t> out(values.size());
  std::memcpy(out.data(), values.data(), values.size() * 4);
  return out;
}

TEST(TrackExample, BytesAreTheAppendixBytes) {
  std::vector<uint8_t> bytes;
  TrackSet decoded;
  const Status status = encode_tracks(example_input(), kExampleSteps, bytes, decoded);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(hex(bytes), kExampleHex) << "update kExampleHex and spec/tracks.md section 10";
}

TEST(TrackExample, DecodesToTheAppendixValues) {
  std::vector<uint8_t> bytes;
  for (size_t i = 0; i + 1 < sizeof(kExampleHex); i += 2)
    bytes.push_back(uint8_t(std::stoul(std::string(kExampleHex + i, 2), nullptr, 16)));
  TrackSet decoded;
  const Status status = decode_tracks(bytes.data(), bytes.size(), track_layout(example_input()), decoded);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(decoded.times.size(), 1u);
  EXPECT_EQ(patterns(decoded.times[0]), kExampleTimes);
  ASSERT_EQ(decoded.samplers.size(), 2u);
  for (size_t s = 0; s < 2; ++s) EXPECT_EQ(patterns(decoded.samplers[s].values), kExampleValues[s]) << "sampler " << s;
}

// The text of spec/tracks.md from the heading `from` to the next heading of the same level.
std::string appendix_section(const std::string& from) {
  std::ifstream file(std::string(SEGMORPH_SPEC_DIR) + "/tracks.md");
  std::stringstream text;
  text << file.rdbuf();
  const std::string all = text.str();
  const size_t start = all.find(from);
  if (start == std::string::npos) return "";
  const size_t end = all.find("\n### ", start + from.size());
  return all.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

TEST(TrackExample, TheAppendixShowsTheseBytesAndValues) {
  // 10.2: the hex dump, "0000    53 47 …" lines.
  const std::string dump = appendix_section("### 10.2 The bytes");
  ASSERT_FALSE(dump.empty()) << "spec/tracks.md has no section 10.2";
  std::string shown;
  const std::regex line("\n[0-9a-f]{4}    ((?:[0-9a-f]{2} ?)+)");
  for (std::sregex_iterator it(dump.begin(), dump.end(), line), end; it != end; ++it)
    for (char c : (*it)[1].str())
      if (c != ' ') shown += c;
  EXPECT_EQ(shown, kExampleHex) << "spec/tracks.md section 10.2";
  // 10.4: every 8-digit pattern in order: the times, then per key the translation's and the rotation's.
  const std::string values = appendix_section("### 10.4 The decoded values");
  std::vector<uint32_t> patterns_shown;
  const std::regex pattern("`([0-9a-f]{8}(?: [0-9a-f]{8})*)`");
  for (std::sregex_iterator it(values.begin(), values.end(), pattern), end; it != end; ++it) {
    std::istringstream words((*it)[1].str());
    std::string word;
    while (words >> word) patterns_shown.push_back(uint32_t(std::stoul(word, nullptr, 16)));
  }
  std::vector<uint32_t> want = kExampleTimes;
  for (size_t k = 0; k < 3; ++k) {
    want.insert(want.end(), kExampleValues[0].begin() + long(k * 3), kExampleValues[0].begin() + long(k * 3 + 3));
    want.insert(want.end(), kExampleValues[1].begin() + long(k * 4), kExampleValues[1].begin() + long(k * 4 + 4));
  }
  EXPECT_EQ(patterns_shown, want) << "spec/tracks.md section 10.4";
}

}  // namespace
}  // namespace segmorph
