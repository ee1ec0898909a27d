// The worked example of spec/bitstream.md (section 9): a hand-built stream content, the exact bytes write_stream
// makes of it, the content read_stream gets back, and the frames it decodes to.
//
// When the stream format changes (a model, a field), only kExampleHex changes: the failure message prints the
// new bytes; paste them here and into spec/bitstream.md (section 9.2, and the walk-through where it quotes
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
#include "test_files.h"

namespace segmorph {
namespace {

using testing::hex;

constexpr char kExampleHex[] =
    "53474d4101063e000000100445d5db1a3c8ed7bc141eada18000000037ee2e161dd2d2d31f1aaf4c3e8b4fa4457ea8dd"
    "3449f56ffaa1356ffcb1f97f6a474ecd6c2ad438a41450d2";

// Base positions (V = 8): a strip of two unit squares, with vertex 6 a seam copy of vertex 4 (welded) and
// vertex 7 a copy of vertex 2 that moves on its own (not welded).
std::vector<float> example_base() {
  return {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 1, 1, 0, 2, 0, 0};
}

std::vector<uint32_t> example_triangles() {
  return {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 6, 2, 7, 5};
}

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

// The decoded frames (clip 0: frames 0 and 1; clip 1: frame 2), V × 3 binary32 bit patterns each.
constexpr uint32_t kExampleFrames[3][8][3] = {
    {{0x00000000, 0x00000000, 0x00000000},
     {0x3f800000, 0x00000000, 0x00000000},
     {0x40000000, 0x00000000, 0x00000000},
     {0x00000000, 0x3f7d70a4, 0x00000000},
     {0x3f800000, 0x3f7f258c, 0x00000000},
     {0x40000000, 0x3f7fb72f, 0x00000000},
     {0x3f800000, 0x3f7f258c, 0x00000000},
     {0x400147ae, 0xba11a2b4, 0x00000000}},
    {{0x3cd1eb85, 0x00000000, 0x00000000},
     {0x3f82c7ae, 0xbc23d70a, 0x3d800000},
     {0x40009bd7, 0xbc23d70a, 0x3ea2b852},
     {0x3cd1eb85, 0x3f7d70a4, 0x00000000},
     {0x3f807852, 0x3f7e4b18, 0x3d51eb85},
     {0x4000369d, 0x3f7db975, 0x3e8da741},
     {0x3f807852, 0x3f7e4b18, 0x3d51eb85},
     {0x4001b4e8, 0x3a11a2b4, 0x3e8bf259}},
    {{0xbc800000, 0x00000000, 0x00000000},
     {0x3f887259, 0x3c23d70a, 0x3d000000},
     {0x3fff37ae, 0x3c23d70a, 0x3e040000},
     {0xbc800000, 0x3f828f5c, 0x00000000},
     {0x3f89828f, 0x3f8147ae, 0x3c800000},
     {0x400130ed, 0x3f8147ae, 0x3e000000},
     {0x3f89828f, 0x3f8147ae, 0x3c800000},
     {0x3fff2a19, 0x3c23d70a, 0x3e666666}},
};

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

// The worked example of version 3 (spec/bitstream.md, section 9.7): the same mesh, clusters, weights and steps, one
// clip of 4 frames whose frames 2 and 3 name frames 0 and 1 as their references (window 2).
constexpr char kReferenceExampleHex[] =
    "53474d4103163e00000010023ae6a02f4034f06e3dd826442509eaa00000000b8529a2402d4604caa68424224eb9e57e"
    "9b20c6b3d9b825c1d8b836be2eb382b857f31cf5e487e30a";

// Its decoded frames: "frame vertex x y z", binary32 bit patterns.
constexpr char kReferenceExampleFrames[] =
    "0 0 00000000 00000000 00000000\n"
    "0 1 3f800000 00000000 00000000\n"
    "0 2 40000000 00000000 00000000\n"
    "0 3 00000000 3f7d70a4 00000000\n"
    "0 4 3f800000 3f7f258c 00000000\n"
    "0 5 40000000 3f7fb72f 00000000\n"
    "0 6 3f800000 3f7f258c 00000000\n"
    "0 7 400147ae ba11a2b4 00000000\n"
    "1 0 3cd1eb85 00000000 00000000\n"
    "1 1 3f82c7ae bc23d70a 3d800000\n"
    "1 2 40009bd7 bc23d70a 3ea2b852\n"
    "1 3 3cd1eb85 3f7d70a4 00000000\n"
    "1 4 3f807852 3f7e4b18 3d51eb85\n"
    "1 5 4000369d 3f7db975 3e8da741\n"
    "1 6 3f807852 3f7e4b18 3d51eb85\n"
    "1 7 4001b4e8 3a11a2b4 3e8bf259\n"
    "2 0 00000000 00000000 00000000\n"
    "2 1 3f800000 00000000 3b800000\n"
    "2 2 40000000 00000000 3c840000\n"
    "2 3 00000000 3f7d70a4 00000000\n"
    "2 4 3f800000 3f7f258c 3b000000\n"
    "2 5 40000000 3f7fb72f 3c800000\n"
    "2 6 3f800000 3f7f258c 3b000000\n"
    "2 7 400147ae ba11a2b4 3c800000\n"
    "3 0 3cd1eb85 00000000 00000000\n"
    "3 1 3f82c7ae bc23d70a 3d800000\n"
    "3 2 40009bd7 bc23d70a 3ea2b852\n"
    "3 3 3cd1eb85 3f7d70a4 00000000\n"
    "3 4 3f81c000 3f7e4b18 3d51eb85\n"
    "3 5 40006d3a 3f7db975 3e8da741\n"
    "3 6 3f81c000 3f7e4b18 3d51eb85\n"
    "3 7 4001d037 3a11a2b4 3e8bf259\n";

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

// The worked example of version 4 (spec/bitstream.md, section 9.8): the head of section 9's stream (clips, welding,
// clusters, motion, weights), then the residuals as bases and coefficients: cluster 0 takes the stream's one vector,
// cluster 1 two of its own.
constexpr char kTransformExampleHex[] =
    "53474d410400530000001004"
    "45d5db1a3c8ed7bc141eada18000000037ee2e161dd2d2d31f1aaf4c3e8b4fa4457ea8dc5c43eabfa71334d7f91f6421984c2dcc3d9802"
    "dc4948c53212f801af198b1c0f3d1a23669fcf86956f437332a6";

// Its decoded frames: "frame vertex x y z", binary32 bit patterns.
constexpr char kTransformExampleFrames[] =
    "0 0 00000000 00000000 00000000\n"
    "0 1 3f800000 00000000 00000000\n"
    "0 2 40000000 3b23d70a 00000000\n"
    "0 3 00000000 3f800000 00000000\n"
    "0 4 3f800000 3f800000 00000000\n"
    "0 5 40000000 3f8051ec 00000000\n"
    "0 6 3f800000 3f800000 00000000\n"
    "0 7 40000000 00000000 3ba3d70a\n"
    "1 0 3cd1eb85 00000000 00000000\n"
    "1 1 3f82c7ae 00000000 3d8a3d71\n"
    "1 2 400516b8 00000000 3e73851f\n"
    "1 3 3cfae148 3f800000 3ba3d70a\n"
    "1 4 3f811c29 3f80a3d7 3d147ae1\n"
    "1 5 40051eb8 3f800000 3e800000\n"
    "1 6 3f811c29 3f80a3d7 3d147ae1\n"
    "1 7 40066666 00000000 3e800000\n"
    "2 0 3b8f5c28 00000000 00000000\n"
    "2 1 3f89ba07 00000000 3d28f5c2\n"
    "2 2 3ff8d148 3b23d70a 3e0e3d71\n"
    "2 3 3c6b851e 3f800000 3c23d70a\n"
    "2 4 3f87cda7 3f8147ae 3cd1eb85\n"
    "2 5 3ffd8bf2 3f8051ec 3e000000\n"
    "2 6 3f87cda7 3f8147ae 3cd1eb85\n"
    "2 7 3ff84444 00000000 3e051eb8\n";

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
