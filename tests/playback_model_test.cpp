// The model of a version-4 stream through the runtime API (segmorph_decoder_model_*, AnimationDecoder::model_*;
// codec/decode/playback_model.h): its arrays in the documented shapes, its float32 evaluation at every frame's parameters
// against the decoded frames, blends of parameters against blends of frames, the bounds against every frame, and
// versions 1 to 3, bad arguments and a closed decoder refused with their statuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "encode/encoder.h"
#include "segmorph/decoder.h"
#include "segmorph/decoder_c.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

struct Case {
  std::vector<FrameSequence> clips;
  std::vector<float> base;
  std::vector<uint8_t> stream;
};

// Two clips of the bending sphere at an error target where version 4 keeps bases (checked below).
Case version_four(bool transform = true) {
  Case c;
  c.clips = {testing::bending_clip(30, 1.0, 0), testing::bending_clip(21, 0.7, 1.5)};
  c.base = testing::quantized_base(c.clips[0]);
  CodecSettings settings;
  settings.target = 0.15;
  settings.transform_residuals = transform;
  c.stream = testing::encode(c.clips, c.base, settings).stream;
  return c;
}

segmorph_status open(segmorph_decoder* decoder, const Case& c) {
  return segmorph_decoder_open(decoder, c.stream.data(), c.stream.size(), c.base.data(), c.base.size() / 3,
                               c.clips[0].triangles.data(), c.clips[0].triangles.size());
}

// The decoded frames of every clip, end to end.
std::vector<float> decoded_frames(segmorph_decoder* decoder) {
  std::vector<float> frames;
  for (size_t clip = 0; clip < segmorph_decoder_clip_count(decoder); ++clip) {
    std::vector<float> one(segmorph_decode_clip_bound(decoder, clip));
    EXPECT_EQ(segmorph_decode_clip(decoder, clip, one.data(), one.size()), SEGMORPH_STATUS_OK);
    frames.insert(frames.end(), one.begin(), one.end());
  }
  return frames;
}

double diagonal(const std::vector<float>& frames) {
  double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < frames.size(); ++i)
    low[i % 3] = std::min(low[i % 3], double(frames[i])), high[i % 3] = std::max(high[i % 3], double(frames[i]));
  return std::sqrt((high[0] - low[0]) * (high[0] - low[0]) + (high[1] - low[1]) * (high[1] - low[1]) +
                   (high[2] - low[2]) * (high[2] - low[2]));
}

// Every array of the model, as an engine reads them.
struct Model {
  segmorph_model_info info;
  std::vector<uint32_t> welded, clusters, bases, offsets;
  std::vector<float> weights, centroids, coefficients, motion, basis;
};

Model read_model(segmorph_decoder* decoder) {
  Model m;
  EXPECT_EQ(segmorph_decoder_model_info(decoder, &m.info), SEGMORPH_STATUS_OK) << segmorph_decoder_message(decoder);
  const segmorph_model_info& info = m.info;
  m.welded.resize(info.vertex_count);
  m.clusters.resize(info.welded_count * 4);
  m.weights.resize(info.welded_count * 4);
  m.centroids.resize(info.cluster_count * 3);
  m.bases.resize(info.cluster_count * 2);
  m.offsets.resize(info.welded_count + 1);
  m.coefficients.resize(info.coefficient_count * 3);
  m.motion.resize(info.frame_count * info.cluster_count * 12);
  m.basis.resize(info.frame_count * info.basis_count);
  EXPECT_EQ(segmorph_decoder_model_welded(decoder, m.welded.data(), m.welded.size()), SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_weights(decoder, m.clusters.data(), m.weights.data(), m.clusters.size()),
            SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_clusters(decoder, m.centroids.data(), m.bases.data(), info.cluster_count),
            SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_coefficients(decoder, m.offsets.data(), m.offsets.size(), m.coefficients.data(),
                                                m.coefficients.size()),
            SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_motion(decoder, 0, info.frame_count, m.motion.data(), m.motion.size()),
            SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_basis(decoder, 0, info.frame_count, m.basis.data(), m.basis.size()),
            SEGMORPH_STATUS_OK);
  return m;
}

TEST(PlaybackModel, ArraysHaveTheDocumentedShapes) {
  const Case c = version_four();
  ASSERT_EQ(c.stream[4], 4);
  segmorph_decoder* decoder = segmorph_decoder_create();
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK) << segmorph_decoder_message(decoder);
  const Model m = read_model(decoder);
  const segmorph_model_info& info = m.info;
  EXPECT_EQ(info.vertex_count, c.base.size() / 3);
  EXPECT_EQ(info.frame_count, 51u);
  EXPECT_GE(info.cluster_count, 2u);
  EXPECT_LE(info.welded_count, info.vertex_count);
  EXPECT_GE(info.max_pairs, 1u);
  EXPECT_LE(info.max_pairs, 4u);
  ASSERT_GT(info.max_basis_size, 0u) << "the case must have residual bases to test them";
  // Every vertex names a welded vertex; copies have the same base position.
  std::vector<bool> seen(info.welded_count, false);
  std::vector<float> welded_position(info.welded_count * 3);
  for (size_t v = 0; v < info.vertex_count; ++v) {
    ASSERT_LT(m.welded[v], info.welded_count);
    for (size_t a = 0; a < 3; ++a) {
      if (seen[m.welded[v]]) {
        EXPECT_EQ(welded_position[m.welded[v] * 3 + a], c.base[v * 3 + a]);
      }
      welded_position[m.welded[v] * 3 + a] = c.base[v * 3 + a];
    }
    seen[m.welded[v]] = true;
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](bool b) { return b; }));
  // Weights sum to 1; pairs name clusters; a vertex's coefficient vectors are its own cluster's m.
  size_t blended = 0;
  for (size_t w = 0; w < info.welded_count; ++w) {
    double sum = 0;
    for (size_t j = 0; j < 4; ++j) {
      ASSERT_LT(m.clusters[w * 4 + j], info.cluster_count);
      sum += m.weights[w * 4 + j];
      if (j > 0 && m.weights[w * 4 + j] != 0) ++blended;
    }
    EXPECT_NEAR(sum, 1.0, 1e-6) << w;
    const uint32_t own = m.clusters[w * 4];
    EXPECT_EQ(m.offsets[w + 1] - m.offsets[w], m.bases[own * 2 + 1]) << w;
  }
  EXPECT_EQ(m.offsets[info.welded_count], info.coefficient_count);
  EXPECT_GT(blended, 0u) << "the case must blend clusters to test the pairs";
  for (size_t k = 0; k < info.cluster_count; ++k) {
    EXPECT_LE(m.bases[k * 2] + m.bases[k * 2 + 1], info.basis_count);
    EXPECT_LE(m.bases[k * 2 + 1], info.max_basis_size);
  }
  // A frame range reads the same values as the whole.
  std::vector<float> motion(3 * info.cluster_count * 12), basis(3 * info.basis_count);
  ASSERT_EQ(segmorph_decoder_model_motion(decoder, 40, 3, motion.data(), motion.size()), SEGMORPH_STATUS_OK);
  ASSERT_EQ(segmorph_decoder_model_basis(decoder, 40, 3, basis.data(), basis.size()), SEGMORPH_STATUS_OK);
  EXPECT_TRUE(std::equal(motion.begin(), motion.end(), m.motion.begin() + ptrdiff_t(40 * info.cluster_count * 12)));
  EXPECT_TRUE(std::equal(basis.begin(), basis.end(), m.basis.begin() + ptrdiff_t(40 * info.basis_count)));
  segmorph_decoder_destroy(decoder);
}

// The float32 reference at each frame's parameters is the decoded frame up to float rounding; and an independent
// evaluation from the arrays alone (in double, as an engine's own code would) agrees with it.
TEST(PlaybackModel, EveryFrameEvaluatesToTheDecodedFrame) {
  const Case c = version_four();
  segmorph_decoder* decoder = segmorph_decoder_create();
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  const std::vector<float> frames = decoded_frames(decoder);
  const Model m = read_model(decoder);
  const segmorph_model_info& info = m.info;
  const double scale = diagonal(frames);
  const size_t K = info.cluster_count, N = info.basis_count, V = info.vertex_count;
  double largest = 0, largest_arrays = 0;
  std::vector<float> positions(V * 3);
  for (size_t f = 0; f < info.frame_count; ++f) {
    ASSERT_EQ(segmorph_decoder_model_evaluate(decoder, &m.motion[f * K * 12], K * 12, &m.basis[f * N], N,
                                              positions.data(), positions.size()),
              SEGMORPH_STATUS_OK);
    for (size_t v = 0; v < V; ++v) {
      const size_t w = m.welded[v];
      double x[3] = {0, 0, 0};
      for (size_t j = 0; j < 4; ++j) {
        const size_t k = m.clusters[w * 4 + j];
        const float* A = &m.motion[(f * K + k) * 12];
        double d[3];
        for (size_t a = 0; a < 3; ++a) d[a] = double(c.base[v * 3 + a]) - m.centroids[k * 3 + a];
        for (size_t r = 0; r < 3; ++r)
          x[r] += m.weights[w * 4 + j] * (A[r * 4] * d[0] + A[r * 4 + 1] * d[1] + A[r * 4 + 2] * d[2] + A[r * 4 + 3]);
      }
      const size_t own = m.clusters[w * 4];
      for (size_t i = 0; i < m.bases[own * 2 + 1]; ++i)
        for (size_t a = 0; a < 3; ++a)
          x[a] += double(m.coefficients[(m.offsets[w] + i) * 3 + a]) * m.basis[f * N + m.bases[own * 2] + i];
      for (size_t a = 0; a < 3; ++a) {
        const double decoded = frames[(f * V + v) * 3 + a];
        largest = std::max(largest, std::fabs(double(positions[v * 3 + a]) - decoded));
        largest_arrays = std::max(largest_arrays, std::fabs(x[a] - decoded));
      }
    }
  }
  EXPECT_LT(largest / scale, 1e-6) << "float32 reference against the decoder";
  EXPECT_LT(largest_arrays / scale, 1e-6) << "the arrays evaluated in double against the decoder";
  EXPECT_GT(largest, 0.0) << "float32 is not expected to be bit for bit the double decoder";
  segmorph_decoder_destroy(decoder);
}

// Positions are linear in the parameters: the model at a blend of two frames' (of different clips, weights not
// summing to 1, as a fading animation gives) is the same blend of the two decoded frames.
TEST(PlaybackModel, BlendedParametersGiveTheBlendOfFrames) {
  const Case c = version_four();
  segmorph_decoder* decoder = segmorph_decoder_create();
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  const std::vector<float> frames = decoded_frames(decoder);
  const Model m = read_model(decoder);
  const size_t K = m.info.cluster_count, N = m.info.basis_count, V = m.info.vertex_count;
  const size_t a = 12, b = 30 + 17;  // clip 0 frame 12, clip 1 frame 17
  const double wa = 0.35, wb = 0.5;
  std::vector<float> motion(K * 12), basis(N), positions(V * 3);
  for (size_t i = 0; i < K * 12; ++i) motion[i] = float(wa * m.motion[a * K * 12 + i] + wb * m.motion[b * K * 12 + i]);
  for (size_t i = 0; i < N; ++i) basis[i] = float(wa * m.basis[a * N + i] + wb * m.basis[b * N + i]);
  ASSERT_EQ(segmorph_decoder_model_evaluate(decoder, motion.data(), motion.size(), basis.data(), basis.size(),
                                            positions.data(), positions.size()),
            SEGMORPH_STATUS_OK);
  double largest = 0, moved = 0;
  for (size_t i = 0; i < V * 3; ++i) {
    const double expected = wa * frames[a * V * 3 + i] + wb * frames[b * V * 3 + i];
    largest = std::max(largest, std::fabs(positions[i] - expected));
    moved = std::max(moved, std::fabs(double(frames[a * V * 3 + i]) - frames[b * V * 3 + i]));
  }
  const double scale = diagonal(frames);
  EXPECT_LT(largest / scale, 1e-6);
  EXPECT_GT(moved / scale, 1e-2) << "the two frames must differ for the blend to mean something";
  segmorph_decoder_destroy(decoder);
}

TEST(PlaybackModel, BoundsHoldEveryFrameAndAreNotLoose) {
  const Case c = version_four();
  segmorph_decoder* decoder = segmorph_decoder_create();
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  const std::vector<float> frames = decoded_frames(decoder);
  float box[6];
  ASSERT_EQ(segmorph_decoder_model_bounds(decoder, box), SEGMORPH_STATUS_OK) << segmorph_decoder_message(decoder);
  double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_GE(frames[i], box[i % 3]) << i;
    EXPECT_LE(frames[i], box[3 + i % 3]) << i;
    low[i % 3] = std::min(low[i % 3], double(frames[i])), high[i % 3] = std::max(high[i % 3], double(frames[i]));
  }
  for (size_t a = 0; a < 3; ++a) EXPECT_LT(box[3 + a] - box[a], 1.5 * (high[a] - low[a])) << "axis " << a;
  segmorph_decoder_destroy(decoder);
}

TEST(PlaybackModel, VersionsOneToThreeHaveNoModel) {
  const Case c = version_four(false);
  ASSERT_LE(c.stream[4], 3);
  segmorph_decoder* decoder = segmorph_decoder_create();
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  segmorph_model_info info;
  EXPECT_EQ(segmorph_decoder_model_info(decoder, &info), SEGMORPH_STATUS_UNSUPPORTED);
  EXPECT_NE(std::string(segmorph_decoder_message(decoder)).find("only version-4 streams have a model"),
            std::string::npos)
      << segmorph_decoder_message(decoder);
  float box[6];
  EXPECT_EQ(segmorph_decoder_model_bounds(decoder, box), SEGMORPH_STATUS_UNSUPPORTED);
  // The decoder still decodes its frames.
  std::vector<float> frames(segmorph_decode_clip_bound(decoder, 0));
  EXPECT_EQ(segmorph_decode_clip(decoder, 0, frames.data(), frames.size()), SEGMORPH_STATUS_OK);
  segmorph_decoder_destroy(decoder);
  // The C++ API says the same.
  AnimationDecoder cpp;
  ASSERT_TRUE(cpp.open(c.stream.data(), c.stream.size(), c.base.data(), c.base.size() / 3,
                       c.clips[0].triangles.data(), c.clips[0].triangles.size())
                  .ok());
  AnimationDecoder::ModelInfo cpp_info;
  EXPECT_EQ(cpp.model_info(cpp_info).code(), StatusCode::unsupported);
}

TEST(PlaybackModel, BadArgumentsAreRefusedWithAMessage) {
  const Case c = version_four();
  segmorph_decoder* decoder = segmorph_decoder_create();
  segmorph_model_info info;
  EXPECT_EQ(segmorph_decoder_model_info(nullptr, &info), SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_info(decoder, &info), SEGMORPH_STATUS_INVALID_ARGUMENT) << "nothing is open";
  EXPECT_STREQ(segmorph_decoder_message(decoder), "no stream is open");
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_info(decoder, nullptr), SEGMORPH_STATUS_INVALID_ARGUMENT);
  ASSERT_EQ(segmorph_decoder_model_info(decoder, &info), SEGMORPH_STATUS_OK);
  std::vector<uint32_t> u(info.vertex_count + info.welded_count * 4 + 8);
  std::vector<float> f(info.frame_count * (info.cluster_count * 12 + info.basis_count) + info.vertex_count * 3 +
                       info.coefficient_count * 3 + 8);
  EXPECT_EQ(segmorph_decoder_model_welded(decoder, u.data(), info.vertex_count - 1), SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(segmorph_decoder_message(decoder)).find("the model needs"), std::string::npos);
  EXPECT_EQ(segmorph_decoder_model_welded(decoder, nullptr, info.vertex_count), SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_weights(decoder, u.data(), nullptr, info.welded_count * 4),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_clusters(decoder, f.data(), u.data(), info.cluster_count - 1),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_coefficients(decoder, u.data(), info.welded_count, f.data(), f.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_motion(decoder, info.frame_count, 1, f.data(), f.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_motion(decoder, 1, SIZE_MAX, f.data(), f.size()), SEGMORPH_STATUS_INVALID_ARGUMENT)
      << "first + count must not wrap around";
  EXPECT_EQ(segmorph_decoder_model_basis(decoder, 0, 2, f.data(), 2 * info.basis_count - 1),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_motion(decoder, 3, 0, nullptr, 0), SEGMORPH_STATUS_OK) << "an empty range";
  EXPECT_EQ(segmorph_decoder_model_bounds(decoder, nullptr), SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_evaluate(decoder, f.data(), info.cluster_count * 12 - 1, f.data(), f.size(),
                                            f.data(), f.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_model_evaluate(decoder, f.data(), f.size(), f.data(), f.size(), f.data(),
                                            info.vertex_count * 3 - 1),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  // After a new open (of a version-3 stream), the old model is gone.
  const Case old = version_four(false);
  ASSERT_EQ(open(decoder, old), SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_model_info(decoder, &info), SEGMORPH_STATUS_UNSUPPORTED);
  segmorph_decoder_destroy(decoder);
}

}  // namespace
}  // namespace segmorph
