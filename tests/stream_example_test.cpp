// The worked example of spec/bitstream.md (section 9): a hand-built stream content, the exact bytes write_stream
// makes of it, the content read_stream gets back, and the frames it decodes to.
//
// When the stream format changes (a model, a field), only kExampleHex changes: the failure message prints the
// new bytes; paste them into spec_examples.h and spec/bitstream.md (section 9.2, and the walk-through where it quotes
// bytes or positions). The content and the frames do not depend on how symbols are entropy coded.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "common/stream.h"
#include "common/stream_format.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "decode/transform_residuals.h"
#include "encode/stream_writer.h"
#include "spec_examples.h"
#include "test_files.h"

namespace segmorph {
namespace {

using testing::hex;
using namespace spec_examples;

StreamContent example_content() {
  StreamContent c;
  c.flags = format::kFlagTemporalResiduals | format::kFlagSpatialResiduals;
  c.vertex_count = 8;
  c.welded_index = {0, 1, 2, 3, 4, 5, 4, 6};
  c.welded_count = 7;
  c.clip_frames = {2, 1};
  c.cluster_count = 2;
  c.labels = {0, 0, 1, 0, 0, 1, 1};
  c.linear_step = 0.03125f;
  c.translation_step = 0.015625f;
  c.motion = {
      0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0,   // frame 0, cluster 0
      0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0,   // frame 0, cluster 1
      0, 0, 0, 0, 0, 0, 0, 0, 0,  1, 0, 0,   // frame 1, cluster 0
      0, 0, 0, 0, 0, 0, 0, 0, -2, 0, 0, 16,  // frame 1, cluster 1
      3, 0, 0, 0, 0, 0, 0, 0, 0,  2, 0, 0,   // frame 2, cluster 0
      0, 1, 0, 0, 0, 0, 0, 0, -1, 0, 0, 8,   // frame 2, cluster 1
  };
  c.weight_bits = 8;
  c.weight_offset = {0, 0, 1, 2, 2, 3, 3, 3};
  c.weight_cluster = {1, 0, 1};
  c.weight_value = {64, -8, 32};
  c.residual_step[0] = 0.01f;
  c.residual_step[1] = 0.01f;
  c.residual_step[2] = 0.02f;
  // clang-format off
  c.residuals = {
      // welded vertex 0, 1, ..., 6; x, y, z each
      0, 0, 0,  0, 0, 0,   0, 0, 0,  0, -1, 0,  0, 0, 0,   0, 0, 0,   2, 0, 0,   // frame 0
      1, 0, 0,  0, -1, 0,  0, 0, 3,  0, 0, 0,   -2, 0, 1,  0, 0, 0,   0, 1, -1,  // frame 1
      0, 0, 0,  1, 1, 0,   0, 0, 0,  0, 2, 0,   0, 0, 0,   -1, 0, 0,  0, 0, 5,   // frame 2
  };
  // clang-format on
  return c;
}

std::vector<uint8_t> written(const StreamContent& content) {
  std::vector<uint8_t> bytes;
  write_stream(content, example_base(), bytes);
  return bytes;
}

std::vector<uint8_t> written() {
  return written(example_content());
}

// The frames of decoded clips, stream frame after stream frame: "frame vertex x y z", binary32 bit patterns.
std::string printed_frames(const std::vector<FrameSequence>& clips) {
  std::string printed;
  size_t frame = 0;
  for (const FrameSequence& clip : clips)
    for (size_t j = 0; j < clip.frame_count; ++j, ++frame)
      for (size_t v = 0; v < clip.vertex_count; ++v) {
        char line[64];
        uint32_t bits[3];
        std::memcpy(bits, clip.frame(j) + v * 3, 12);
        std::snprintf(line, sizeof(line), "%zu %zu %08x %08x %08x\n", frame, v, bits[0], bits[1], bits[2]);
        printed += line;
      }
  return printed;
}

TEST(StreamExample, BytesAreTheAppendixBytes) {
  EXPECT_EQ(hex(written()), kExampleHex) << "update kExampleHex and spec/bitstream.md section 9";
}

TEST(StreamExample, ReadsBackTheContent) {
  const std::vector<uint8_t> bytes = written();
  StreamContent read;
  const Status status = read_stream(bytes.data(), bytes.size(), example_base(), read);
  ASSERT_TRUE(status.ok()) << status.message();
  const StreamContent want = example_content();
  EXPECT_EQ(read.flags, want.flags);
  EXPECT_EQ(read.vertex_count, want.vertex_count);
  EXPECT_EQ(read.welded_index, want.welded_index);
  EXPECT_EQ(read.welded_count, want.welded_count);
  EXPECT_EQ(read.clip_frames, want.clip_frames);
  EXPECT_EQ(read.cluster_count, want.cluster_count);
  EXPECT_EQ(read.labels, want.labels);
  EXPECT_EQ(read.linear_step, want.linear_step);
  EXPECT_EQ(read.translation_step, want.translation_step);
  EXPECT_EQ(read.motion, want.motion);
  EXPECT_EQ(read.weight_bits, want.weight_bits);
  EXPECT_EQ(read.weight_offset, want.weight_offset);
  EXPECT_EQ(read.weight_cluster, want.weight_cluster);
  EXPECT_EQ(read.weight_value, want.weight_value);
  for (int axis = 0; axis < 3; ++axis) EXPECT_EQ(read.residual_step[axis], want.residual_step[axis]);
  EXPECT_EQ(read.residuals, want.residuals);
}

TEST(StreamExample, DecodesToTheAppendixFrames) {
  const std::vector<uint8_t> bytes = written();
  std::vector<FrameSequence> clips;
  const Status status = decode_animation(bytes.data(), bytes.size(), example_base(), example_triangles(), clips);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(clips.size(), 2u);
  ASSERT_EQ(clips[0].frame_count, 2u);
  ASSERT_EQ(clips[1].frame_count, 1u);
  for (size_t frame = 0; frame < 3; ++frame) {
    const FrameSequence& clip = clips[frame < 2 ? 0 : 1];
    const float* positions = clip.frame(frame < 2 ? frame : 0);
    for (size_t v = 0; v < 8; ++v)
      for (size_t axis = 0; axis < 3; ++axis) {
        uint32_t bits;
        std::memcpy(&bits, &positions[v * 3 + axis], 4);
        EXPECT_EQ(bits, kExampleFrames[frame][v][axis]) << "frame " << frame << ", vertex " << v << ", axis " << axis;
      }
  }
}

StreamContent reference_example_content() {
  StreamContent c = example_content();
  c.flags |= format::kFlagFrameReferences;
  c.clip_frames = {4};
  c.reference_window = 2;
  c.references = {0, 1, 2, 2};
  c.motion = {
      0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0,   // frame 0, cluster 0
      0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0,   // frame 0, cluster 1
      0, 0, 0, 0, 0, 0, 0, 0, 0,  1, 0, 0,   // frame 1, cluster 0
      0, 0, 0, 0, 0, 0, 0, 0, -2, 0, 0, 16,  // frame 1, cluster 1
      0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 0,   // frame 2, cluster 0: frame 0's
      0, 0, 0, 0, 0, 0, 0, 0, 0,  0, 0, 1,   // frame 2, cluster 1: frame 0's but slot 11
      0, 0, 0, 0, 0, 0, 0, 0, 0,  1, 0, 0,   // frame 3, cluster 0: frame 1's
      0, 0, 0, 0, 0, 0, 0, 0, -2, 0, 0, 16,  // frame 3, cluster 1: frame 1's
  };
  // clang-format off
  c.residuals = {
      // welded vertex 0, 1, ..., 6; x, y, z each
      0, 0, 0,  0, 0, 0,   0, 0, 0,  0, -1, 0,  0, 0, 0,   0, 0, 0,   2, 0, 0,   // frame 0
      1, 0, 0,  0, -1, 0,  0, 0, 3,  0, 0, 0,   -2, 0, 1,  0, 0, 0,   0, 1, -1,  // frame 1
      0, 0, 0,  0, 0, 0,   0, 0, 0,  0, 0, 0,   0, 0, 0,   0, 0, 0,   0, 0, 0,   // frame 2
      0, 0, 0,  0, 0, 0,   0, 0, 0,  0, 0, 0,   1, 0, 0,   0, 0, 0,   0, 0, 0,   // frame 3
  };
  // clang-format on
  return c;
}

std::vector<uint8_t> reference_written() {
  return written(reference_example_content());
}

TEST(StreamExample, VersionThreeBytesAreTheAppendixBytes) {
  EXPECT_EQ(hex(reference_written()), kReferenceExampleHex) << "update kReferenceExampleHex and spec/bitstream.md 9.7";
}

TEST(StreamExample, VersionThreeReadsBackTheContent) {
  const std::vector<uint8_t> bytes = reference_written();
  ASSERT_GT(bytes.size(), 5u);
  EXPECT_EQ(bytes[4], format::kReferenceVersion);
  StreamContent read;
  const Status status = read_stream(bytes.data(), bytes.size(), example_base(), read);
  ASSERT_TRUE(status.ok()) << status.message();
  const StreamContent want = reference_example_content();
  EXPECT_EQ(read.flags, want.flags);
  EXPECT_EQ(read.clip_frames, want.clip_frames);
  EXPECT_EQ(read.reference_window, want.reference_window);
  EXPECT_EQ(read.references, want.references);
  EXPECT_EQ(read.motion, want.motion);
  EXPECT_EQ(read.residuals, want.residuals);
}

// Frame 2 repeats frame 0 but for cluster 1's z translation, one step up: its residuals are all zero, predicted from
// frame 0's. Frame 3 repeats frame 1 but for welded vertex 4's x, one step right.
TEST(StreamExample, VersionThreeDecodesToTheAppendixFrames) {
  const std::vector<uint8_t> bytes = reference_written();
  std::vector<FrameSequence> clips;
  const Status status = decode_animation(bytes.data(), bytes.size(), example_base(), example_triangles(), clips);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(clips.size(), 1u);
  ASSERT_EQ(clips[0].frame_count, 4u);
  EXPECT_EQ(printed_frames(clips), kReferenceExampleFrames)
      << "update kReferenceExampleFrames and spec/bitstream.md 9.7";
}

// The coefficients the symbols give (spec 8.7.1), per welded vertex: axis by axis, vector by vector.
// clang-format off
const std::vector<int32_t> kTransformExampleCoefficients = {
    2, 0, 0,             // w0 (cluster 0, m = 1): x, y, z
    2, 0, 1,             // w1
    4, 0, 0, 1, -1, 0,   // w2 (cluster 1, m = 2): x0 x1, y0 y1, z0 z1
    3, 0, 1,             // w3
    -1, 1, 1,            // w4
    4, 0, 0, 1, 0, 0,    // w5
    5, 0, 0, 0, 0, 2,    // w6
};
// clang-format on

StreamContent transform_example_content() {
  StreamContent c = example_content();
  c.flags = 0;
  c.residual_step[0] = c.residual_step[1] = c.residual_step[2] = 0;
  c.residuals.clear();
  c.transform = true;
  c.stream_basis.step = {0.5f};
  c.stream_basis.entries = {0, 1, 2};
  c.basis_source = {format::kBasisStream, format::kBasisOwn};
  c.basis_size = {1, 2};
  c.coefficient_step = {0.01f, 0.02f};
  c.own_basis.resize(2);
  c.own_basis[1].step = {0.25f, 0.125f};
  c.own_basis[1].entries = {0, 4, -2, 1, 0, 1};
  // clang-format off
  c.coefficient_symbols = {
      2, 0, 1, -3,  0, 0, 0, 1,  0, 1, 1, 0,   // cluster 0, vector 0: x, y, z of w0, w1, w3, w4
      4, 0, 1,  0, 0, 0,  -1, 1, 1,            // cluster 1, vector 0: x, y, z of w2, w5, w6
      0, 0, 0,  1, 0, -1,  0, 0, 2,            // cluster 1, vector 1
  };
  // clang-format on
  return c;
}

std::vector<uint8_t> transform_written() {
  return written(transform_example_content());
}

TEST(StreamExample, VersionFourBytesAreTheAppendixBytes) {
  EXPECT_EQ(hex(transform_written()), kTransformExampleHex) << "update kTransformExampleHex and spec/bitstream.md 9.8";
}

TEST(StreamExample, VersionFourReadsBackTheContent) {
  const std::vector<uint8_t> bytes = transform_written();
  ASSERT_GT(bytes.size(), 5u);
  EXPECT_EQ(bytes[4], format::kTransformVersion);
  StreamContent read;
  const Status status = read_stream(bytes.data(), bytes.size(), example_base(), read);
  ASSERT_TRUE(status.ok()) << status.message();
  const StreamContent want = transform_example_content();
  EXPECT_TRUE(read.transform);
  EXPECT_EQ(read.flags, want.flags);
  EXPECT_EQ(read.motion, want.motion);
  EXPECT_EQ(read.weight_value, want.weight_value);
  EXPECT_EQ(read.stream_basis.step, want.stream_basis.step);
  EXPECT_EQ(read.stream_basis.entries, want.stream_basis.entries);
  EXPECT_EQ(read.basis_source, want.basis_source);
  EXPECT_EQ(read.basis_size, want.basis_size);
  EXPECT_EQ(read.coefficient_step, want.coefficient_step);
  ASSERT_EQ(read.own_basis.size(), 2u);
  EXPECT_EQ(read.own_basis[1].step, want.own_basis[1].step);
  EXPECT_EQ(read.own_basis[1].entries, want.own_basis[1].entries);
  EXPECT_EQ(read.coefficient_symbols, want.coefficient_symbols);

  TransformCoefficients coefficients;
  ASSERT_TRUE(transform_coefficients(read, residual_traversal(read, example_triangles()), coefficients).ok());
  EXPECT_EQ(coefficients.values, kTransformExampleCoefficients);
}

TEST(StreamExample, VersionFourDecodesToTheAppendixFrames) {
  const std::vector<uint8_t> bytes = transform_written();
  std::vector<FrameSequence> clips;
  const Status status = decode_animation(bytes.data(), bytes.size(), example_base(), example_triangles(), clips);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(clips.size(), 2u);
  EXPECT_EQ(printed_frames(clips), kTransformExampleFrames)
      << "update kTransformExampleFrames and spec/bitstream.md 9.8";
}

}  // namespace
}  // namespace segmorph
