#include "encode/motion.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "encode/metrics.h"

namespace segmorph {
namespace {

// Random base positions (W × 3) in the unit cube.
std::vector<float> random_base(size_t vertex_count, std::mt19937& random) {
  std::uniform_real_distribution<float> unit(-1, 1);
  std::vector<float> base(vertex_count * 3);
  for (float& x : base) x = unit(random);
  return base;
}

// Frames in which every cluster moves by its own affine map (row-major [L | t], about the origin).
Trajectories move_by(const std::vector<float>& base, const Clusters& clusters,
                     const std::vector<std::vector<std::array<double, 12>>>& maps) {
  Trajectories frames;
  frames.vertex_count = base.size() / 3;
  frames.frame_count = maps.size();
  for (const auto& frame_maps : maps)
    for (size_t v = 0; v < frames.vertex_count; ++v) {
      const std::array<double, 12>& m = frame_maps[clusters.label[v]];
      for (int r = 0; r < 3; ++r)
        frames.positions.push_back(float(m[size_t(r) * 4] * base[v * 3] + m[size_t(r) * 4 + 1] * base[v * 3 + 1] +
                                         m[size_t(r) * 4 + 2] * base[v * 3 + 2] + m[size_t(r) * 4 + 3]));
    }
  return frames;
}

std::array<double, 12> random_map(std::mt19937& random) {
  std::uniform_real_distribution<double> small(-0.3, 0.3);
  std::array<double, 12> m = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  for (double& x : m) x += small(random);
  return m;
}

TEST(Motion, RecoversSyntheticPerClusterAffineMotionExactly) {
  std::mt19937 random(3);
  const std::vector<float> base = random_base(300, random);
  Clusters clusters;
  clusters.count = 3;
  for (size_t v = 0; v < 300; ++v) clusters.label.push_back(uint32_t(v % 3));
  std::vector<std::vector<std::array<double, 12>>> maps(5);
  for (auto& frame : maps)
    for (int k = 0; k < 3; ++k) frame.push_back(random_map(random));
  const Trajectories frames = move_by(base, clusters, maps);
  const AffineMotion motion = fit_affine_motion(base.data(), frames, clusters);

  // Predictions with one-hot weights reproduce the frames to float precision (positions of order 1).
  std::vector<double> predicted(900);
  for (size_t f = 0; f < 5; ++f) {
    predict_frame(base.data(), motion, own_cluster_weights(clusters), f, predicted.data());
    for (size_t i = 0; i < 900; ++i) ASSERT_NEAR(predicted[i], frames.frame(f)[i], 1e-5) << "frame " << f;
  }
  EXPECT_LT(motion_compensation_error(base.data(), frames, clusters, motion), 1e-11);
  // The centred translation is the image of the centroid.
  const std::vector<double> centroid = cluster_centroids(base.data(), clusters);
  const std::array<double, 12>& m = maps[2][1];
  for (int r = 0; r < 3; ++r) {
    const double image = m[size_t(r) * 4] * centroid[3] + m[size_t(r) * 4 + 1] * centroid[4] +
                         m[size_t(r) * 4 + 2] * centroid[5] + m[size_t(r) * 4 + 3];
    EXPECT_NEAR(motion.transform(2, 1)[r * 4 + 3], image, 1e-5);
  }
}

TEST(Motion, MotionErrorGrowsWhenAClusterMixesTwoMotions) {
  std::mt19937 random(4);
  const std::vector<float> base = random_base(200, random);
  Clusters truth;
  truth.count = 2;
  for (size_t v = 0; v < 200; ++v) truth.label.push_back(uint32_t(v < 100 ? 0 : 1));
  std::vector<std::vector<std::array<double, 12>>> maps(4);
  for (auto& frame : maps) frame = {random_map(random), random_map(random)};
  const Trajectories frames = move_by(base, truth, maps);
  Clusters one;
  one.count = 1;
  one.label.assign(200, 0);
  const double wrong = motion_compensation_error(base.data(), frames, one, fit_affine_motion(base.data(), frames, one));
  EXPECT_GT(wrong, 1e-4);
}

TEST(Motion, RefitGivesTheWholeFitsNumbers) {
  std::mt19937 random(8);
  const std::vector<float> base = random_base(300, random);
  Clusters before;
  before.count = 6;
  for (size_t v = 0; v < 300; ++v) before.label.push_back(uint32_t(v % 6));
  std::vector<std::vector<std::array<double, 12>>> maps(7);
  for (auto& frame : maps)
    for (int k = 0; k < 6; ++k) frame.push_back(random_map(random));
  Trajectories frames = move_by(base, before, maps);
  std::normal_distribution<float> noise(0, 0.01f);
  for (float& x : frames.positions) x += noise(random);  // no fit is exact
  const AffineMotion previous = fit_affine_motion(base.data(), frames, before);
  // Renumbered; vertex 1 moves from cluster 1 to 2 (1 loses one, 2 gains one); vertices 0 and 3 trade places
  // (clusters 0 and 3 keep their sizes, not their vertices); half of cluster 4 becomes a cluster of its own; 5 stays.
  Clusters after;
  after.count = 7;
  for (size_t v = 0; v < 300; ++v) after.label.push_back(uint32_t((v % 6 + 2) % 6));
  after.label[1] = 4, after.label[0] = 5, after.label[3] = 2;
  for (size_t v = 4; v < 300; v += 12) after.label[v] = 6;
  for (size_t threads : {1, 3}) {
    const AffineMotion whole = fit_affine_motion(base.data(), frames, after, threads);
    const AffineMotion refit = refit_affine_motion(base.data(), frames, after, before, previous, threads);
    ASSERT_EQ(refit.cluster_count, 7u);
    ASSERT_EQ(refit.frame_count, 7u);
    EXPECT_EQ(0, std::memcmp(refit.centroid.data(), whole.centroid.data(), whole.centroid.size() * sizeof(double)));
    ASSERT_EQ(refit.transforms.size(), whole.transforms.size());
    for (size_t f = 0; f < 7; ++f)
      for (size_t k = 0; k < 7; ++k)
        EXPECT_EQ(0, std::memcmp(refit.transform(f, k), whole.transform(f, k), 12 * sizeof(double)))
            << "frame " << f << " cluster " << k;
  }
}

// Found by the fuzz seed generator (tests/fuzz): a vertex no triangle uses became a cluster of its own, whose
// G + ρI was too small to invert (ρ³ underflowed); its motion came out NaN, and a bpvf encode converted NaN to int.
TEST(Motion, AClusterOfOneVertexGetsFiniteMotion) {
  std::mt19937 random(6);
  const std::vector<float> base = random_base(40, random);
  Clusters clusters;
  clusters.count = 2;
  for (size_t v = 0; v < 40; ++v) clusters.label.push_back(uint32_t(v == 39 ? 1 : 0));
  std::vector<std::vector<std::array<double, 12>>> maps(3);
  for (auto& frame : maps) frame = {random_map(random), random_map(random)};
  const Trajectories frames = move_by(base, clusters, maps);
  const AffineMotion motion = fit_affine_motion(base.data(), frames, clusters);
  for (double x : motion.transforms) ASSERT_TRUE(std::isfinite(x));
  EXPECT_TRUE(std::isfinite(motion_compensation_error(base.data(), frames, clusters, motion)));
  // The lone vertex is its cluster's centroid: its prediction is its own position.
  std::vector<double> predicted(120);
  for (size_t f = 0; f < 3; ++f) {
    predict_frame(base.data(), motion, own_cluster_weights(clusters), f, predicted.data());
    for (size_t c = 0; c < 3; ++c) EXPECT_NEAR(predicted[39 * 3 + c], frames.frame(f)[39 * 3 + c], 1e-6);
  }
}

TEST(Motion, WeightsRecoverASyntheticBlend) {
  // Vertices 0..99 follow cluster 0, 100..199 cluster 1, and the "seam" vertices 200..219 (labelled 0) move by
  // 0.3 of cluster 0's map plus 0.7 of cluster 1's: Eq. 3 must find those weights.
  std::mt19937 random(5);
  const std::vector<float> base = random_base(220, random);
  Clusters clusters;
  clusters.count = 2;
  for (size_t v = 0; v < 220; ++v) clusters.label.push_back(uint32_t(v >= 100 && v < 200 ? 1 : 0));
  std::vector<std::vector<std::array<double, 12>>> maps(6);
  for (auto& frame : maps) frame = {random_map(random), random_map(random)};
  Trajectories frames = move_by(base, clusters, maps);
  Clusters pure = clusters;  // the fit of the cluster maps from the unmixed vertices only
  for (size_t f = 0; f < 6; ++f)
    for (size_t v = 200; v < 220; ++v)
      for (int r = 0; r < 3; ++r) {
        double blended = 0;
        for (int k = 0; k < 2; ++k) {
          const std::array<double, 12>& m = maps[f][size_t(k)];
          blended += (k == 0 ? 0.3 : 0.7) * (m[size_t(r) * 4] * base[v * 3] + m[size_t(r) * 4 + 1] * base[v * 3 + 1] +
                                             m[size_t(r) * 4 + 2] * base[v * 3 + 2] + m[size_t(r) * 4 + 3]);
        }
        frames.positions[(f * 220 + v) * 3 + size_t(r)] = float(blended);
      }
  // Fit the maps on the pure vertices (the seam vertices would bias cluster 0's fit).
  Trajectories pure_frames;
  pure_frames.vertex_count = 200;
  pure_frames.frame_count = 6;
  for (size_t f = 0; f < 6; ++f)
    pure_frames.positions.insert(pure_frames.positions.end(), frames.positions.begin() + long(f * 660),
                                 frames.positions.begin() + long(f * 660 + 600));
  pure.label.resize(200);
  AffineMotion motion = fit_affine_motion(base.data(), pure_frames, pure);
  motion.centroid = cluster_centroids(base.data(), pure);  // same as the fit's; kept explicit for clarity
  // Every seam vertex is adjacent to one vertex of cluster 1 (vertex 100).
  std::vector<uint32_t> offset(221, 0), neighbour;
  for (size_t v = 0; v < 220; ++v) {
    if (v >= 200) neighbour.push_back(100);
    offset[v + 1] = uint32_t(neighbour.size());
  }
  const ClusterWeights weights = fit_cluster_weights(base.data(), frames, clusters, motion, offset, neighbour, 1, 4);
  for (size_t v = 200; v < 220; ++v) {
    ASSERT_EQ(weights.offset[v + 1] - weights.offset[v], 2u);
    const uint32_t i = weights.offset[v];
    EXPECT_EQ(weights.cluster[i], 0u);
    EXPECT_NEAR(weights.weight[i], 0.3, 1e-3) << v;
    EXPECT_NEAR(weights.weight[i + 1], 0.7, 1e-3) << v;
  }
  for (size_t v = 0; v < 200; ++v) {
    double sum = 0;
    for (uint32_t i = weights.offset[v]; i < weights.offset[v + 1]; ++i) sum += weights.weight[i];
    EXPECT_NEAR(sum, 1.0, 1e-9);
  }
  // Fitted over vertex ranges on threads: the same weights, in the same places, for every thread count.
  for (size_t threads : {2, 3, 8, 300}) {
    const ClusterWeights split =
        fit_cluster_weights(base.data(), frames, clusters, motion, offset, neighbour, 1, 4, threads);
    EXPECT_EQ(split.offset, weights.offset) << threads << " threads";
    EXPECT_EQ(split.cluster, weights.cluster) << threads << " threads";
    EXPECT_EQ(split.weight, weights.weight) << threads << " threads";
  }
}

// The prediction of spec/bitstream.md section 8.5, written as the specification writes it: one rounding per
// operation, in its order (each step through a volatile double, so that the compiler can neither fuse nor reorder,
// whatever the tests' flags).
void spec_prediction(const std::vector<float>& base, const AffineMotion& motion, const ClusterWeights& weights,
                     size_t frame, std::vector<double>& out) {
  for (size_t v = 0; v + 1 < weights.offset.size(); ++v) {
    volatile double s[3] = {0.0, 0.0, 0.0};
    for (uint32_t i = weights.offset[v]; i < weights.offset[v + 1]; ++i) {
      const size_t k = weights.cluster[i];
      const double* t = motion.transform(frame, k);
      double d[3];
      for (size_t a = 0; a < 3; ++a) d[a] = double(base[v * 3 + a]) - motion.centroid[k * 3 + a];
      double y[3];
      for (size_t r = 0; r < 3; ++r) {
        volatile double p0 = t[r * 4] * d[0], p1 = t[r * 4 + 1] * d[1];
        volatile double s01 = p0 + p1, p2 = t[r * 4 + 2] * d[2];
        volatile double s012 = s01 + p2;
        y[r] = s012 + t[r * 4 + 3];
      }
      for (size_t r = 0; r < 3; ++r) {
        volatile double product = weights.weight[i] * y[r];
        s[r] = s[r] + product;
      }
    }
    for (size_t r = 0; r < 3; ++r) out[v * 3 + r] = s[r];
  }
}

// FramePredictor gives the specification's doubles bit for bit, on each of its paths: two-lane vectors and, where
// the processor has it, AVX. Random transforms, weights and base positions of mixed magnitudes, so that any change of
// operation order would round differently somewhere.
TEST(Motion, FramePredictorPathsGiveTheScalarPredictionExactly) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  const size_t vertices = 500, clusters = 7, frames = 5;
  std::vector<float> base(vertices * 3);
  for (float& x : base) x = float(unit(random) * std::pow(10.0, unit(random) * 3));
  AffineMotion motion;
  motion.cluster_count = clusters, motion.frame_count = frames;
  for (size_t i = 0; i < clusters * 3; ++i) motion.centroid.push_back(unit(random) * 10);
  for (size_t i = 0; i < frames * clusters * 12; ++i) motion.transforms.push_back(unit(random) * 3);
  ClusterWeights weights;
  weights.offset.push_back(0);
  for (size_t v = 0; v < vertices; ++v) {
    const size_t count = 1 + v % 4;  // 1 to 4 clusters per vertex
    double rest = 1;
    for (size_t j = 0; j < count; ++j) {
      weights.cluster.push_back(uint32_t((v + j * 3) % clusters));
      const double w = j + 1 == count ? rest : unit(random) * 0.5;
      weights.weight.push_back(w);
      rest -= w;
    }
    weights.offset.push_back(uint32_t(weights.cluster.size()));
  }
  const FramePredictor best(base.data(), motion, weights), two_lanes(base.data(), motion, weights, false);
  std::vector<double> expected(vertices * 3), actual(vertices * 3);
  for (size_t f = 0; f < frames; ++f) {
    spec_prediction(base, motion, weights, f, expected);
    for (const FramePredictor* predictor : {&best, &two_lanes}) {
      std::fill(actual.begin(), actual.end(), 0.0);
      predictor->predict(f, actual.data());
      EXPECT_EQ(std::memcmp(actual.data(), expected.data(), expected.size() * sizeof(double)), 0)
          << "frame " << f << (predictor == &best ? " (best path)" : " (two lanes)");
    }
  }
}

TEST(Metrics, KgAndRmseOfAKnownOffset) {
  // Two vertices at x = ±1, one frame; the decoded frame moves both by 0.01 along y.
  FrameSequence original, decoded;
  original.vertex_count = decoded.vertex_count = 2;
  original.frame_count = decoded.frame_count = 1;
  original.positions = {-1, 0, 0, 1, 0, 0};
  decoded.positions = {-1, 0.01f, 0, 1, 0.01f, 0};
  ErrorAccumulator accumulator;
  accumulator.add(original, decoded);
  const ErrorMetrics metrics = accumulator.result();
  // ‖A − Ã‖ = √(2 · 0.01²), ‖A − E(A)‖ = √2: KG = 100 · 0.01 = 1 %. RMSE 0.01 over a diagonal of 2.
  EXPECT_NEAR(metrics.kg_percent, 1.0, 1e-5);
  EXPECT_NEAR(metrics.rmse_over_diagonal, 0.005, 1e-7);
  EXPECT_NEAR(metrics.max_error_over_diagonal, 0.005, 1e-7);
  EXPECT_DOUBLE_EQ(bits_per_vertex_frame(100, 2, 1), 400.0);
}

}  // namespace
}  // namespace segmorph
