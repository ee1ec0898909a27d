// Stream version 4: the residuals as temporal bases and coefficients (codec/encode/transform_coding.h, the encoder's side;
// codec/decode/transform_residuals.h, the decoder's; spec/bitstream.md 5.9 and 8.7.1).
#include "decode/transform_residuals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

#include "common/stream.h"
#include "common/stream_format.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "decode/transform_blocks.h"
#include "decode/transform_walk.h"
#include "encode/encoder.h"
#include "encode/stream_writer.h"
#include "encode/transform_symbols.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::bending_clip;
using testing::encode;
using testing::Encoded;
using testing::kg;
using testing::quantized_base;

// Two clips of the bending sphere (642 vertices), the second with another phase: smooth, non-rigid motion the
// affine clusters leave residuals on.
std::vector<FrameSequence> two_clips() {
  return {bending_clip(30, 1.0, 0), bending_clip(21, 0.7, 1.5)};
}

CodecSettings residual_loop(CodecSettings settings) {
  settings.transform_residuals = false;
  return settings;
}

CodecSettings error(double target) {
  CodecSettings settings;
  settings.target = target;
  return settings;
}

// At each error target: version 4 with no residual-loop flag, fewer bytes than the residual loop's stream at no more
// KG error, the decoder's frames the encoder's bit for bit, and the content read back written to the same bytes.
TEST(TransformResiduals, FewerBytesAtNoMoreErrorAndTheDecodersFramesAreTheEncoders) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  for (double target : {0.15, 0.5}) {
    SCOPED_TRACE(target);
    const Encoded transform = encode(clips, base, error(target)),
                  loop = encode(clips, base, residual_loop(error(target)));
    ASSERT_GT(transform.stream.size(), 5u);
    EXPECT_EQ(transform.stream[4], format::kTransformVersion);
    EXPECT_EQ(transform.stream[5] & format::kResidualLoopFlags, 0);
    EXPECT_LE(loop.stream[4], format::kReferenceVersion);
    EXPECT_LT(transform.stream.size(), loop.stream.size());
    const double transform_kg = kg(clips, transform.reconstruction), loop_kg = kg(clips, loop.reconstruction);
    EXPECT_LE(transform_kg, loop_kg * (1 + 1e-12));
    EXPECT_NEAR(transform.report.kg_percent, transform_kg, 1e-9);
    EXPECT_EQ(transform.report.bytes_total, transform.stream.size());
    std::vector<FrameSequence> decoded;
    ASSERT_TRUE(
        decode_animation(transform.stream.data(), transform.stream.size(), base, clips[0].triangles, decoded).ok());
    ASSERT_EQ(decoded.size(), clips.size());
    for (size_t c = 0; c < clips.size(); ++c) EXPECT_EQ(decoded[c].positions, transform.reconstruction[c].positions);
    // On threads (the blocks of each clip side by side): the same floats.
    for (size_t threads : {2, 3, 0}) {
      std::vector<FrameSequence> threaded;
      ASSERT_TRUE(decode_animation(transform.stream.data(), transform.stream.size(), base, clips[0].triangles,
                                   threaded, threads)
                      .ok());
      ASSERT_EQ(threaded.size(), clips.size());
      for (size_t c = 0; c < clips.size(); ++c) {
        EXPECT_EQ(threaded[c].frame_count, clips[c].frame_count) << threads;
        EXPECT_EQ(threaded[c].positions, transform.reconstruction[c].positions) << threads;
      }
    }
    StreamContent content;
    ASSERT_TRUE(read_stream(transform.stream.data(), transform.stream.size(), base, content).ok());
    EXPECT_TRUE(content.transform);
    EXPECT_TRUE(content.residuals.empty());
    std::vector<uint8_t> again;
    write_stream(content, base, again);
    EXPECT_EQ(again, transform.stream);
  }
}

// Every way of decoding gives the same floats: any number of frames at a time up to the block, and after seeking back
// and forth.
TEST(TransformResiduals, AnyFramesAtATimeAndAfterASeekAreTheEncodersFrames) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, error(0.15));
  ASSERT_EQ(encoded.stream[4], format::kTransformVersion);
  for (size_t step : {size_t(1), size_t(2), size_t(3), TransformBlocks::kMaxFrames}) {
    SCOPED_TRACE(step);
    FrameDecoder decoder;
    ASSERT_TRUE(decoder.open(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles).ok());
    EXPECT_EQ(decoder.block_frames(), TransformBlocks::kMaxFrames);
    ASSERT_TRUE(decoder.seek(1).ok());
    for (int pass = 0; pass < 2; ++pass) {
      for (size_t c = pass == 0 ? 1 : 0; c < clips.size(); ++c) {
        std::vector<float> frames;
        while (decoder.next_clip() == c)
          ASSERT_TRUE(decoder.decode_append(std::min(step, decoder.frames_left_in_clip()), frames).ok());
        EXPECT_EQ(frames, encoded.reconstruction[c].positions) << "clip " << c << ", pass " << pass;
      }
      ASSERT_TRUE(decoder.seek(0).ok());
    }
  }
}

// The frame loop's blocks (transform_blocks.h), with every instruction set the processor has, against the reference
// one frame at a time: the prediction of FramePredictor (spec 8.5) plus TransformResiduals::frame, as floats, bit for
// bit, for every first frame and block length, on streams with bases of the stream's, the clusters' own and none.
TEST(TransformResiduals, BlocksOfFramesAreTheReferenceFrames) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  size_t sources[3] = {0, 0, 0};
  for (double target : {0.05, 0.15, 0.5, 2.0}) {
    SCOPED_TRACE(target);
    const Encoded encoded = encode(clips, base, error(target));
    ASSERT_EQ(encoded.stream[4], format::kTransformVersion);
    StreamContent content;
    ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
    for (uint8_t source : content.basis_source) ++sources[std::min<size_t>(source, 2)];
    const std::vector<float> welded = welded_base(base, content);
    const AffineMotion motion = dequantized_motion(content, welded);
    const ClusterWeights weights = dequantized_weights(content);
    TransformCoefficients coefficients;
    ASSERT_TRUE(transform_coefficients(content, residual_traversal(content, clips[0].triangles), coefficients).ok());
    const TransformResiduals residuals(content, std::move(coefficients));
    const size_t frames = content.frame_count(), row = size_t(content.welded_count) * 3;
    std::vector<float> reference(frames * row);
    std::vector<double> predicted(row), r(row);
    for (size_t f = 0; f < frames; ++f) {
      predict_frame(welded.data(), motion, weights, f, predicted.data());
      residuals.frame(f, r.data());
      for (size_t i = 0; i < row; ++i) reference[f * row + i] = float(predicted[i] + r[i]);
    }
    using Instructions = TransformBlocks::Instructions;
    for (Instructions instructions : {Instructions::baseline, Instructions::avx, Instructions::avx512}) {
      const TransformBlocks blocks(content, residuals, welded.data(), motion.centroid, weights, instructions);
      if (blocks.instructions() != instructions) continue;  // the processor has not got them
      SCOPED_TRACE(int(instructions));
      std::vector<float> out(TransformBlocks::kMaxFrames * row);
      for (size_t count = 1; count <= TransformBlocks::kMaxFrames; ++count)
        for (size_t first = 0; first + count <= frames; ++first) {
          std::fill(out.begin(), out.end(), -1.0f);
          blocks.reconstruct(first, count, out.data());
          ASSERT_EQ(std::memcmp(out.data(), &reference[first * row], count * row * sizeof(float)), 0)
              << "frames " << first << " + " << count;
          ASSERT_TRUE(std::all_of(out.begin() + ptrdiff_t(count * row), out.end(), [](float x) { return x == -1.0f; }))
              << "written past " << count << " frames";
        }
    }
  }
  EXPECT_GT(sources[format::kBasisStream], 0u);
  EXPECT_GT(sources[format::kBasisOwn], 0u);
}

// With the bases and options estimated from a sample of each cluster's rows (as on large meshes), the transform is
// still chosen, meets the residual loop's error, and its stream is within a few per cent of the one from every row.
TEST(TransformResiduals, ASampleOfTheRowsChoosesAsWell) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  for (double target : {0.15, 0.5}) {
    SCOPED_TRACE(target);
    CodecSettings sampled = error(target);
    sampled.transform_sample_rows = 300;  // of 1926 rows, about 110 to 520 a cluster
    const Encoded all = encode(clips, base, error(target)), some = encode(clips, base, sampled),
                  loop = encode(clips, base, residual_loop(error(target)));
    ASSERT_EQ(some.stream[4], format::kTransformVersion);
    EXPECT_LE(kg(clips, some.reconstruction), kg(clips, loop.reconstruction) * (1 + 1e-12));
    EXPECT_LT(double(some.stream.size()), double(all.stream.size()) * 1.05);
    std::vector<FrameSequence> decoded;
    ASSERT_TRUE(decode_animation(some.stream.data(), some.stream.size(), base, clips[0].triangles, decoded).ok());
    for (size_t c = 0; c < clips.size(); ++c) EXPECT_EQ(decoded[c].positions, some.reconstruction[c].positions);
  }
  CodecSettings none = error(0.15);
  none.transform_sample_rows = 2;  // less than a vertex
  std::vector<uint8_t> stream;
  EXPECT_EQ(encode_animation(clips, base, none, stream).code(), StatusCode::invalid_argument);
}

// The walk's mean by a multiplication is the mean by division, for every count a vertex can have neighbours and sums
// around the multiplication's limit (dividends of 32 bits) and far beyond it.
TEST(TransformResiduals, MeansByMultiplicationAreMeansByDivision) {
  using transform_code::reciprocal;
  using transform_code::rounded_mean;
  std::mt19937_64 random(35);
  for (int64_t count = 1; count <= 64; ++count) {
    const uint64_t magic = reciprocal(count);
    std::vector<int64_t> sums = {0, 1, -1, count, -count, count / 2, -(count / 2), (count + 1) / 2, -((count + 1) / 2)};
    for (int64_t edge : {(int64_t(1) << 31) - count / 2, int64_t(1) << 31, int64_t(1) << 32, int64_t(1) << 36})
      for (int64_t d = -3; d <= 3; ++d) sums.push_back(edge + d), sums.push_back(-(edge + d));
    for (int i = 0; i < 2000; ++i) {
      sums.push_back(int64_t(random() % (uint64_t(1) << 31)) - (int64_t(1) << 30));
      sums.push_back(int64_t(random() % (uint64_t(count) << 31)) - (count << 30));  // count coefficients of ±2^30
    }
    for (int64_t sum : sums) ASSERT_EQ(rounded_mean(sum, count, magic), rounded_mean(sum, count)) << sum << " / " << count;
  }
}

// The coefficients' symbols and the coefficients are each other's inverse through the traversal's prediction.
TEST(TransformResiduals, SymbolsAndCoefficientsAreInverse) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, error(0.15));
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  const ResidualTraversal traversal = residual_traversal(content, clips[0].triangles);
  TransformCoefficients coefficients;
  ASSERT_TRUE(transform_coefficients(content, traversal, coefficients).ok());
  ASSERT_FALSE(coefficients.values.empty());
  EXPECT_EQ(transform_symbols(content, traversal, coefficients), content.coefficient_symbols);
  // Not a trivial pair: some coefficient is nonzero, and some symbol differs from its coefficient (a prediction).
  EXPECT_TRUE(std::any_of(coefficients.values.begin(), coefficients.values.end(), [](int32_t q) { return q != 0; }));
  int64_t coefficient_sum = 0, symbol_sum = 0;
  for (int32_t q : coefficients.values) coefficient_sum += q < 0 ? -q : q;
  for (int32_t s : content.coefficient_symbols) symbol_sum += s < 0 ? -s : s;
  EXPECT_NE(coefficient_sum, symbol_sum);
}

// Without the setting (the converter's --max-stream-version 3), with the table code, with a bpvf target and lossless,
// the stream stays on the residual loop.
TEST(TransformResiduals, OnlyWithTheSettingAndAnErrorTarget) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  EXPECT_TRUE(CodecSettings().transform_residuals);
  CodecSettings table = error(0.5);
  table.table_residuals = true;
  CodecSettings bpvf;
  bpvf.mode = RateMode::bpvf;
  bpvf.target = 2;
  CodecSettings lossless;
  lossless.mode = RateMode::lossless;
  for (const CodecSettings& settings : {residual_loop(error(0.5)), table, bpvf, lossless})
    EXPECT_LE(encode(clips, base, settings).stream[4], format::kReferenceVersion);
}

// gpu_playable: a stream that is version 4 anyway is the same bytes; one that the default leaves on the residual loop
// (a few frames of the bending sphere, where the bases do not pay) becomes version 4 within the error target, and
// decodes to the encoder's frames; the setting is refused where no version 4 can be written.
TEST(TransformResiduals, GpuPlayableWritesVersionFourWithinTheTarget) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings playable = error(0.15);
  playable.gpu_playable = true;
  const Encoded anyway = encode(clips, base, error(0.15));
  ASSERT_EQ(anyway.stream[4], format::kTransformVersion);
  EXPECT_EQ(encode(clips, base, playable).stream, anyway.stream);

  const std::vector<FrameSequence> short_clip = {bending_clip(3, 0.3, 0)};
  const std::vector<float> short_base = quantized_base(short_clip[0]);
  for (double target : {0.15, 0.5}) {
    SCOPED_TRACE(target);
    playable.target = target;
    const Encoded loop = encode(short_clip, short_base, error(target)),
                  forced = encode(short_clip, short_base, playable);
    EXPECT_LE(loop.stream[4], format::kReferenceVersion);
    ASSERT_EQ(forced.stream[4], format::kTransformVersion);
    EXPECT_LE(kg(short_clip, forced.reconstruction), target);
    std::vector<FrameSequence> decoded;
    ASSERT_TRUE(decode_animation(forced.stream.data(), forced.stream.size(), short_base, short_clip[0].triangles,
                                 decoded).ok());
    EXPECT_EQ(decoded[0].positions, forced.reconstruction[0].positions);
  }

  CodecSettings table = playable, bpvf = playable, lossless = playable, no_transform = playable;
  table.table_residuals = true;
  bpvf.mode = RateMode::bpvf;
  bpvf.target = 2;
  lossless.mode = RateMode::lossless;
  no_transform.transform_residuals = false;
  for (const CodecSettings& settings : {table, bpvf, lossless, no_transform}) {
    std::vector<uint8_t> stream;
    EXPECT_EQ(encode_animation(clips, base, settings, stream).code(), StatusCode::invalid_argument);
  }
}

// decode_animation_into decodes into clips the caller has shaped: the same floats as decode_animation, for a
// version-4 stream on 1 and 3 threads and for a residual-loop stream; clips shaped otherwise are refused.
TEST(TransformResiduals, DecodesIntoShapedClipsAsDecodeAnimationDoes) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  for (const CodecSettings& settings : {error(0.15), residual_loop(error(0.15))}) {
    const Encoded encoded = encode(clips, base, settings);
    std::vector<FrameSequence> whole;
    ASSERT_TRUE(decode_animation(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, whole).ok());
    ASSERT_EQ(whole.size(), clips.size());
    for (size_t threads : {1, 3}) {
      std::vector<FrameSequence> shaped = clips;
      for (FrameSequence& clip : shaped) std::fill(clip.positions.begin(), clip.positions.end(), -1.0f);
      ASSERT_TRUE(decode_animation_into(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, shaped,
                                        threads).ok());
      for (size_t c = 0; c < clips.size(); ++c) EXPECT_EQ(shaped[c].positions, whole[c].positions) << c;
    }
    auto refused = [&](std::vector<FrameSequence> shaped, const char* what) {
      EXPECT_EQ(decode_animation_into(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, shaped)
                    .code(),
                StatusCode::invalid_argument)
          << what;
    };
    std::vector<FrameSequence> shaped = clips;
    shaped.pop_back();
    refused(shaped, "a clip fewer");
    shaped = clips;
    shaped[1].frame_count -= 1;
    refused(shaped, "a frame fewer");
    shaped = clips;
    shaped[0].positions.pop_back();
    refused(shaped, "positions short");
  }
}

// A stream that breaks version 4's rules is refused, never decoded: residual-loop flags, a basis source or size out
// of range, a bad step, a coefficient beyond the limit; and every prefix of a valid stream.
TEST(TransformResidualsHostile, BrokenStreamsAreRefused) {
  const std::vector<FrameSequence> clips = two_clips();
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, error(0.15));
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  auto refused = [&](const StreamContent& changed, const char* what) {
    std::vector<uint8_t> stream;
    write_stream_until_invalid(changed, base, stream);
    std::vector<FrameSequence> decoded;
    for (size_t threads : {1, 3}) {
      const Status status = decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded, threads);
      EXPECT_FALSE(status.ok()) << what << ", " << threads << " threads";
      EXPECT_EQ(status.code(), StatusCode::bad_data) << what << ", " << threads << " threads";
    }
  };
  size_t with_basis = 0;
  while (with_basis < content.cluster_count && content.basis_size[with_basis] == 0) ++with_basis;
  ASSERT_LT(with_basis, content.cluster_count);
  {
    std::vector<uint8_t> stream = encoded.stream;
    stream[5] |= format::kFlagTemporalResiduals;
    std::vector<FrameSequence> decoded;
    EXPECT_FALSE(decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded).ok());
  }
  {
    StreamContent changed = content;
    changed.basis_source[with_basis] = 3;
    refused(changed, "basis source 3");
  }
  {
    StreamContent changed = content;
    changed.basis_size[with_basis] = uint32_t(content.frame_count() + 1);
    refused(changed, "more vectors than frames");
  }
  {
    StreamContent changed = content;
    changed.coefficient_step[with_basis] = 0;
    refused(changed, "a zero coefficient step");
  }
  {
    StreamContent changed = content;
    changed.coefficient_symbols[0] = INT32_MAX;  // its prediction is at least −kMaxTransformValue
    refused(changed, "a coefficient beyond the limit");
  }
  for (size_t size = 0; size < encoded.stream.size(); size += std::max<size_t>(1, encoded.stream.size() / 200)) {
    std::vector<FrameSequence> decoded;
    EXPECT_FALSE(decode_animation(encoded.stream.data(), size, base, clips[0].triangles, decoded).ok()) << size;
    EXPECT_FALSE(decode_animation(encoded.stream.data(), size, base, clips[0].triangles, decoded, 3).ok()) << size;
  }
}

}  // namespace
}  // namespace segmorph
