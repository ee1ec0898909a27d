#include "encode/segmentation/refinement.h"

#include <gtest/gtest.h>

#include <cmath>

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
