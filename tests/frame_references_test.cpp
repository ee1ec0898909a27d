// Frame references (stream version 3, codec/encode/frame_references.h): the encoder gives a frame an earlier reference than
// the previous one where the motion repeats itself, keeps them only when they pay, and every way of decoding (whole
// clips, one frame or two at a time, after a seek) gives the encoder's frames; the decoder refuses references a
// stream may not hold. The other tools of version 3 too: the motion's and the weights' contexts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <string>

#include "common/range_coder.h"
#include "common/stream.h"
#include "common/stream_format.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "encode/stream_writer.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::encode;
using testing::Encoded;
using testing::quantized_base;

// A bending sphere whose first `period` frames play again and again until `frames`: a cycle, as a gait's.
FrameSequence cycling_clip(size_t frames, size_t period, double phase = 0) {
  const FrameSequence cycle = testing::bending_clip(period, 1.0, phase);
  FrameSequence clip = cycle;
  clip.frame_count = frames;
  clip.positions.clear();
  clip.times.clear();
  for (size_t f = 0; f < frames; ++f) {
    const float* frame = cycle.frame(f % period);
    clip.positions.insert(clip.positions.end(), frame, frame + cycle.vertex_count * 3);
    clip.times.push_back(float(f) / 30);
  }
  return clip;
}

// Version 3's tools on the residual loop: version 4's transform residuals, which replace the residuals these tests
// look at (their references, their decoding frame by frame), off.
CodecSettings residual_loop(CodecSettings settings = CodecSettings()) {
  settings.transform_residuals = false;
  return settings;
}

CodecSettings without_references(CodecSettings settings = residual_loop()) {
  settings.frame_references = false;
  return settings;
}

// A cycle played three times: version 3, its two repeats costing less than a fifth of what the first cycle costs
// alone (without references they cost most of what the first does), the error target met, and the decoder's frames
// the encoder's.
TEST(FrameReferences, ARepeatedCycleIsVersionThreeAndCostsLittleMore) {
  const std::vector<FrameSequence> clips = {cycling_clip(36, 12)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded with = encode(clips, base, residual_loop()), without = encode(clips, base, without_references());
  const Encoded once = encode({cycling_clip(12, 12)}, base, residual_loop());
  ASSERT_GT(with.stream.size(), 5u);
  EXPECT_EQ(with.stream[4], format::kReferenceVersion);
  EXPECT_TRUE(with.stream[5] & format::kFlagFrameReferences);
  EXPECT_FALSE(without.stream[5] & format::kFlagFrameReferences);
  EXPECT_LT(double(with.stream.size()), 1.2 * double(once.stream.size()))
      << with.stream.size() << " bytes with references, " << once.stream.size() << " for one cycle";
  EXPECT_GT(double(without.stream.size()), 1.6 * double(once.stream.size()))
      << without.stream.size() << " bytes without references, " << once.stream.size() << " for one cycle";
  EXPECT_LE(testing::kg(clips, with.reconstruction), 0.15 * 1.0001);

  StreamContent content;
  ASSERT_TRUE(read_stream(with.stream.data(), with.stream.size(), base, content).ok());
  ASSERT_EQ(content.references.size(), 36u);
  size_t long_references = 0;
  for (size_t f = 12; f < 36; ++f) long_references += content.references[f] % 12 == 0 && content.references[f] > 0;
  EXPECT_GE(long_references, 20u) << "the repeats should reference the frames a whole cycle back";

  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(with.stream.data(), with.stream.size(), base, clips[0].triangles, decoded).ok());
  ASSERT_EQ(decoded.size(), 1u);
  EXPECT_EQ(decoded[0].positions, with.reconstruction[0].positions);
}

// The frames are scored on threads, each range of frames with a ring of its own filled from as far back as its first
// frame's window reaches: two clips of cycles (a range may start inside either, or at a clip's first frame) give
// the same stream on every thread count, with references a cycle back in both clips.
TEST(FrameReferences, TheSameReferencesOnEveryThreadCount) {
  const std::vector<FrameSequence> clips = {cycling_clip(36, 12), cycling_clip(27, 9, 0.5)};
  const std::vector<float> base = quantized_base(clips[0]);
  std::vector<uint8_t> first;
  for (size_t threads : {1, 2, 3, 7}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    CodecSettings settings = residual_loop();
    settings.threads = threads;
    const Encoded encoded = encode(clips, base, settings);
    ASSERT_GT(encoded.stream.size(), 5u);
    EXPECT_TRUE(encoded.stream[5] & format::kFlagFrameReferences);
    if (threads == 1) {
      first = encoded.stream;
      StreamContent content;
      ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
      ASSERT_EQ(content.references.size(), 63u);
      EXPECT_EQ(content.references[30] % 12, 0u);
      EXPECT_GT(content.references[30], 0u);
      EXPECT_EQ(content.references[36 + 20] % 9, 0u);
      EXPECT_GT(content.references[36 + 20], 0u);
    } else {
      EXPECT_TRUE(encoded.stream == first) << "the stream differs from the one-thread stream";
    }
  }
}

// Lossless streams too: the frames come back bit for bit, in fewer bytes than without references.
TEST(FrameReferences, LosslessRepeatsAreSmallerAndExact) {
  const std::vector<FrameSequence> clips = {cycling_clip(24, 8)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings lossless;
  lossless.mode = RateMode::lossless;
  const Encoded with = encode(clips, base, lossless), without = encode(clips, base, without_references(lossless));
  EXPECT_EQ(with.stream[4], format::kReferenceVersion);
  EXPECT_LT(with.stream.size(), without.stream.size());
  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(with.stream.data(), with.stream.size(), base, clips[0].triangles, decoded).ok());
  ASSERT_EQ(decoded[0].positions.size(), clips[0].positions.size());
  EXPECT_EQ(std::memcmp(decoded[0].positions.data(), clips[0].positions.data(), clips[0].positions.size() * 4), 0);
}

// A motion that never comes back to a pose keeps the implied references: the same bytes as without the setting.
TEST(FrameReferences, MotionThatDoesNotRepeatHasNoReferences) {
  const std::vector<FrameSequence> clips = {testing::bending_clip(20, 1.2, 0.3)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded with = encode(clips, base, residual_loop()), without = encode(clips, base, without_references());
  EXPECT_FALSE(with.stream[5] & format::kFlagFrameReferences);
  EXPECT_EQ(with.stream, without.stream);
}

// Every way of decoding gives the same floats: two frames at a time (whose second frame references an earlier one
// than the first), one at a time, and from a clip reached by seeking back.
TEST(FrameReferences, OneOrTwoFramesAtATimeAndAfterASeekAreTheEncodersFrames) {
  const std::vector<FrameSequence> clips = {cycling_clip(15, 5), cycling_clip(13, 4, 1.0)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, residual_loop());
  ASSERT_EQ(encoded.stream[4], format::kReferenceVersion);
  // The premise: clips longer than the window and two, and a pair of frames decoded together (an even frame of its
  // clip and the next) whose second references further back than the first frame.
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  ASSERT_GT(content.clip_frames[0], content.reference_window + 2);
  bool far_second = false;
  for (size_t f = 1; f < content.clip_frames[0]; f += 2) far_second = far_second || content.references[f] >= 2;
  ASSERT_TRUE(far_second);
  const size_t row = clips[0].vertex_count * 3;
  for (bool two : {false, true}) {
    SCOPED_TRACE(two ? "two at a time" : "one at a time");
    FrameDecoder decoder;
    ASSERT_TRUE(decoder.open(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles).ok());
    for (int pass = 0; pass < 2; ++pass) {  // the second pass after seeking back to clip 0
      for (size_t c = 0; c < clips.size(); ++c) {
        std::vector<float> frames;
        while (decoder.next_clip() == c) {
          const size_t count = two && decoder.frames_left_in_clip() >= 2 ? 2 : 1;
          ASSERT_TRUE(decoder.decode_append(count, frames).ok());
        }
        EXPECT_EQ(frames, encoded.reconstruction[c].positions) << "clip " << c << ", pass " << pass;
        EXPECT_EQ(frames.size(), clips[c].frame_count * row);
      }
      ASSERT_TRUE(decoder.seek(0).ok());
    }
    // Straight to the second clip, and back to it from the middle of itself.
    FrameDecoder fresh;
    ASSERT_TRUE(fresh.open(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles).ok());
    ASSERT_TRUE(fresh.seek(1).ok());
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<float> frames;
      while (fresh.next_clip() == 1 && (pass == 1 || frames.size() < 5 * row))
        ASSERT_TRUE(fresh.decode_append(two && fresh.frames_left_in_clip() >= 2 ? 2 : 1, frames).ok());
      const std::vector<float>& want = encoded.reconstruction[1].positions;
      ASSERT_LE(frames.size(), want.size());
      EXPECT_TRUE(std::equal(frames.begin(), frames.end(), want.begin())) << "pass " << pass;
      ASSERT_TRUE(fresh.seek(1).ok());
    }
  }
}

// The stream of `content` written again with its flags in `mask` replaced by `option`, and read back into `read`.
std::vector<uint8_t> rewritten(const StreamContent& content, uint8_t mask, uint8_t option,
                               const std::vector<float>& base, StreamContent& read) {
  StreamContent changed = content;
  changed.flags = uint8_t((content.flags & ~mask) | option);
  std::vector<uint8_t> stream;
  write_stream(changed, base, stream);
  const Status status = read_stream(stream.data(), stream.size(), base, read);
  EXPECT_TRUE(status.ok()) << status.message();
  return stream;
}

// Version 3's motion codings (in contexts; in contexts and predicted linearly) carry the same coefficients as the
// plain one, read back exactly, and decode to the same frames; the encoder keeps the smallest, which on a smooth
// bend is not the plain one.
TEST(FrameReferences, MotionContextsAndLinearMotionCarryTheSameMotion) {
  const std::vector<FrameSequence> clips = {testing::bending_clip(40, 1.5, 0.2), testing::bending_clip(9, -0.7, 1.0)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, residual_loop());
  ASSERT_EQ(encoded.stream[4], format::kReferenceVersion);
  EXPECT_TRUE(encoded.stream[5] & format::kFlagMotionContexts);
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  std::map<uint8_t, size_t> sizes;
  const uint8_t both = format::kFlagMotionContexts | format::kFlagLinearMotion;
  for (uint8_t option : {uint8_t(0), uint8_t(format::kFlagMotionContexts), both}) {
    SCOPED_TRACE(int(option));
    StreamContent read;
    const std::vector<uint8_t> stream = rewritten(content, both, option, base, read);
    sizes[option] = stream.size();
    EXPECT_EQ(read.motion, content.motion);
    EXPECT_EQ(read.residuals, content.residuals);
    std::vector<FrameSequence> decoded;
    ASSERT_TRUE(decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded).ok());
    for (size_t c = 0; c < clips.size(); ++c) EXPECT_EQ(decoded[c].positions, encoded.reconstruction[c].positions);
  }
  EXPECT_EQ(encoded.stream.size(), std::min({sizes[0], sizes[format::kFlagMotionContexts], sizes[both]}));
  EXPECT_LT(encoded.stream.size(), sizes[0]);
}

// Version 3's weight coding (the extra count in contexts, the extra clusters as places among their own cluster's
// recent ones) carries the same weights as the plain one, reads back exactly and decodes to the same frames; the
// encoder writes it where it is smaller, which with blended weights over a few clusters it is.
TEST(FrameReferences, WeightContextsCarryTheSameWeights) {
  const std::vector<FrameSequence> clips = {testing::bending_clip(30, 1.5, 0.2)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings = residual_loop();
  settings.clusters = 8;
  const Encoded encoded = encode(clips, base, settings);
  ASSERT_EQ(encoded.stream[4], format::kReferenceVersion);
  EXPECT_TRUE(encoded.stream[5] & format::kFlagWeightContexts);
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  ASSERT_GT(content.weight_cluster.size(), 100u);
  std::map<uint8_t, size_t> sizes;
  for (uint8_t option : {uint8_t(0), format::kFlagWeightContexts}) {
    SCOPED_TRACE(int(option));
    StreamContent read;
    const std::vector<uint8_t> stream = rewritten(content, format::kFlagWeightContexts, option, base, read);
    sizes[option] = stream.size();
    EXPECT_EQ(read.weight_offset, content.weight_offset);
    EXPECT_EQ(read.weight_cluster, content.weight_cluster);
    EXPECT_EQ(read.weight_value, content.weight_value);
    std::vector<FrameSequence> decoded;
    ASSERT_TRUE(decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded).ok());
    EXPECT_EQ(decoded[0].positions, encoded.reconstruction[0].positions);
  }
  EXPECT_EQ(encoded.stream.size(), sizes[format::kFlagWeightContexts]);
  EXPECT_LT(sizes[format::kFlagWeightContexts], sizes[0]);
}

// --max-stream-version below 3 (CodecSettings: no frame references, no motion or weight contexts) gives the stream of
// versions 1 and 2 for the same input.
TEST(FrameReferences, WithoutVersionThreesToolsTheStreamIsVersionOne) {
  const std::vector<FrameSequence> clips = {cycling_clip(24, 8)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings = residual_loop();
  settings.frame_references = settings.motion_contexts = settings.weight_contexts = false;
  const Encoded encoded = encode(clips, base, settings);
  EXPECT_EQ(encoded.stream[4], format::kAdaptiveVersion);
  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, decoded).ok());
  EXPECT_EQ(decoded[0].positions, encoded.reconstruction[0].positions);
}

// The head of a version-3 stream for 3 vertices, one clip of `frames` frames, up to its frame references (what comes
// after them is missing: a decoder must refuse the references before it reads on).
std::vector<uint8_t> head_with_references(uint32_t frames, uint32_t window, const std::vector<uint32_t>& references,
                                          uint8_t version = format::kReferenceVersion,
                                          uint8_t flags = format::kFlagTemporalResiduals |
                                                          format::kFlagFrameReferences) {
  std::vector<uint8_t> out = {'S', 'G', 'M', 'A', version, flags, 0, 0, 0, 0};
  {
    RangeEncoder encoder(out);
    UnsignedModel count, reference;
    count.encode(encoder, 3);
    count.encode(encoder, 1);
    count.encode(encoder, frames);
    count.encode(encoder, window);
    for (uint32_t d : references) reference.encode(encoder, d);
    encoder.finish();
  }
  const uint32_t length = uint32_t(out.size() - format::kHeaderBytes);
  for (int i = 0; i < 4; ++i) out[6 + size_t(i)] = uint8_t(length >> (8 * i));
  return out;
}

std::string refusal(const std::vector<uint8_t>& stream) {
  const std::vector<float> base = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  StreamContent content;
  const Status status = read_stream(stream.data(), stream.size(), base, content);
  EXPECT_EQ(status.code(), StatusCode::bad_data);
  return status.message();
}

// The head of a version-3 stream with WEIGHT_CONTEXTS for 3 vertices (labels 0, 0, 1 of K = 2) and one frame of zero
// motion, up to its residual steps, coded symbol by symbol as spec/bitstream.md (5.1-5.7) says: each vertex's extras as
// (place, cluster if the place is the escape, value).
struct Extra {
  uint32_t place, cluster;
  int32_t value;
};
std::vector<uint8_t> head_with_weights(const std::vector<std::vector<Extra>>& extras) {
  std::vector<uint8_t> out = {'S', 'G', 'M', 'A', format::kReferenceVersion, format::kFlagWeightContexts, 0, 0, 0, 0};
  {
    RangeEncoder encoder(out);
    UnsignedModel count;
    for (uint32_t value : {3u, 1u, 1u, 2u}) count.encode(encoder, value);  // V, C, the frames, K
    BitTreeModel label(1);
    for (uint32_t value : {0u, 0u, 1u}) label.encode(encoder, value);
    for (int i = 0; i < 2; ++i) encoder.encode_direct_bits(0x3c23d70a, 32);  // the motion steps: 0.01f
    std::array<SignedModel, 12> motion;
    for (int k = 0; k < 2; ++k)
      for (SignedModel& slot : motion) slot.encode(encoder, 0);
    count.encode(encoder, 8);  // weight_bits
    std::array<BitTreeModel, 4> extra_count{BitTreeModel(2), BitTreeModel(2), BitTreeModel(2), BitTreeModel(2)};
    BitTreeModel place(3), cluster(1);
    SignedModel weight;
    uint32_t previous = 0;
    for (const std::vector<Extra>& vertex : extras) {
      extra_count[previous].encode(encoder, uint32_t(vertex.size()));
      previous = uint32_t(vertex.size());
      for (const Extra& extra : vertex) {
        place.encode(encoder, extra.place);
        if (extra.place == format::kRecentWeightClusters) cluster.encode(encoder, extra.cluster);
        weight.encode(encoder, extra.value);
      }
    }
    for (int axis = 0; axis < 3; ++axis) encoder.encode_direct_bits(0x3c23d70a, 32);  // the residual steps
    encoder.finish();
  }
  const uint32_t length = uint32_t(out.size() - format::kHeaderBytes);
  for (int i = 0; i < 4; ++i) out[6 + size_t(i)] = uint8_t(length >> (8 * i));
  return out;
}

// Places name the clusters last blended into vertices of the same own cluster, most recent first: vertex 1 (label 0)
// finds vertex 0's extra cluster 1 at place 0, and after vertex 1's escape to cluster 0 (which the decoder accepts
// although a vertex's own cluster gains nothing from it) cluster 1 is at place 1. Vertex 2 (label 1) has a list of
// its own, empty: a place in it is refused.
TEST(FrameReferences, WeightPlacesNameRecentClustersOfTheSameLabel) {
  const std::vector<float> base = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t escape = format::kRecentWeightClusters;
  const std::vector<uint8_t> stream =
      head_with_weights({{{escape, 1, 64}}, {{0, 0, 32}, {escape, 0, -8}, {1, 0, 5}}, {}});
  StreamContent content;
  StreamReader reader(stream.data(), stream.size());
  ASSERT_TRUE(reader.read_head(base, content).ok());
  EXPECT_EQ(content.weight_offset, (std::vector<uint32_t>{0, 1, 4, 4}));
  EXPECT_EQ(content.weight_cluster, (std::vector<uint32_t>{1, 1, 0, 1}));
  EXPECT_EQ(content.weight_value, (std::vector<int32_t>{64, 32, -8, 5}));
  EXPECT_NE(refusal(head_with_weights({{}, {}, {{0, 0, 64}}})).find("weight cluster out of range"), std::string::npos);
  EXPECT_NE(refusal(head_with_weights({{{escape, 1, 64}}, {}, {{0, 0, 64}}})).find("weight cluster out of range"),
            std::string::npos);
}

// References a stream may not hold are refused as bad data before anything is read or sized by them: a window of
// 0 or above 255, a reference beyond the frame's index in its clip or beyond the window; references without temporal
// residuals, and the flag in version 2.
TEST(FrameReferences, ReferencesAStreamMayNotHoldAreRefused) {
  EXPECT_NE(refusal(head_with_references(4, 0, {})).find("bad reference window"), std::string::npos);
  EXPECT_NE(refusal(head_with_references(4, 256, {})).find("bad reference window"), std::string::npos);
  EXPECT_NE(refusal(head_with_references(4, 2, {0, 1, 3})).find("reference is out of range"), std::string::npos);
  EXPECT_NE(refusal(head_with_references(4, 2, {0, 1, 1, 3})).find("reference is out of range"), std::string::npos);
  EXPECT_NE(refusal(head_with_references(4, 3, {1})).find("reference is out of range"), std::string::npos);
  EXPECT_NE(refusal(head_with_references(4, 2, {0, 1}, format::kReferenceVersion, format::kFlagFrameReferences))
                .find("frame references without temporal residuals"),
            std::string::npos);
  EXPECT_NE(refusal(head_with_references(4, 2, {0, 1}, format::kTableVersion)).find("unknown flags"),
            std::string::npos);
  // A window above 1 times V may not exceed 2^21 (a decoder's memory for the window's residuals).
  {
    const std::vector<float> large((size_t(1) << 20) * 3 + 3, 0.0f);  // 2^20 + 1 vertices
    std::vector<uint8_t> out = {'S', 'G', 'M', 'A', format::kReferenceVersion,
                                format::kFlagTemporalResiduals | format::kFlagFrameReferences, 0, 0, 0, 0};
    {
      RangeEncoder encoder(out);
      UnsignedModel count;
      for (uint32_t value : {uint32_t(large.size() / 3), 1u, 4u, 2u}) count.encode(encoder, value);
      encoder.finish();
    }
    const uint32_t length = uint32_t(out.size() - format::kHeaderBytes);
    for (int i = 0; i < 4; ++i) out[6 + size_t(i)] = uint8_t(length >> (8 * i));
    StreamContent content;
    const Status status = read_stream(out.data(), out.size(), large, content);
    EXPECT_NE(status.message().find("bad reference window"), std::string::npos) << status.message();
  }
  // A stream of a few bytes claiming a clip of 89 million frames is refused when its data runs out, not after
  // reading a reference (a zero, which is valid) for every frame it claims.
  {
    const std::vector<uint8_t> stream = head_with_references((1u << 28) / 3, 2, {0});
    StreamContent content;
    const Status status = read_stream(stream.data(), stream.size(), {0, 0, 0, 1, 0, 0, 0, 1, 0}, content);
    EXPECT_EQ(status.code(), StatusCode::bad_data);
    EXPECT_LT(content.references.size(), 1000u);
  }
  // The same head with valid references gets past them (and then runs out of data).
  const std::string later = refusal(head_with_references(4, 2, {0, 1, 2, 1}));
  EXPECT_EQ(later.find("reference"), std::string::npos) << later;
}

}  // namespace
}  // namespace segmorph
