// The codec end to end: closed loop, determinism, lossless, rate control, several clips, hostile streams.
#include "decode/frame_decoder.h"
#include "encode/encoder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "common/parallel.h"
#include "common/stream.h"
#include "common/stream_format.h"
#include "decode/stream_reader.h"
#include "encode/metrics.h"
#include "encode/stream_writer.h"
#include "fuzz/fuzz_base_mesh.h"
#include "gltf/load.h"
#include "sampling/sample.h"
#include "test_files.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::bending_clip;
using testing::kg;
using testing::quantized_base;

double bpvf(size_t bytes, const std::vector<FrameSequence>& clips) {
  size_t frames = 0;
  for (const FrameSequence& clip : clips) frames += clip.frame_count;
  return bits_per_vertex_frame(bytes, clips[0].vertex_count, frames);
}

using testing::Encoded;
using testing::encode;

TEST(Codec, DecodingGivesTheEncodersReconstructionExactly) {
  const std::vector<FrameSequence> clips = {bending_clip(30, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings;
  settings.target = 0.5;
  const Encoded encoded = encode(clips, base, settings);
  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, decoded).ok());
  ASSERT_EQ(decoded.size(), 1u);
  EXPECT_EQ(decoded[0].positions, encoded.reconstruction[0].positions);
  EXPECT_LE(kg(clips, decoded), 0.5);
  EXPECT_GT(encoded.report.clusters, 1u);
}

// parallel_items (common/parallel.h): every item exactly once, item 0 on the calling thread, for any item and thread
// count; an item's exception comes back after every thread has finished (on one thread: the first failing item's,
// and no item after it starts).
TEST(Parallel, ItemsRunOnceEachTheFirstOnTheCallingThread) {
  for (size_t count : {0, 1, 2, 5, 100})
    for (size_t threads : {1, 2, 3, 8}) {
      SCOPED_TRACE(std::to_string(count) + " items, " + std::to_string(threads) + " threads");
      std::vector<std::atomic<int>> runs(count);
      std::thread::id first;
      parallel_items(count, threads, [&](size_t i) {
        if (i == 0) first = std::this_thread::get_id();
        runs[i] += 1;
      });
      for (size_t i = 0; i < count; ++i) EXPECT_EQ(runs[i].load(), 1) << "item " << i;
      if (count > 0) {
        EXPECT_EQ(first, std::this_thread::get_id());
      }
    }
}

TEST(Parallel, AnItemsExceptionComesBack) {
  for (size_t threads : {1, 4}) {
    std::vector<std::atomic<int>> runs(40);
    try {
      parallel_items(40, threads, [&](size_t i) {
        runs[i] += 1;
        if (i == 3 || i == 7) throw std::runtime_error("item " + std::to_string(i));
      });
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& error) {
      if (threads == 1) {
        EXPECT_STREQ(error.what(), "item 3");
        for (size_t i = 4; i < runs.size(); ++i) EXPECT_EQ(runs[i].load(), 0) << "item " << i << " ran after item 3 failed";
      } else {
        EXPECT_TRUE(std::string(error.what()) == "item 3" || std::string(error.what()) == "item 7") << error.what();
      }
    }
  }
}

TEST(Codec, TwoEncodesAreByteIdentical) {
  const std::vector<FrameSequence> clips = {bending_clip(20, 0.8, 1)};
  const std::vector<float> base = quantized_base(clips[0]);
  EXPECT_EQ(encode(clips, base, CodecSettings()).stream, encode(clips, base, CodecSettings()).stream);
}

// Long encodes say where they are: every stage, the passes over every frame with their fraction done, always on the
// calling thread (a caller prints from it), and the same bytes as without a listener.
TEST(Codec, ProgressNamesEachStageOnTheCallingThread) {
  const std::vector<FrameSequence> clips = {bending_clip(30, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings;
  settings.threads = 2;
  const Encoded quiet = encode(clips, base, settings);
  std::vector<std::pair<std::string, double>> calls;
  bool other_thread = false;
  const std::thread::id caller = std::this_thread::get_id();
  settings.progress = [&](const std::string& stage, double fraction) {
    other_thread |= std::this_thread::get_id() != caller;
    calls.emplace_back(stage, fraction);
  };
  EXPECT_EQ(encode(clips, base, settings).stream, quiet.stream);
  EXPECT_FALSE(other_thread);
  auto seen = [&](const std::string& prefix) {
    return std::any_of(calls.begin(), calls.end(), [&](const auto& call) { return call.first.rfind(prefix, 0) == 0; });
  };
  for (const char* stage : {"segmentation: heat diffusion", "segmentation: eigenpairs: factorizing",
                            "segmentation: eigenpairs: Lanczos iteration", "segmentation: feature points",
                            "segmentation: Morse levels", "cluster count: trying ",
                            "motion refinement", "rate control: quantizing",
                            "rate control: measuring ", "rate control: trying ", "coding the residuals",
                            "writing the stream"})
    EXPECT_TRUE(seen(stage)) << stage;
  // Within a run of one stage the fraction only grows, to 1 for the passes over the frames (a pass starts at 0, and
  // two passes in a row may measure as many steps).
  for (size_t i = 0; i < calls.size(); ++i) {
    EXPECT_LE(calls[i].second, 1.0) << calls[i].first;
    const bool last_of_run = i + 1 == calls.size() || calls[i + 1].first != calls[i].first ||
                             (calls[i].second == 1.0 && calls[i + 1].second == 0.0);
    if (!last_of_run) {
      EXPECT_LE(calls[i].second, calls[i + 1].second) << calls[i].first;
    } else if (calls[i].first.rfind("rate control: measuring ", 0) == 0 ||
               calls[i].first.rfind("rate control: trying ", 0) == 0 || calls[i].first == "coding the residuals") {
      EXPECT_EQ(calls[i].second, 1.0) << calls[i].first;
    }
  }
}

TEST(Codec, LosslessRestoresTheFloatsBitForBit) {
  const std::vector<FrameSequence> clips = {bending_clip(12, 1.2, 2), bending_clip(7, -0.5, 0.3)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings;
  settings.mode = RateMode::lossless;
  const Encoded encoded = encode(clips, base, settings);
  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, decoded).ok());
  ASSERT_EQ(decoded.size(), 2u);
  for (size_t c = 0; c < 2; ++c) {
    ASSERT_EQ(decoded[c].positions.size(), clips[c].positions.size());
    EXPECT_EQ(std::memcmp(decoded[c].positions.data(), clips[c].positions.data(), clips[c].positions.size() * 4), 0);
  }
  // Lossless still compresses: well under the 96 bits of three raw floats.
  EXPECT_LT(bpvf(encoded.stream.size(), clips), 60.0);
}

// The stream's welding refers to groups of identical base positions (the decoder finds them itself), so the
// encoder may weld only vertices whose frames AND base positions are equal. A lossy base (Draco) can separate
// two copies of a seam vertex, and can merge two vertices that move apart: both must round-trip.
TEST(Codec, WeldingFollowsTheBaseWhereItDisagreesWithTheFrames) {
  std::vector<FrameSequence> clips = {bending_clip(16, 1.0, 0)};
  FrameSequence& clip = clips[0];
  const size_t v = clip.vertex_count;
  // Vertex v copies vertex 0 (same frames); vertex v + 1 copies vertex 1 at rest, then drifts.
  std::vector<float> positions;
  for (size_t f = 0; f < clip.frame_count; ++f) {
    const float* frame = clip.frame(f);
    positions.insert(positions.end(), frame, frame + v * 3);
    positions.insert(positions.end(), frame, frame + 3);
    positions.insert(positions.end(), {frame[3] + 0.01f * float(f), frame[4], frame[5]});
  }
  clip.positions = positions;
  clip.vertex_count = v + 2;
  for (size_t t = 0; t < clip.triangles.size(); ++t) {
    if (clip.triangles[t] == 0) {
      clip.triangles[t] = uint32_t(v);
      break;
    }
  }
  for (size_t t = 0; t < clip.triangles.size(); ++t) {
    if (clip.triangles[t] == 1) {
      clip.triangles[t] = uint32_t(v + 1);
      break;
    }
  }
  for (int variant = 0; variant < 2; ++variant) {
    std::vector<float> base = quantized_base(clip);
    if (variant == 0) {
      base[v * 3] += 1e-4f;  // the copy of vertex 0 lands one quantization step away
    } else {
      base[2] = 0.0f;  // or differs only by the sign of a zero (the stream compares bit patterns)
      base[v * 3 + 2] = -0.0f;
    }
    for (RateMode mode : {RateMode::error, RateMode::lossless}) {
      CodecSettings settings;
      settings.mode = mode;
      const Encoded encoded = encode(clips, base, settings);
      std::vector<FrameSequence> decoded;
      const Status status =
          decode_animation(encoded.stream.data(), encoded.stream.size(), base, clip.triangles, decoded);
      ASSERT_TRUE(status.ok()) << status.message() << " (variant " << variant << ")";
      EXPECT_EQ(decoded[0].positions, encoded.reconstruction[0].positions);
    }
  }
}

TEST(Codec, ErrorTargetIsMetWithoutWaste) {
  const std::vector<FrameSequence> clips = {bending_clip(30, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  for (double target : {1.0, 0.3, 0.1}) {
    CodecSettings settings;
    settings.target = target;
    const Encoded encoded = encode(clips, base, settings);
    const double error = kg(clips, encoded.reconstruction);
    EXPECT_LE(error, target) << target;
    EXPECT_GE(error, 0.6 * target) << target << ": the rate control leaves most of the allowed error unused";
    EXPECT_NEAR(encoded.report.kg_percent, error, 1e-9);
  }
}

TEST(Codec, RateTargetWithinFivePercent) {
  const std::vector<FrameSequence> clips = {bending_clip(40, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  for (double target : {1.5, 3.0, 6.0}) {
    CodecSettings settings;
    settings.mode = RateMode::bpvf;
    settings.target = target;
    const Encoded encoded = encode(clips, base, settings);
    EXPECT_NEAR(bpvf(encoded.stream.size(), clips), target, 0.05 * target)
        << "motion " << encoded.report.bytes_motion << " B, residuals " << encoded.report.bytes_residuals
        << " B, steps " << encoded.report.residual_steps[0] << " " << encoded.report.residual_steps[1] << " "
        << encoded.report.residual_steps[2];
  }
}

TEST(Codec, SeveralClipsShareOneSegmentation) {
  const std::vector<FrameSequence> clips = {bending_clip(15, 1.0, 0), bending_clip(9, -1.0, 1),
                                            bending_clip(4, 0.3, 2)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, CodecSettings());
  std::vector<FrameSequence> decoded;
  ASSERT_TRUE(decode_animation(encoded.stream.data(), encoded.stream.size(), base, clips[0].triangles, decoded).ok());
  ASSERT_EQ(decoded.size(), 3u);
  for (size_t c = 0; c < 3; ++c) {
    EXPECT_EQ(decoded[c].frame_count, clips[c].frame_count);
    EXPECT_EQ(decoded[c].positions, encoded.reconstruction[c].positions);
  }
  EXPECT_LE(kg(clips, decoded), 0.15);
}

TEST(CodecHostile, PrefixesTrailingBytesAndWrongBasesAreRefused) {
  const std::vector<FrameSequence> clips = {bending_clip(6, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, CodecSettings());
  std::vector<FrameSequence> decoded;
  for (size_t size = 0; size < encoded.stream.size(); ++size)
    EXPECT_FALSE(decode_animation(encoded.stream.data(), size, base, clips[0].triangles, decoded).ok())
        << "prefix of " << size << " bytes";
  std::vector<uint8_t> longer = encoded.stream;
  longer.push_back(0);
  EXPECT_FALSE(decode_animation(longer.data(), longer.size(), base, clips[0].triangles, decoded).ok());
  const std::vector<float> smaller(base.begin(), base.end() - 3);
  EXPECT_FALSE(
      decode_animation(encoded.stream.data(), encoded.stream.size(), smaller, clips[0].triangles, decoded).ok());
  std::vector<uint8_t> version = encoded.stream;
  version[4] = 99;
  EXPECT_EQ(decode_animation(version.data(), version.size(), base, clips[0].triangles, decoded).code(),
            StatusCode::unsupported);
}

TEST(CodecHostile, RandomByteFlipsNeverCrash) {
  const std::vector<FrameSequence> clips = {bending_clip(6, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  const Encoded encoded = encode(clips, base, CodecSettings());
  std::mt19937 random(11);
  size_t refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> bytes = encoded.stream;
    for (int flips = 1 + int(random() % 4); flips > 0; --flips)
      bytes[random() % bytes.size()] ^= uint8_t(1 + random() % 255);
    std::vector<FrameSequence> decoded;
    const Status status = decode_animation(bytes.data(), bytes.size(), base, clips[0].triangles, decoded);
    if (!status.ok()) {
      ++refused;
      EXPECT_EQ(status.message().find('\n'), std::string::npos);
    } else {
      for (const FrameSequence& clip : decoded)
        for (float x : clip.positions) ASSERT_TRUE(std::isfinite(x));
    }
  }
  EXPECT_GT(refused, 200u);  // the range coder's end check catches nearly every change
}

// 25 bytes for the fuzz targets' base mesh that claim one clip of 5 million frames and one cluster, and end
// after the motion quantizer steps. The decoder sized the motion by the claim (240 MB here; 11 GB with 46
// clusters, which fuzz_animation_stream reports as out-of-memory) before decoding any of it.
TEST(CodecHostile, ShortStreamClaimingMillionsOfFramesAllocatesNothingForThem) {
  const uint8_t stream[] = {0x53, 0x47, 0x4d, 0x41, 0x01, 0x06, 0x0f, 0x00, 0x00, 0x00, 0x1a, 0x80, 0xb9,
                            0x84, 0x08, 0x8c, 0x7f, 0x1a, 0xbc, 0x50, 0x20, 0x71, 0xf5, 0x3a, 0x20};
  const fuzz::BaseMesh mesh = fuzz::base_mesh();
  std::vector<FrameSequence> decoded;
  EXPECT_EQ(decode_animation(stream, sizeof(stream), mesh.positions, mesh.triangles, decoded).code(),
            StatusCode::bad_data);
  StreamContent content;
  EXPECT_FALSE(read_stream(stream, sizeof(stream), mesh.positions, content).ok());
  EXPECT_EQ(content.frame_count(), 5000000u);
  // What was decoded before the data ran out, not 60 million coefficients.
  EXPECT_LT(content.motion.capacity(), 1000u);
  EXPECT_EQ(content.residuals.capacity(), 0u);
}

// The decoder turns residuals into frames as it reads them. A stream whose head is whole (its motion is there for
// every frame it claims) but whose residuals stop short must not have the claimed frames allocated first: the
// output grows with what decodes, as the motion and the residuals do.
TEST(CodecHostile, StreamCutInItsResidualsIsRefusedBeforeItsFramesAreAllocated) {
  const std::vector<FrameSequence> clips = {bending_clip(400, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings;
  settings.transform_residuals = false;  // residual symbols, read frame by frame (version 4 reads them all at once)
  const Encoded encoded = encode(clips, base, settings);
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  std::vector<uint8_t> stream;
  StreamSizes sizes;
  write_stream(content, base, stream, &sizes);
  ASSERT_EQ(stream, encoded.stream);
  // The head (the range coder holds back up to a few of its bytes) and a little of the residuals, with the length
  // field to match: 16 bytes cannot hold 400 frames of 642 vertices (at most 364 vertex-frames a byte), and the
  // decoder says so before it decodes or allocates any frame.
  ASSERT_GT(sizes.residuals, 1000u);
  stream.resize(sizes.motion + 16);
  const uint32_t length = uint32_t(stream.size() - format::kHeaderBytes);
  for (int i = 0; i < 4; ++i) stream[6 + size_t(i)] = uint8_t(length >> (8 * i));
  std::vector<FrameSequence> decoded;
  const Status status = decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded);
  EXPECT_EQ(status.code(), StatusCode::bad_data);
  EXPECT_NE(status.message().find("more than its"), std::string::npos) << status.message();
  EXPECT_TRUE(decoded.empty());
}

// A lossless escape carries any 64-bit value. Added to the float pattern of a prediction, one beyond the largest
// difference of two patterns (±(2^32 − 1)) overflowed int64: undefined behaviour, which UBSan reported in
// fuzz_animation_stream on a seed rewritten this way.
TEST(CodecHostile, LosslessEscapeBeyondAnyFloatDifferenceIsRefused) {
  const std::vector<FrameSequence> clips = {bending_clip(3, 1.0, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings;
  settings.mode = RateMode::lossless;
  const Encoded encoded = encode(clips, base, settings);
  StreamContent content;
  ASSERT_TRUE(read_stream(encoded.stream.data(), encoded.stream.size(), base, content).ok());
  for (int64_t extreme : {INT64_MAX, -INT64_MAX, int64_t(1) << 32}) {
    StreamContent changed = content;
    std::fill_n(changed.residuals.begin(), size_t(content.welded_count) * 3, extreme);  // the first frame
    std::vector<uint8_t> stream;
    write_stream(changed, base, stream);
    std::vector<FrameSequence> decoded;
    EXPECT_EQ(decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded).code(),
              StatusCode::bad_data)
        << extreme;
  }
}

}  // namespace
}  // namespace segmorph

namespace segmorph {
namespace {

// Motion refinement moves boundary vertices to the clusters whose motion predicts them best: at the same K, E(Π) after
// it is below E(Π) without it. (E(Π) of the raw Morse segmentation, e_pi_morse, is of more clusters, before the merge
// to K: it is no reference for the final clusters.)
TEST(Codec, MotionRefinementLowersTheSegmentationErrorAtTheSameClusterCount) {
  const std::vector<FrameSequence> clips = {bending_clip(20, 1.2, 0)};
  const std::vector<float> base = quantized_base(clips[0]);
  CodecSettings settings;
  settings.clusters = 6;
  settings.motion_refinement = false;
  const Encoded plain = encode(clips, base, settings);
  settings.motion_refinement = true;
  const Encoded refined = encode(clips, base, settings);
  ASSERT_EQ(plain.report.clusters, refined.report.clusters);
  EXPECT_EQ(plain.report.motion_refinement_iterations, 0);
  EXPECT_GT(refined.report.motion_refinement_iterations, 0);
  EXPECT_LT(refined.report.e_pi, plain.report.e_pi);
}

// With choose_segmentation the encoder codes the Morse segmentation as found or as refined by Eq. 6, whichever its
// cluster count's estimate finds cheaper, and says which: a stream reported unrefined is the stream of an encode with
// the refinement off, one reported refined is the stream of the default encode (refined, no choice). The three bends
// choose both ways.
TEST(Codec, TheSegmentationCodedIsTheOneReported) {
  int refined = 0;
  for (double bend : {0.6, 1.2, 2.0}) {
    const std::vector<FrameSequence> clips = {bending_clip(24, bend, 0.5)};
    const std::vector<float> base = quantized_base(clips[0]);
    CodecSettings settings;
    const Encoded refined_only = encode(clips, base, settings);
    EXPECT_TRUE(refined_only.report.curvature_refined);
    settings.choose_segmentation = true;
    const Encoded chosen = encode(clips, base, settings);
    settings.curvature_refinement = false;
    const Encoded unrefined = encode(clips, base, settings);
    EXPECT_FALSE(unrefined.report.curvature_refined);
    EXPECT_EQ(chosen.stream == unrefined.stream, !chosen.report.curvature_refined) << bend;
    EXPECT_EQ(chosen.stream == refined_only.stream, chosen.report.curvature_refined) << bend;
    refined += chosen.report.curvature_refined;
  }
  EXPECT_EQ(refined, 1);
}

// The paper's Cow, the classic sequence: E(Π) within the paper's Table 2, and the KG targets met.
TEST(CodecSequences, CowMeetsThePapersSegmentationErrorAndTheErrorTargets) {
  if (!testing::have_shared_samples()) GTEST_SKIP() << "../shared/samples is absent: the cow sequence is not tested";
  tinygltf::Model model;
  Scene scene;
  SampledNode node;
  ASSERT_TRUE(load_gltf(std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/sequences/Cow_pcow/cow.glb", model).ok());
  ASSERT_TRUE(analyze_scene(model, scene).ok());
  ASSERT_TRUE(sample_node(model, scene, scene.animated[0], SampleSettings(), node).ok());
  const std::vector<FrameSequence>& clips = node.primitives[0].clips;
  const std::vector<float> base = quantized_base(clips[0]);
  for (double target : {0.5, 0.15}) {
    CodecSettings settings;
    settings.target = target;
    const Encoded encoded = encode(clips, base, settings);
    EXPECT_LE(encoded.report.e_pi, 0.0016);
    EXPECT_LE(kg(clips, encoded.reconstruction), target);
  }
}

}  // namespace
}  // namespace segmorph
