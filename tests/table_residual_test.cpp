// The table residual code of stream version 2 (codec/common/table_residual_format.h, CodecSettings::table_residuals): the
// closed loop, determinism, the version byte and flag, residual symbols written and read back, the frame bound, and
// hostile streams (every refusal bad_data in one line, never a crash).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <functional>
#include <iterator>
#include <random>
#include <string>

#include "common/float_bits.h"
#include "common/range_coder.h"
#include "common/stream.h"
#include "common/stream_format.h"
#include "common/table_residual_format.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "decode/table_residual_decoder.h"
#include "encode/encoder.h"
#include "encode/metrics.h"
#include "encode/stream_writer.h"
#include "encode/table_residual_encoder.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

// `shape` animated for `frames` frames: the half right of its middle (in x) bends about z by up to `bend` radians,
// with a travelling ripple in y. With `jump`, vertex 20 jumps back and forth in x far from its cluster's motion:
// residuals far beyond ±2, which the table code carries in the body.
FrameSequence animated(const FrameSequence& shape, size_t frames, double bend, double phase, bool jump = false) {
  double low = INFINITY, high = -INFINITY;
  for (size_t v = 0; v < shape.vertex_count; ++v) {
    low = std::min(low, double(shape.positions[v * 3]));
    high = std::max(high, double(shape.positions[v * 3]));
  }
  const double middle = (low + high) / 2, half = (high - low) / 2;
  FrameSequence clip = shape;
  clip.frame_count = frames;
  clip.positions.clear();
  for (size_t f = 0; f < frames; ++f) {
    const double t = double(f) / double(frames);
    for (size_t v = 0; v < shape.vertex_count; ++v) {
      const double u = (shape.positions[v * 3] - middle) / half;  // in [−1, 1]
      const double x = u * 2, y = shape.positions[v * 3 + 1] * 2 / half, z = shape.positions[v * 3 + 2];
      const double angle = x > 0 ? bend * t * x / 2 : 0.0;
      const double ripple = 0.02 * std::sin(3 * x + 6.28 * t + phase);
      const double bent_x = x * std::cos(angle) - y * std::sin(angle);
      const double bent_y = x * std::sin(angle) + y * std::cos(angle) + ripple;
      clip.positions.insert(clip.positions.end(),
                            {float(middle + bent_x * half / 2), float(bent_y * half / 2), float(z)});
    }
    if (jump) clip.positions[(f * shape.vertex_count + 20) * 3] = float(middle + (f % 2 ? 0.75 : -0.75) * half);
    clip.times.push_back(float(f) / 30);
  }
  return clip;
}

using testing::kg;
using testing::quantized_base;

// Clips of `shape` with copies appended: of vertices 0, 1 and 2 with the same frames (welded to their originals), and
// of vertex 3 that drifts away from it (the same base position, not welded). Each copy takes over one triangle corner.
std::vector<FrameSequence> with_copies(std::vector<FrameSequence> clips) {
  const size_t v = clips[0].vertex_count;
  for (FrameSequence& clip : clips) {
    std::vector<float> positions;
    for (size_t f = 0; f < clip.frame_count; ++f) {
      const float* frame = clip.frame(f);
      positions.insert(positions.end(), frame, frame + v * 3);
      positions.insert(positions.end(), frame, frame + 9);
      positions.insert(positions.end(), {frame[9] + 0.01f * float(f), frame[10], frame[11]});
    }
    clip.positions = positions;
    clip.vertex_count = v + 4;
    for (uint32_t original = 0; original < 4; ++original)
      for (uint32_t& index : clip.triangles)
        if (index == original) {
          index = uint32_t(v) + original;
          break;
        }
  }
  for (FrameSequence& clip : clips) clip.triangles = clips[0].triangles;
  return clips;
}

using testing::Encoded;
using testing::encode;

// The table code in a version-2 stream: without version 3's frame references and motion contexts, which
// frame_references_test covers (with the table code too).
CodecSettings table(CodecSettings settings) {
  settings.table_residuals = true;
  settings.frame_references = settings.motion_contexts = settings.weight_contexts = false;
  return settings;
}

CodecSettings error(double target) {
  CodecSettings settings;
  settings.target = target;
  return settings;
}

CodecSettings predictors(CodecSettings settings, bool temporal, bool spatial) {
  settings.temporal_residuals = temporal;
  settings.spatial_residuals = spatial;
  return settings;
}

uint32_t body_length(const std::vector<uint8_t>& stream) {
  return uint32_t(stream[6]) | uint32_t(stream[7]) << 8 | uint32_t(stream[8]) << 16 | uint32_t(stream[9]) << 24;
}

void set_body_length(std::vector<uint8_t>& stream, uint32_t length) {
  for (int i = 0; i < 4; ++i) stream[6 + size_t(i)] = uint8_t(length >> (8 * i));
}

// Where the table code's rANS words begin: after the header and the body.
size_t symbols_at(const std::vector<uint8_t>& stream) {
  return format::kHeaderBytes + body_length(stream);
}

// One case of the closed loop: clips, their base, table settings, and what the case is there for.
struct Case {
  std::string name;
  std::vector<FrameSequence> clips;
  CodecSettings settings;
  bool odd_welded = false;    // W is odd (the two rANS states swap roles from frame to frame)
  bool fewer_welded = false;  // W < V
  bool large = false;         // some residual beyond ±2
};

std::vector<Case> cases() {
  const FrameSequence sphere = testing::stretched_sphere(3, 2.0), small = testing::stretched_sphere(2, 2.0);
  // 81 vertices, all base positions distinct.
  const FrameSequence grid = testing::height_field(8, [](int i, int j) { return 0.1 * std::sin(i + 0.5 * j); });
  CodecSettings bpvf;
  bpvf.mode = RateMode::bpvf;
  bpvf.target = 4;
  std::vector<Case> list = {
      {"error 0.5", {animated(sphere, 24, 1.0, 0)}, table(error(0.5))},
      {"error 0.05, a jumping vertex", {animated(sphere, 16, 1.0, 0, true)}, table(error(0.05)), false, false, true},
      {"no prediction", {animated(sphere, 16, 0.8, 1)}, table(predictors(error(0.15), false, false))},
      {"temporal prediction only", {animated(sphere, 16, 0.8, 1)}, table(predictors(error(0.15), true, false))},
      {"spatial prediction only", {animated(sphere, 16, 0.8, 1)}, table(predictors(error(0.15), false, true))},
      {"bpvf 4", {animated(sphere, 20, 1.2, 2)}, table(bpvf)},
      {"three clips",
       {animated(small, 15, 1.0, 0), animated(small, 9, -1.0, 1), animated(small, 4, 0.3, 2)},
       table(error(0.15))},
      {"odd welded count", {animated(grid, 14, 0.7, 0), animated(grid, 5, -0.4, 1)}, table(error(0.15)), true},
      {"copies of vertices, a jumping vertex",
       with_copies({animated(small, 13, 1.0, 0, true), animated(small, 6, -0.5, 1, true)}), table(error(0.1)), true,
       true, true},
  };
  return list;
}

// The decoder gives back the encoder's own reconstruction bit for bit, with the residuals in the table code, for
// every configuration: each residual predictor on and off, a rate target, several clips, an odd welded count, vertex
// copies (W < V), residuals far beyond ±2. The error target is met.
TEST(TableResiduals, DecodingGivesTheEncodersReconstructionExactly) {
  uint8_t flags_seen = 0, flags_missed = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const std::vector<float> base = quantized_base(c.clips[0]);
    const Encoded encoded = encode(c.clips, base, c.settings);
    ASSERT_GT(encoded.stream.size(), format::kHeaderBytes);
    EXPECT_EQ(encoded.stream[4], format::kTableVersion);
    EXPECT_TRUE(encoded.stream[5] & format::kFlagTableResiduals);
    flags_seen |= encoded.stream[5];
    flags_missed |= uint8_t(~encoded.stream[5]);

    StreamContent content;
    const Status read = read_stream(encoded.stream.data(), encoded.stream.size(), base, content);
    ASSERT_TRUE(read.ok()) << read.message();
    if (c.odd_welded) {
      EXPECT_EQ(content.welded_count % 2, 1u);
    }
    if (c.fewer_welded) {
      EXPECT_LT(content.welded_count, content.vertex_count);
    }
    if (c.large) {
      EXPECT_TRUE(
          std::any_of(content.residuals.begin(), content.residuals.end(), [](int64_t r) { return r < -2 || r > 2; }));
    }

    std::vector<FrameSequence> decoded;
    const Status status =
        decode_animation(encoded.stream.data(), encoded.stream.size(), base, c.clips[0].triangles, decoded);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(decoded.size(), c.clips.size());
    for (size_t clip = 0; clip < c.clips.size(); ++clip) {
      EXPECT_EQ(decoded[clip].frame_count, c.clips[clip].frame_count);
      EXPECT_EQ(decoded[clip].positions, encoded.reconstruction[clip].positions) << "clip " << clip;
    }
    if (c.settings.mode == RateMode::error) {
      EXPECT_LE(kg(c.clips, decoded), c.settings.target);
    }
  }
  // The cases covered streams with and without each residual predictor.
  for (uint8_t flag : {format::kFlagTemporalResiduals, format::kFlagSpatialResiduals}) {
    EXPECT_TRUE(flags_seen & flag) << int(flag);
    EXPECT_TRUE(flags_missed & flag) << int(flag);
  }
}

TEST(TableResiduals, TwoEncodesAreByteIdentical) {
  for (const Case& c : cases()) {
    if (c.name != "error 0.5" && c.name != "copies of vertices, a jumping vertex") continue;
    SCOPED_TRACE(c.name);
    const std::vector<float> base = quantized_base(c.clips[0]);
    EXPECT_EQ(encode(c.clips, base, c.settings).stream, encode(c.clips, base, c.settings).stream);
  }
}

// Version 2 and the flag exactly when the setting asks for the table code: without it the stream is version 1, as
// the default writes it. With an error target the setting changes how the residuals are coded, not which: both
// streams hold the same content but for the flag.
TEST(TableResiduals, VersionTwoAndTheFlagOnlyWithTheSetting) {
  const std::vector<FrameSequence> clips = {animated(testing::stretched_sphere(3, 2.0), 20, 0.8, 1)};
  const std::vector<float> base = quantized_base(clips[0]);
  EXPECT_FALSE(CodecSettings().table_residuals);
  CodecSettings adaptive;
  adaptive.table_residuals = false;
  adaptive.frame_references = adaptive.motion_contexts = adaptive.weight_contexts = false;
  adaptive.transform_residuals = false;  // version 4 replaces the residual code
  const Encoded plain = encode(clips, base, adaptive), fast = encode(clips, base, table(CodecSettings()));
  CodecSettings defaults;
  defaults.frame_references = defaults.motion_contexts = defaults.weight_contexts = false;
  defaults.transform_residuals = false;
  EXPECT_EQ(plain.stream, encode(clips, base, defaults).stream);
  EXPECT_EQ(plain.stream[4], format::kAdaptiveVersion);
  EXPECT_FALSE(plain.stream[5] & format::kFlagTableResiduals);
  EXPECT_EQ(fast.stream[4], format::kTableVersion);
  EXPECT_TRUE(fast.stream[5] & format::kFlagTableResiduals);
  EXPECT_NE(plain.stream, fast.stream);

  StreamContent from_plain, from_fast;
  ASSERT_TRUE(read_stream(plain.stream.data(), plain.stream.size(), base, from_plain).ok());
  ASSERT_TRUE(read_stream(fast.stream.data(), fast.stream.size(), base, from_fast).ok());
  EXPECT_EQ(from_fast.flags, from_plain.flags | format::kFlagTableResiduals);
  EXPECT_EQ(from_fast.motion, from_plain.motion);
  EXPECT_EQ(from_fast.residuals, from_plain.residuals);
  EXPECT_EQ(fast.reconstruction[0].positions, plain.reconstruction[0].positions);
}

// Lossless streams keep the adaptive code: the setting changes nothing, and the floats come back bit for bit.
TEST(TableResiduals, LosslessIgnoresTheSetting) {
  const std::vector<FrameSequence> clips = {animated(testing::stretched_sphere(2, 2.0), 8, 1.2, 2, true),
                                            animated(testing::stretched_sphere(2, 2.0), 5, -0.5, 0.3)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings lossless;
  lossless.mode = RateMode::lossless;
  lossless.frame_references = lossless.motion_contexts = lossless.weight_contexts = false;
  const Encoded encoded = encode(clips, base, table(lossless));
  EXPECT_EQ(encoded.stream, encode(clips, base, lossless).stream);
  EXPECT_EQ(encoded.stream[4], format::kAdaptiveVersion);
  EXPECT_FALSE(encoded.stream[5] & format::kFlagTableResiduals);
  EXPECT_TRUE(encoded.stream[5] & format::kFlagLossless);
  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, decoded).ok());
  ASSERT_EQ(decoded.size(), 2u);
  for (size_t c = 0; c < 2; ++c) {
    ASSERT_EQ(decoded[c].positions.size(), clips[c].positions.size());
    EXPECT_EQ(std::memcmp(decoded[c].positions.data(), clips[c].positions.data(), clips[c].positions.size() * 4), 0);
  }
}

// A rate target counts the bytes the table code really takes (they differ from the adaptive code's).
TEST(TableResiduals, RateTargetWithinFivePercent) {
  const std::vector<FrameSequence> clips = {animated(testing::stretched_sphere(3, 2.0), 40, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  for (double target : {1.5, 3.0, 6.0}) {
    CodecSettings settings;
    settings.mode = RateMode::bpvf;
    settings.target = target;
    const Encoded encoded = encode(clips, base, table(settings));
    EXPECT_EQ(encoded.stream[4], format::kTableVersion);
    EXPECT_NEAR(bits_per_vertex_frame(encoded.stream.size(), clips[0].vertex_count, clips[0].frame_count), target,
                0.05 * target);
  }
}

// A table stream of the sphere (162 vertices) read back into its content, for tests that write their own residuals.
struct TableStream {
  std::vector<FrameSequence> clips;
  std::vector<float> base;
  std::vector<uint8_t> stream;
  StreamContent content;
};

TableStream table_stream(size_t frames, double target = 0.15) {
  TableStream s;
  s.clips = {animated(testing::stretched_sphere(2, 2.0), frames, 1.0, 0, true)};
  s.base = quantized_base(s.clips[0]);
  s.stream = encode(s.clips, s.base, table(error(target))).stream;
  const Status status = read_stream(s.stream.data(), s.stream.size(), s.base, s.content);
  EXPECT_TRUE(status.ok()) << status.message();
  return s;
}

// The stream of `s` with every residual zero: its most compressible table stream.
std::vector<uint8_t> zero_residual_stream(const TableStream& s) {
  StreamContent zero = s.content;
  std::fill(zero.residuals.begin(), zero.residuals.end(), 0);
  std::vector<uint8_t> stream;
  write_stream(zero, s.base, stream);
  return stream;
}

// `content` written with its residuals replaced by `residuals`, read back: the same residuals, in a version-2 stream
// with the flag.
void expect_residuals_round_trip(const TableStream& s, const std::vector<int64_t>& residuals, const char* what) {
  SCOPED_TRACE(what);
  StreamContent content = s.content;
  ASSERT_EQ(residuals.size(), content.residuals.size());
  content.residuals = residuals;
  std::vector<uint8_t> stream;
  write_stream(content, s.base, stream);
  ASSERT_GT(stream.size(), format::kHeaderBytes);
  EXPECT_EQ(stream[4], format::kTableVersion);
  EXPECT_TRUE(stream[5] & format::kFlagTableResiduals);
  StreamContent read;
  const Status status = read_stream(stream.data(), stream.size(), s.base, read);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(read.flags, content.flags);
  EXPECT_TRUE(read.residuals == residuals);  // (not EXPECT_EQ: tens of thousands of values would be printed)
  size_t first_difference = 0;
  while (first_difference < residuals.size() && first_difference < read.residuals.size() &&
         read.residuals[first_difference] == residuals[first_difference])
    ++first_difference;
  EXPECT_EQ(first_difference, residuals.size()) << "first difference at " << first_difference;
}

// The table code round-trips residual symbols as they are: every clamped value (0, ±1, ±2), magnitudes just above
// the clamp and up to ±(2^31 − 1), whole frames and long runs of vertices at zero.
TEST(TableResiduals, CraftedResidualsRoundTrip) {
  const TableStream s = table_stream(48);
  ASSERT_TRUE(s.content.flags & format::kFlagTableResiduals);
  const size_t row = size_t(s.content.welded_count) * 3, frames = s.content.frame_count();
  // clang-format off
  const int64_t values[] = {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, 100, -100, 65535, -65536, 1 << 20, INT32_MAX,
                            -int64_t(INT32_MAX), INT32_MAX - 1, -int64_t(INT32_MAX) + 1, INT32_MAX - 3};
  // clang-format on
  std::mt19937 random(7);
  std::vector<int64_t> residuals(row * frames, 0);
  for (size_t f = 0; f < frames; ++f) {
    if (f >= 10 && f < 30) continue;  // 20 frames of zeros
    for (size_t i = 0; i < row; ++i) {
      const size_t vertex = i / 3;
      if (vertex >= 40 && vertex < 120) continue;  // a long run of zero vertices in every frame
      residuals[f * row + i] = values[random() % std::size(values)];
    }
  }
  // Every value on every axis in the first frame, in order.
  for (size_t i = 0; i < row; ++i) residuals[i] = values[(i / 3 + i % 3) % std::size(values)];
  expect_residuals_round_trip(s, residuals, "crafted");
}

// Distributions at the edges of the frequency tables: every residual zero (a context holds one symbol, capped below
// the total), one other symbol everywhere, every symbol equally likely, a few rare symbols beside a dominant one
// (rounding gives more than the total), every residual the largest magnitude.
TEST(TableResiduals, ExtremeDistributionsRoundTrip) {
  const TableStream s = table_stream(40);
  const size_t count = s.content.residuals.size();
  expect_residuals_round_trip(s, std::vector<int64_t>(count, 0), "all zero");
  std::vector<int64_t> one(count);
  for (size_t i = 0; i < count; ++i) one[i] = i % 3 == 0 ? 1 : i % 3 == 1 ? -2 : 2;
  expect_residuals_round_trip(s, one, "one symbol");
  std::mt19937 random(3);
  std::vector<int64_t> uniform(count), skewed(count, 0);
  for (int64_t& r : uniform) r = int64_t(random() % 7) - 3;
  for (size_t i = 0; i < count; i += 3)
    if (random() % 100 < 3)
      for (size_t a = 0; a < 3; ++a) skewed[i + a] = int64_t(random() % 7) - 3;
  expect_residuals_round_trip(s, uniform, "uniform");
  expect_residuals_round_trip(s, skewed, "skewed");
  expect_residuals_round_trip(s, std::vector<int64_t>(count, INT32_MAX), "largest");
  expect_residuals_round_trip(s, std::vector<int64_t>(count, -int64_t(INT32_MAX)), "smallest");
}

// frame_bound() holds the frames of a table stream, even its most compressible one (every residual zero: each
// vertex-frame a symbol of frequency 4032/4096), and is no larger than the symbol bytes allow (spec: 376
// vertex-frames per byte).
TEST(TableResiduals, FrameBoundHoldsTheFramesAndFollowsTheSymbolBytes) {
  const TableStream s = table_stream(300, 0.5);
  const std::vector<uint8_t> zero_stream = zero_residual_stream(s);
  const std::vector<uint8_t>* streams[] = {&s.stream, &zero_stream};
  for (const std::vector<uint8_t>* stream : streams) {
    StreamReader reader(stream->data(), stream->size());
    StreamContent content;
    ASSERT_TRUE(reader.read_head(s.base, content).ok());
    const size_t symbol_bytes = stream->size() - symbols_at(*stream);
    const size_t bound = reader.frame_bound();
    EXPECT_GE(bound, content.frame_count()) << symbol_bytes << " symbol bytes";
    EXPECT_LE(bound, symbol_bytes * 376 / content.welded_count + 1);
  }
  // The zero stream is near the bound: the bound is not loose by orders of magnitude.
  StreamReader reader(zero_stream.data(), zero_stream.size());
  StreamContent content;
  ASSERT_TRUE(reader.read_head(s.base, content).ok());
  EXPECT_LT(reader.frame_bound(), 2 * content.frame_count());
}

// decode_animation and read_stream refuse `stream` as bad data, in one line; the message contains `expected`.
void expect_refused(const TableStream& s, const std::vector<uint8_t>& stream, const std::string& expected,
                    const std::string& what) {
  SCOPED_TRACE(what);
  std::vector<FrameSequence> decoded;
  const Status status = decode_animation(stream.data(), stream.size(), s.base, s.clips[0].triangles, decoded);
  EXPECT_EQ(status.code(), StatusCode::bad_data) << status.message();
  EXPECT_FALSE(status.message().empty());
  EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
  EXPECT_NE(status.message().find(expected), std::string::npos) << status.message();
  StreamContent content;
  EXPECT_EQ(read_stream(stream.data(), stream.size(), s.base, content).code(), StatusCode::bad_data);
}

// The flag belongs to version 2 and to lossy streams; a version-2 stream without it is laid out as version 1.
TEST(TableResidualsHostile, TableFlagOutsideVersionTwoOrInALosslessStreamIsRefused) {
  const TableStream s = table_stream(6);
  std::vector<uint8_t> version_one = s.stream;
  version_one[4] = format::kAdaptiveVersion;
  expect_refused(s, version_one, "unknown flags", "version 1 with the table flag");
  std::vector<uint8_t> lossless = s.stream;
  lossless[5] |= format::kFlagLossless;
  expect_refused(s, lossless, "lossless", "the table flag with the lossless flag");
  std::vector<uint8_t> later = s.stream;
  later[4] = format::kNewestVersion + 1;
  std::vector<FrameSequence> decoded;
  EXPECT_EQ(decode_animation(later.data(), later.size(), s.base, s.clips[0].triangles, decoded).code(),
            StatusCode::unsupported);

  // An adaptive stream marked version 2 decodes as it does marked version 1 (and so does one marked version 3).
  CodecSettings plain = error(0.15);
  plain.frame_references = plain.motion_contexts = plain.weight_contexts = false;
  const Encoded adaptive = encode(s.clips, s.base, plain);
  ASSERT_EQ(adaptive.stream[4], format::kAdaptiveVersion);
  std::vector<uint8_t> three = adaptive.stream;
  three[4] = format::kReferenceVersion;
  ASSERT_TRUE(decode_animation(three.data(), three.size(), s.base, s.clips[0].triangles, decoded).ok());
  EXPECT_EQ(decoded[0].positions, adaptive.reconstruction[0].positions);
  std::vector<uint8_t> marked = adaptive.stream;
  marked[4] = format::kTableVersion;
  const Status status = decode_animation(marked.data(), marked.size(), s.base, s.clips[0].triangles, decoded);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(decoded[0].positions, adaptive.reconstruction[0].positions);
}

// The bytes after the body: an even number, at least the two states' 8; a body length beyond the stream.
TEST(TableResidualsHostile, BadSymbolStreamLengthsAreRefused) {
  const TableStream s = table_stream(6);
  const size_t at = symbols_at(s.stream);
  ASSERT_GE(s.stream.size() - at, 10u);
  std::vector<uint8_t> odd = s.stream;
  odd.push_back(0);
  expect_refused(s, odd, "bad length of the residual symbols", "one byte more");
  odd = s.stream;
  odd.erase(odd.begin() + long(at) + 3);
  expect_refused(s, odd, "bad length of the residual symbols", "one byte less");
  for (size_t kept : {0, 2, 4, 6, 7}) {
    std::vector<uint8_t> short_ = s.stream;
    short_.resize(at + kept);
    expect_refused(s, short_, "bad length of the residual symbols", std::to_string(kept) + " symbol bytes");
  }
  std::vector<uint8_t> beyond = s.stream;
  set_body_length(beyond, uint32_t(s.stream.size() - format::kHeaderBytes + 2));
  expect_refused(s, beyond, "truncated", "body length beyond the stream");
  set_body_length(beyond, UINT32_MAX);
  expect_refused(s, beyond, "truncated", "body length 2^32 − 1");
  // A body length that leaves an even count of at least 8 bytes, but moves the boundary: refused somewhere.
  for (int shift : {-2, 2}) {
    std::vector<uint8_t> moved = s.stream;
    set_body_length(moved, uint32_t(int64_t(body_length(s.stream)) + shift));
    std::vector<FrameSequence> decoded;
    const Status status = decode_animation(moved.data(), moved.size(), s.base, s.clips[0].triangles, decoded);
    EXPECT_EQ(status.code(), StatusCode::bad_data) << shift;
  }
}

// The rANS words end with the stream: a word missing at the end, or one more, is refused.
TEST(TableResidualsHostile, TruncatedOrExtraSymbolWordsAreRefused) {
  const TableStream s = table_stream(6);
  ASSERT_GE(s.stream.size() - symbols_at(s.stream), 12u);
  std::vector<uint8_t> shorter = s.stream;
  shorter.resize(shorter.size() - 2);
  expect_refused(s, shorter, "truncated", "the last word missing");
  shorter.resize(shorter.size() - 2);
  expect_refused(s, shorter, "truncated", "the last two words missing");
  std::vector<uint8_t> longer = s.stream;
  longer.insert(longer.end(), {0, 0});
  expect_refused(s, longer, "do not end with the stream", "a word more");
  longer = s.stream;
  longer.insert(longer.end(), {0x34, 0x12, 0x78, 0x56});
  expect_refused(s, longer, "do not end with the stream", "two words more");
}

// A state below 2^16 at the start is refused (each state's first word is its high half).
TEST(TableResidualsHostile, StateBelowTwoToTheSixteenIsRefused) {
  const TableStream s = table_stream(6);
  const size_t at = symbols_at(s.stream);
  for (size_t state = 0; state < 2; ++state) {
    std::vector<uint8_t> low = s.stream;
    low[at + state * 4] = low[at + state * 4 + 1] = 0;
    expect_refused(s, low, "bad residual symbol state", "state " + std::to_string(state));
  }
}

// A change to any one rANS word is refused: the states then end elsewhere than where they started (2^16), or the
// words are not used up. Most plainly in a stream with every residual zero, where the body has nothing after the
// tables that could notice a different symbol.
TEST(TableResidualsHostile, EveryChangedSymbolWordIsRefused) {
  const TableStream s = table_stream(40);
  const std::vector<uint8_t> zero_stream = zero_residual_stream(s);
  const std::vector<uint8_t>* streams[] = {&s.stream, &zero_stream};
  for (const std::vector<uint8_t>* stream : streams) {
    const size_t at = symbols_at(*stream);
    ASSERT_GE(stream->size() - at, 16u);
    for (size_t byte = at; byte < stream->size(); byte += 2)
      for (uint8_t bits : {0x01, 0x80}) {
        std::vector<uint8_t> changed = *stream;
        changed[byte + (bits == 0x80 ? 1 : 0)] ^= bits;  // the low bit, or the high bit, of the word
        StreamContent content;
        const Status status = read_stream(changed.data(), changed.size(), s.base, content);
        EXPECT_EQ(status.code(), StatusCode::bad_data) << "word " << (byte - at) / 2 << ", bits " << int(bits);
      }
  }
}

int bits_for(uint32_t count) {  // as codec/common/stream_syntax.h
  int bits = 0;
  while (bits < 32 && (uint64_t(1) << bits) < count) ++bits;
  return bits;
}

// The stream write_stream makes of `content` up to its residual steps, written here model by model (a mirror of
// codec/encode/stream_writer.cpp for a base without two identical positions), then what `rest` codes into the body, then the bytes
// `rest` returns after it. For table streams whose body holds what write_stream never writes.
std::vector<uint8_t> hand_written(const StreamContent& c,
                                  const std::function<std::vector<uint8_t>(RangeEncoder&)>& rest) {
  std::vector<uint8_t> out = {'S', 'G', 'M', 'A', format::kTableVersion, c.flags, 0, 0, 0, 0};
  std::vector<uint8_t> after;
  {
    RangeEncoder encoder(out);
    UnsignedModel count;
    std::array<SignedModel, 12> motion;
    BitTreeModel extra_count(2);
    SignedModel weight;
    count.encode(encoder, c.vertex_count);
    count.encode(encoder, uint32_t(c.clip_frames.size()));
    for (uint32_t frames : c.clip_frames) count.encode(encoder, frames);
    count.encode(encoder, c.cluster_count);
    BitTreeModel label_model(bits_for(c.cluster_count));
    for (uint32_t label : c.labels) label_model.encode(encoder, label);
    encoder.encode_direct_bits(float_bits(c.linear_step), 32);
    encoder.encode_direct_bits(float_bits(c.translation_step), 32);
    const size_t clusters = c.cluster_count;
    for (size_t i = 0; i < c.motion.size(); ++i)
      motion[i % 12].encode(encoder, c.motion[i] - (i < clusters * 12 ? 0 : c.motion[i - clusters * 12]));
    count.encode(encoder, uint32_t(c.weight_bits));
    BitTreeModel cluster_model(bits_for(c.cluster_count));
    for (size_t w = 0; w < c.welded_count; ++w) {
      extra_count.encode(encoder, c.weight_offset[w + 1] - c.weight_offset[w]);
      for (uint32_t i = c.weight_offset[w]; i < c.weight_offset[w + 1]; ++i) {
        cluster_model.encode(encoder, c.weight_cluster[i]);
        weight.encode(encoder, c.weight_value[i]);
      }
    }
    for (int axis = 0; axis < 3; ++axis) encoder.encode_direct_bits(float_bits(c.residual_step[axis]), 32);
    after = rest(encoder);
    encoder.finish();
  }
  set_body_length(out, uint32_t(out.size() - format::kHeaderBytes));
  out.insert(out.end(), after.begin(), after.end());
  return out;
}

// Frequency tables a stream may not hold are refused: a context whose frequencies sum to less or more than 4096, a
// frequency above 4032 (even one symbol taking all 4096, or one near 2^32), a context with no symbol; tables cut
// short by the end of the body.
TEST(TableResidualsHostile, BadFrequencyTablesAreRefused) {
  const TableStream s = table_stream(6);
  for (const std::vector<uint32_t>& group : identical_position_groups(s.base)) ASSERT_EQ(group.size(), 1u);
  // The mirror writes what write_stream writes.
  const std::vector<uint8_t> mirrored = hand_written(s.content, [&](RangeEncoder& encoder) {
    std::vector<uint8_t> symbols;
    encode_table_residuals(encoder, s.content.residuals, s.content.welded_count, symbols);
    return symbols;
  });
  ASSERT_EQ(mirrored, s.stream);

  using table_code::kContexts;
  using table_code::kSymbols;
  using table_code::kZeroSymbol;
  // Valid tables: in every context the zero symbol 4032, symbol 0 the other 64; `change` alters them.
  auto with_tables = [&](const std::function<void(std::vector<uint32_t>&)>& change, int contexts_written) {
    std::vector<uint32_t> frequency(size_t(kContexts) * kSymbols, 0);
    for (int c = 0; c < kContexts; ++c) {
      frequency[size_t(c) * kSymbols + kZeroSymbol] = 4032;
      frequency[size_t(c) * kSymbols] = 64;
    }
    change(frequency);
    return hand_written(s.content, [&](RangeEncoder& encoder) {
      UnsignedModel model;
      for (size_t i = 0; i < size_t(contexts_written) * kSymbols; ++i) model.encode(encoder, frequency[i]);
      return std::vector<uint8_t>{0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00};  // both states 2^16
    });
  };
  auto at = [](int context, int symbol) { return size_t(context) * kSymbols + size_t(symbol); };
  // The valid tables pass (the stream then fails at its symbols, which these 8 bytes do not hold).
  {
    const std::vector<uint8_t> valid = with_tables([](std::vector<uint32_t>&) {}, kContexts);
    std::vector<FrameSequence> decoded;
    const Status status = decode_animation(valid.data(), valid.size(), s.base, s.clips[0].triangles, decoded);
    EXPECT_EQ(status.code(), StatusCode::bad_data);
    EXPECT_EQ(status.message().find("frequency table"), std::string::npos) << status.message();
  }
  const struct {
    const char* what;
    std::function<void(std::vector<uint32_t>&)> change;
  } bad[] = {
      {"sum 4095", [&](std::vector<uint32_t>& f) { f[at(5, kZeroSymbol)] = 4031; }},
      {"sum 4097", [&](std::vector<uint32_t>& f) { f[at(5, kSymbols - 1)] = 1; }},
      {"frequency 4033", [&](std::vector<uint32_t>& f) { f[at(0, kZeroSymbol)] = 4033, f[at(0, 0)] = 63; }},
      {"frequency 4096", [&](std::vector<uint32_t>& f) { f[at(15, kZeroSymbol)] = 4096, f[at(15, 0)] = 0; }},
      {"frequency 2^32 - 1", [&](std::vector<uint32_t>& f) { f[at(9, 0)] = UINT32_MAX; }},
      // 64 + (2^32 − 64) + 64 + 4032: 4096 in 32-bit arithmetic.
      {"frequencies wrapping past 2^32 to 4096",
       [&](std::vector<uint32_t>& f) { f[at(9, 1)] = UINT32_MAX - 63, f[at(9, 2)] = 64; }},
      {"no symbol", [&](std::vector<uint32_t>& f) { f[at(2, kZeroSymbol)] = f[at(2, 0)] = 0; }},
  };
  for (const auto& b : bad) expect_refused(s, with_tables(b.change, kContexts), "frequency table", b.what);
  for (int contexts : {0, 1, 15}) {
    const std::vector<uint8_t> cut = with_tables([](std::vector<uint32_t>&) {}, contexts);
    std::vector<FrameSequence> decoded;
    EXPECT_EQ(decode_animation(cut.data(), cut.size(), s.base, s.clips[0].triangles, decoded).code(),
              StatusCode::bad_data)
        << contexts << " contexts";
  }
}

// A magnitude beyond int32 (the encoder never writes one; a damaged stream may claim it) is refused: the excess
// 2^31 − 3 above 3 of an axis clamped to ±2. (The magnitude 2^31 − 1 round-trips: CraftedResidualsRoundTrip.)
TEST(TableResidualsHostile, MagnitudeBeyondInt32IsRefused) {
  const TableStream s = table_stream(4);
  for (const std::vector<uint32_t>& group : identical_position_groups(s.base)) ASSERT_EQ(group.size(), 1u);
  // Tables in which slot 0, where states of 2^16 start, is symbol 0: (−2, −2, −2), all three axes clamped. The first
  // vertex-frame decodes it and reads the excess of axis 0 from the body.
  auto with_excess = [&](uint32_t minus_three) {
    return hand_written(s.content, [&](RangeEncoder& encoder) {
      UnsignedModel model;
      for (int c = 0; c < table_code::kContexts; ++c)
        for (int symbol = 0; symbol < table_code::kSymbols; ++symbol)
          model.encode(encoder, symbol == 0 ? 64 : symbol == table_code::kZeroSymbol ? 4032 : 0);
      ExcessModels excess;
      encoder.encode_bit(excess.above_two[0], 1);
      excess.minus_three[0].encode(encoder, minus_three);
      // Both states 2^16, and the word the first vertex-frame reads.
      return std::vector<uint8_t>{0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00};
    });
  };
  expect_refused(s, with_excess(uint32_t(INT32_MAX) - 2), "residual outside int32", "excess 2^31 - 3");
  // The largest magnitude passes that check (the stream fails later: its 10 bytes of words hold one vertex-frame).
  const std::vector<uint8_t> largest = with_excess(uint32_t(INT32_MAX) - 3);
  std::vector<FrameSequence> decoded;
  const Status status = decode_animation(largest.data(), largest.size(), s.base, s.clips[0].triangles, decoded);
  EXPECT_EQ(status.code(), StatusCode::bad_data);
  EXPECT_EQ(status.message().find("int32"), std::string::npos) << status.message();
}

// Every prefix of a table stream is refused, with its length field as written or made to match.
TEST(TableResidualsHostile, PrefixesAreRefused) {
  const TableStream s = table_stream(4);
  std::vector<FrameSequence> decoded;
  for (size_t size = 0; size < s.stream.size(); ++size) {
    EXPECT_FALSE(decode_animation(s.stream.data(), size, s.base, s.clips[0].triangles, decoded).ok())
        << "prefix of " << size << " bytes";
    if (size < symbols_at(s.stream) && size >= format::kHeaderBytes + 8) {
      // The body cut as well, and the length field saying so: the symbol stream starts in the body's bytes.
      std::vector<uint8_t> prefix(s.stream.begin(), s.stream.begin() + long(size));
      set_body_length(prefix, uint32_t(size - format::kHeaderBytes - 8));
      EXPECT_FALSE(decode_animation(prefix.data(), prefix.size(), s.base, s.clips[0].triangles, decoded).ok())
          << "prefix of " << size << " bytes, body length " << size - format::kHeaderBytes - 8;
    }
  }
}

// Random changes anywhere, and in the rANS words alone: never a crash; a refusal is one line; what decodes is
// finite. Nearly every change is caught (the range coder's end check, the rANS states' final value).
TEST(TableResidualsHostile, RandomByteFlipsNeverCrash) {
  const TableStream s = table_stream(6);
  const size_t at = symbols_at(s.stream);
  std::mt19937 random(12);
  for (bool symbols_only : {false, true}) {
    size_t refused = 0;
    for (int trial = 0; trial < 300; ++trial) {
      std::vector<uint8_t> bytes = s.stream;
      for (int flips = 1 + int(random() % 4); flips > 0; --flips) {
        const size_t i = symbols_only ? at + random() % (bytes.size() - at) : random() % bytes.size();
        bytes[i] ^= uint8_t(1 + random() % 255);
      }
      std::vector<FrameSequence> decoded;
      const Status status = decode_animation(bytes.data(), bytes.size(), s.base, s.clips[0].triangles, decoded);
      if (!status.ok()) {
        ++refused;
        EXPECT_EQ(status.message().find('\n'), std::string::npos);
      } else {
        for (const FrameSequence& clip : decoded)
          for (float x : clip.positions) ASSERT_TRUE(std::isfinite(x));
      }
    }
    EXPECT_GT(refused, 270u) << (symbols_only ? "in the symbols" : "anywhere");
  }
}

// The worked example of spec/entropy-coding.md section 9.7: a table-code section on its own (W = 5, F = 3), its
// body and symbol stream byte for byte, and its decoding back, excesses included.
// clang-format off
const std::vector<int64_t> kTableExample = {
    1, 1, 1,    -1, 2, 1,     1, -1, -1,   3, 1, -1,   -1, -1, -2,  // frame 0: vertices 0 .. 4
    1, -1, 1,   -1, -1, -1,   1, 1, -1,    -1, 1, 1,   1, -7, -1,   // frame 1
    0, 0, 0,    2, 0, 1,      0, 0, 0,     0, -1, 0,   -1, 0, 0,    // frame 2
};
const std::vector<uint8_t> kTableExampleBody = {
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F, 0xC8, 0x29, 0x3B, 0x00,
    0x20, 0x71, 0xB0, 0xB7, 0x7E, 0x6E, 0x45, 0xC7, 0xBA, 0x9B, 0xB1, 0x32, 0x85, 0xA1, 0x74, 0x7F, 0xB9, 0xBA,
    0x53, 0x67, 0xF4, 0xA5, 0x03, 0x1A, 0x78, 0x62, 0xF3, 0x56, 0x18, 0x2D, 0xFB, 0xA8, 0xE6, 0x9B, 0xA9, 0x2F,
    0x74, 0x53, 0xB5, 0x19, 0x67, 0xA2, 0x18, 0x46, 0xEC, 0xBF, 0x23, 0xCD, 0x83, 0x77, 0x5B, 0x43, 0xB3, 0x15,
    0x65, 0x62, 0x7B, 0xAF, 0x64, 0xBE, 0xAF, 0x70, 0x42, 0xF5, 0x9A, 0x71, 0xDE, 0x08, 0x9E, 0x00, 0xC2, 0x36,
    0x4C, 0x4D, 0x36, 0x2A, 0x3F, 0x70, 0x75, 0x09, 0x9F, 0x49, 0xBD, 0xFA, 0xAA, 0xB4, 0x79, 0xB0, 0xF5, 0xC4,
    0xB6, 0x0F, 0xD8, 0xE4, 0x7B, 0x71, 0xCF, 0x75, 0x8B, 0x0F, 0xC9, 0x10, 0x20, 0x3E, 0xA2, 0x42, 0x69, 0xC2,
    0x3D, 0x98, 0x9F, 0x73, 0xFE, 0xF8, 0xBC, 0x8A, 0x05, 0x39, 0x75, 0xF7, 0x80, 0x53,
};
const std::vector<uint8_t> kTableExampleSymbols = {
    0x01, 0x00, 0x1F, 0x7C, 0x01, 0x00, 0xCB, 0x33, 0xF1, 0xE6, 0x13, 0x2F,
};
// clang-format on

TEST(TableResidualSpec, WorkedExampleIsAGoldenVector) {
  std::vector<uint8_t> body, symbols;
  {
    RangeEncoder encoder(body);
    encode_table_residuals(encoder, kTableExample, 5, symbols);
    encoder.finish();
  }
  const char* changed =
      "the table code changed: if that is deliberate, update spec/entropy-coding.md 9.7 and the version";
  EXPECT_EQ(body, kTableExampleBody) << changed;
  EXPECT_EQ(symbols, kTableExampleSymbols) << changed;

  RangeDecoder decoder(kTableExampleBody.data(), kTableExampleBody.size());
  TableResidualDecoder residuals(5, kTableExampleSymbols.data(), kTableExampleSymbols.size());
  ASSERT_TRUE(residuals.read_tables(decoder).ok());
  EXPECT_EQ(decoder.position(), 141u);  // the spec: pos = 141 after the tables
  std::vector<int64_t> decoded(kTableExample.size());
  for (size_t f = 0; f < 3; ++f) residuals.decode_frame(decoder, &decoded[f * 15]);
  EXPECT_EQ(decoded, kTableExample);
  EXPECT_TRUE(residuals.finish().ok()) << residuals.finish().message();
  EXPECT_TRUE(decoder.finish().ok()) << decoder.finish().message();
  EXPECT_EQ(decoder.position(), 143u);  // L + 3
}

}  // namespace
}  // namespace segmorph
