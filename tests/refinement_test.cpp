#include "encode/segmentation/refinement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "encode/segmentation/curvature.h"
#include "encode/segmentation/laplacian.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::height_field;

TEST(Curvature, CylinderHasZeroMinimumCurvatureAndAValleyIsNegative) {
  // A half cylinder of radius 10 along y, seen from outside (z = sqrt(100 − (x − 15)²)): κ_min ≈ 0 (along
  // the axis) on the interior vertices; a valley crease z = 0.5 |x − 12| has κ_min < 0 on the crease.
  const FrameSequence cylinder = height_field(30, [](int i, int) {
    const double x = (i - 15) * 0.3;
    return std::sqrt(100 - x * x);
  });
  WeldedTopology topology = weld_topology({cylinder});
  std::vector<double> curvature = minimum_curvature(welded_positions(cylinder.frame(0), topology), topology);
  for (int j = 2; j < 29; ++j)
    for (int i = 2; i < 29; ++i) EXPECT_NEAR(curvature[size_t(j * 31 + i)], 0.0, 0.02) << i << " " << j;

  const FrameSequence valley = height_field(30, [](int i, int) { return 0.5 * std::abs(i - 12); });
  topology = weld_topology({valley});
  curvature = minimum_curvature(welded_positions(valley.frame(0), topology), topology);
  for (int j = 2; j < 29; ++j) {
    EXPECT_LT(curvature[size_t(j * 31 + 12)], -0.1) << j;
    EXPECT_NEAR(curvature[size_t(j * 31 + 5)], 0.0, 1e-9) << j;
  }
}

// Both concavity scores (refinement.h), each test run once per score.
const ConcavityProfile kProfiles[] = {ConcavityProfile::boundary_vertices, ConcavityProfile::level_curves};

TEST(Refinement, LevelMovesTowardsAConcaveCrease) {
  // μ = x with one band level at x = 10; the surface is a smooth valley z = sqrt(1 + (x − 12.5)²), most
  // concave at x = 12.5. The refined level's boundary (the first column with μ >= level) must be column 12
  // or 13, nearer the valley than column 10. The level set is one open curve across the grid.
  const FrameSequence valley = height_field(30, [](int i, int) { return std::sqrt(1 + (i - 12.5) * (i - 12.5)); });
  const WeldedTopology topology = weld_topology({valley});
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const std::vector<double> positions = welded_positions(valley.frame(0), topology);
  const std::vector<double> curvature = minimum_curvature(positions, topology);
  std::vector<double> mu;
  for (size_t w = 0; w < topology.welded_count(); ++w) mu.push_back(positions[w * 3]);
  MorseBands bands;
  bands.levels = {{10.0}};
  for (ConcavityProfile profile : kProfiles) {
    SCOPED_TRACE(int(profile));
    RefinementSettings settings;
    settings.profile = profile;
    int iterations = 0;
    const MorseBands refined =
        refine_levels(positions, mu, curvature, topology, adjacency, bands, settings, &iterations);
    ASSERT_EQ(refined.levels[0].size(), 1u);
    const double column = std::ceil(refined.levels[0][0]);
    EXPECT_GE(column, 12.0);
    EXPECT_LE(column, 13.0);
    // It moved, then settled: a pass that moved the level and one that found nothing better, within the pass limit.
    EXPECT_GE(iterations, 2);
    EXPECT_LT(iterations, settings.max_iterations);
    // Settled means a fixed point: refined again, the level stays, after one pass.
    int again = 0;
    const MorseBands twice = refine_levels(positions, mu, curvature, topology, adjacency, refined, settings, &again);
    EXPECT_EQ(twice.levels[0], refined.levels[0]);
    EXPECT_EQ(again, 1);
  }
}

TEST(Refinement, LevelMovesToTheWaistOfAClosedSurface) {
  // A sphere stretched to x in [−3, 3] and pinched at x = 0.8 (its radius there halved, a smooth waist): the level
  // sets of μ = x are closed loops around it, and the one at x = 0 must move to the waist, where the surface is most
  // concave along the loop.
  FrameSequence shape = testing::stretched_sphere(4, 3.0);
  for (size_t v = 0; v < shape.vertex_count; ++v) {
    const double x = shape.positions[v * 3];
    const double pinch = 1 - 0.5 * std::exp(-(x - 0.8) * (x - 0.8) / (2 * 0.3 * 0.3));
    shape.positions[v * 3 + 1] = float(shape.positions[v * 3 + 1] * pinch);
    shape.positions[v * 3 + 2] = float(shape.positions[v * 3 + 2] * pinch);
  }
  const WeldedTopology topology = weld_topology({shape});
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const std::vector<double> positions = welded_positions(shape.frame(0), topology);
  const std::vector<double> curvature = minimum_curvature(positions, topology);
  std::vector<double> mu;
  for (size_t w = 0; w < topology.welded_count(); ++w) mu.push_back(positions[w * 3]);
  MorseBands bands;
  bands.levels = {{0.0}};
  for (ConcavityProfile profile : kProfiles) {
    SCOPED_TRACE(int(profile));
    RefinementSettings settings;
    settings.profile = profile;
    const MorseBands refined = refine_levels(positions, mu, curvature, topology, adjacency, bands, settings);
    EXPECT_NEAR(refined.levels[0][0], 0.8, 0.2);
  }
}

// The boundary-vertex refinement as first written: every candidate level scans every vertex of its component.
std::vector<std::vector<double>> levels_by_whole_scans(const std::vector<double>& mu,
                                                       const std::vector<double>& curvature,
                                                       const WeldedTopology& topology,
                                                       const VertexAdjacency& adjacency, MorseBands bands,
                                                       const RefinementSettings& settings) {
  const size_t count = topology.welded_count();
  std::vector<double> low(topology.component_count, INFINITY), high(topology.component_count, -INFINITY);
  for (size_t w = 0; w < count; ++w) {
    low[topology.component[w]] = std::min(low[topology.component[w]], mu[w]);
    high[topology.component[w]] = std::max(high[topology.component[w]], mu[w]);
  }
  auto concavity = [&](double level, size_t c) {
    std::vector<uint32_t> boundary;
    for (uint32_t v = 0; v < count; ++v) {
      if (topology.component[v] != c || mu[v] < level) continue;
      for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i)
        if (mu[adjacency.neighbour[i]] < level) {
          boundary.push_back(v);
          break;
        }
    }
    if (boundary.empty()) return double(INFINITY);
    std::vector<int> slot(count, -1);
    std::vector<double> profile(boundary.size());
    for (size_t b = 0; b < boundary.size(); ++b) slot[boundary[b]] = int(b), profile[b] = curvature[boundary[b]];
    for (int pass = 0; pass < settings.smoothing; ++pass) {
      std::vector<double> next(profile.size());
      for (size_t b = 0; b < boundary.size(); ++b) {
        double sum = profile[b];
        int n = 1;
        for (uint32_t i = adjacency.offset[boundary[b]]; i < adjacency.offset[boundary[b] + 1]; ++i)
          if (slot[adjacency.neighbour[i]] >= 0) sum += profile[size_t(slot[adjacency.neighbour[i]])], ++n;
        next[b] = sum / n;
      }
      profile = next;
    }
    return *std::min_element(profile.begin(), profile.end());
  };
  for (int iteration = 0, moved = 1; moved && iteration < settings.max_iterations; ++iteration) {
    moved = 0;
    for (size_t c = 0; c < topology.component_count; ++c) {
      std::vector<double>& levels = bands.levels[c];
      for (size_t j = 0; j < levels.size(); ++j) {
        const double below = j > 0 ? levels[j - 1] : low[c], above = j + 1 < levels.size() ? levels[j + 1] : high[c];
        const double from = levels[j] - settings.window * (levels[j] - below);
        const double to = levels[j] + settings.window * (above - levels[j]);
        double best = levels[j], best_score = concavity(best, c);
        for (int k = 0; k < settings.candidates; ++k) {
          const double candidate = from + (to - from) * k / std::max(settings.candidates - 1, 1);
          const double score = concavity(candidate, c);
          if (score < best_score - 1e-12 * std::fabs(best_score)) best = candidate, best_score = score;
        }
        if (best != levels[j]) levels[j] = best, moved = 1;
      }
    }
  }
  return bands.levels;
}

// The candidates of a window look only at the vertices that can be on the boundary of a level in it: the levels are
// those of scanning every vertex for every candidate. Two pinched spheres side by side (two components), μ = x with
// noise, five levels each, at several windows.
TEST(Refinement, BoundaryVerticesFromTheWindowsBandAreThoseOfTheWholeComponent) {
  FrameSequence shape = testing::stretched_sphere(4, 3.0);
  const size_t one = shape.vertex_count;
  for (size_t v = 0; v < one; ++v) {
    const double x = shape.positions[v * 3];
    const double pinch = 1 - 0.5 * std::exp(-(x - 0.8) * (x - 0.8) / (2 * 0.3 * 0.3));
    shape.positions[v * 3 + 1] = float(shape.positions[v * 3 + 1] * pinch);
    shape.positions[v * 3 + 2] = float(shape.positions[v * 3 + 2] * pinch);
  }
  const std::vector<uint32_t> triangles = shape.triangles;
  for (size_t v = 0; v < one; ++v)
    for (int a = 0; a < 3; ++a) shape.positions.push_back(shape.positions[v * 3 + size_t(a)] + (a == 1 ? 5.0f : 0.0f));
  for (uint32_t t : triangles) shape.triangles.push_back(t + uint32_t(one));
  shape.vertex_count = 2 * one;
  const WeldedTopology topology = weld_topology({shape});
  ASSERT_EQ(topology.component_count, 2u);
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const std::vector<double> positions = welded_positions(shape.frame(0), topology);
  const std::vector<double> curvature = minimum_curvature(positions, topology);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> noise(-0.05, 0.05);
  std::vector<double> mu;
  for (size_t w = 0; w < topology.welded_count(); ++w) mu.push_back(positions[w * 3] + noise(random));
  MorseBands bands;
  bands.levels = {{-2.0, -1.0, 0.0, 1.0, 2.0}, {-1.5, -0.5, 0.3, 1.2, 2.4}};
  for (double window : {0.25, 0.5, 0.9}) {
    SCOPED_TRACE(window);
    RefinementSettings settings;
    settings.window = window;
    const MorseBands refined = refine_levels(positions, mu, curvature, topology, adjacency, bands, settings);
    EXPECT_EQ(refined.levels, levels_by_whole_scans(mu, curvature, topology, adjacency, bands, settings));
    EXPECT_NE(refined.levels, bands.levels);  // levels moved
  }
}

TEST(Refinement, MotionRefinementMovesMislabelledVerticesHome) {
  // Two halves of a grid move by different rotations; the initial split is off by two columns. Motion
  // refinement must restore the true split, and E(Π) must fall to float rounding.
  const FrameSequence grid = height_field(20, [](int, int) { return 0.0; });
  const WeldedTopology topology = weld_topology({grid});
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const size_t vertex_count = topology.welded_count();
  Clusters truth, initial;
  truth.count = initial.count = 2;
  for (size_t v = 0; v < vertex_count; ++v) {
    truth.label.push_back(grid.positions[v * 3] < 10 ? 0u : 1u);
    initial.label.push_back(grid.positions[v * 3] < 8 ? 0u : 1u);
  }
  Trajectories frames;
  frames.vertex_count = vertex_count;
  frames.frame_count = 4;
  for (int f = 0; f < 4; ++f)
    for (size_t v = 0; v < vertex_count; ++v) {
      const double angle = (truth.label[v] ? 0.3 : -0.2) * f;
      const double x = grid.positions[v * 3] - 10, y = grid.positions[v * 3 + 1];
      frames.positions.insert(frames.positions.end(),
                              {float(x * std::cos(angle) + 10), float(y), float(x * std::sin(angle))});
    }
  const float* base = frames.frame(0);
  const double before = motion_compensation_error(base, frames, initial, fit_affine_motion(base, frames, initial));
  int iterations = 0;
  AffineMotion motion;
  const Clusters refined = refine_by_motion(initial, base, frames, adjacency, 20, &iterations, 1, &motion);
  const AffineMotion fitted = fit_affine_motion(base, frames, refined);
  const double after = motion_compensation_error(base, frames, refined, fitted);
  // The motion it hands back is the fit of the clusters it returns, bit for bit: after the round that moved nothing,
  // and when the rounds run out while vertices still move (then a fit of its own).
  EXPECT_EQ(motion.transforms, fitted.transforms);
  EXPECT_EQ(motion.centroid, fitted.centroid);
  ASSERT_GE(iterations, 2);
  ASSERT_LT(iterations, 20);  // it settled: the motion handed back is the last round's
  AffineMotion cut_short;
  const Clusters moving = refine_by_motion(initial, base, frames, adjacency, 1, nullptr, 1, &cut_short);
  EXPECT_NE(moving.label, initial.label);
  EXPECT_EQ(cut_short.transforms, fit_affine_motion(base, frames, moving).transforms);
  EXPECT_NE(cut_short.transforms, fit_affine_motion(base, frames, initial).transforms);
  EXPECT_GT(before, 1e-4);
  EXPECT_LT(after, 1e-10);
  ASSERT_EQ(refined.count, 2u);
  for (size_t v = 0; v < vertex_count; ++v)
    if (std::fabs(grid.positions[v * 3] - 10) > 0.5) {
      EXPECT_EQ(refined.label[v] == refined.label[0], truth.label[v] == 0) << v;
    }
}

}  // namespace
}  // namespace segmorph
