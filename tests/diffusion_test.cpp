#include "encode/segmentation/diffusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

#include "encode/segmentation/feature_points.h"
#include "encode/segmentation/laplacian.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::stretched_sphere;

TEST(Diffusion, FeaturePointsOfAnElongatedShapeAreItsTips) {
  const FrameSequence clip = stretched_sphere(3, 4.0);  // 642 vertices, from x = -4 to 4
  const WeldedTopology topology = weld_topology({clip});
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const std::vector<double> positions = welded_positions(clip.frame(0), topology);
  MorseFunction morse;
  ASSERT_TRUE(diffusion_morse_function(positions, topology, adjacency, DiffusionSettings(), morse).ok());

  // The two farthest points are the tips.
  ASSERT_EQ(morse.farthest_points.size(), 1u);
  const double x1 = positions[morse.farthest_points[0][0] * 3], x2 = positions[morse.farthest_points[0][1] * 3];
  EXPECT_GT(std::fabs(x1), 3.5);
  EXPECT_GT(std::fabs(x2), 3.5);
  EXPECT_LT(x1 * x2, 0);
  // The feature points are at the tips: both ends found, nothing in the middle.
  bool left = false, right = false;
  for (uint32_t p : morse.feature_points) {
    EXPECT_GT(std::fabs(positions[p * 3]), 3.5) << "feature point at x = " << positions[p * 3];
    left = left || positions[p * 3] < 0;
    right = right || positions[p * 3] > 0;
  }
  EXPECT_TRUE(left && right);
  // μ's level sets cut the shape across: on a thin slice x in [2, 2.25] μ varies by a small part of its range.
  double low = INFINITY, high = -INFINITY, slice_low = INFINITY, slice_high = -INFINITY;
  for (size_t w = 0; w < positions.size() / 3; ++w) {
    low = std::min(low, morse.mu[w]);
    high = std::max(high, morse.mu[w]);
    if (positions[w * 3] >= 2.0 && positions[w * 3] <= 2.25) {
      slice_low = std::min(slice_low, morse.mu[w]);
      slice_high = std::max(slice_high, morse.mu[w]);
    }
  }
  EXPECT_LT(slice_high - slice_low, 0.15 * (high - low));
}

// The shortest edge paths by relaxing every edge until nothing changes (Bellman-Ford): a reference that shares no code
// with the Dijkstra search. Distances beyond `limit` are infinite.
std::vector<double> relaxed_distances(const std::vector<double>& positions, const VertexAdjacency& adjacency,
                                      uint32_t source, double limit) {
  std::vector<double> distance(adjacency.offset.size() - 1, INFINITY);
  distance[source] = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (uint32_t u = 0; u < distance.size(); ++u)
      for (uint32_t i = adjacency.offset[u]; i < adjacency.offset[u + 1]; ++i) {
        const uint32_t w = adjacency.neighbour[i];
        const double dx = positions[u * 3] - positions[w * 3], dy = positions[u * 3 + 1] - positions[w * 3 + 1],
                     dz = positions[u * 3 + 2] - positions[w * 3 + 2];
        const double candidate = distance[u] + std::sqrt(dx * dx + dy * dy + dz * dz);
        if (candidate < distance[w] && candidate <= limit) distance[w] = candidate, changed = true;
      }
  }
  return distance;
}

// edge_path_distances gives the shortest edge paths within the limit (and nothing beyond it); GeodesicBall the same
// distances, bit for bit, call after call on one instance.
TEST(Diffusion, GeodesicBallsMatchTheWholeMeshSearch) {
  const FrameSequence clip = stretched_sphere(3, 2.0);
  const WeldedTopology topology = weld_topology({clip});
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const std::vector<double> positions = welded_positions(clip.frame(0), topology);
  GeodesicBall ball(positions, adjacency);
  for (const auto& [source, limit] : {std::pair(0u, 0.5), std::pair(100u, 1.5), std::pair(7u, 0.2),
                                      std::pair(300u, double(INFINITY)), std::pair(0u, 0.5)}) {
    const std::vector<double> whole = edge_path_distances(positions, adjacency, source, limit);
    const std::vector<double> reference = relaxed_distances(positions, adjacency, source, limit);
    for (size_t v = 0; v < whole.size(); ++v)
      EXPECT_EQ(whole[v], reference[v]) << "source " << source << " vertex " << v;
    const std::vector<uint32_t>& reached = ball.reach(source, limit);
    ASSERT_FALSE(reached.empty());
    EXPECT_EQ(reached.front(), source);
    size_t within = 0;
    for (size_t v = 0; v < whole.size(); ++v) {
      within += std::isfinite(whole[v]);
      EXPECT_EQ(ball.distance(uint32_t(v)), whole[v]) << "source " << source << " vertex " << v;
    }
    EXPECT_EQ(reached.size(), within) << "source " << source;
    EXPECT_GT(within, 1u);
    // A search told to stop at a vertex within the limit stops there; at one beyond it, it reaches all the rest.
    const uint32_t inside = reached.back();
    uint32_t outside = source;
    for (size_t v = 0; v < whole.size(); ++v)
      if (!std::isfinite(whole[v])) outside = uint32_t(v);
    EXPECT_EQ(ball.reach(source, limit, [&](uint32_t v) { return v == inside; }).back(), inside);
    EXPECT_TRUE(ball.stopped());
    if (outside != source) {
      EXPECT_EQ(ball.reach(source, limit, [&](uint32_t v) { return v == outside; }).size(), within);
      EXPECT_FALSE(ball.stopped());
    }
  }
}

// maxima() (its searches end at the first larger vertex) against its definition written with whole-mesh searches (the
// code it replaced): f with many ties (values in a few levels) and radii from less than an edge to the whole mesh.
TEST(Diffusion, MaximaAreTheDefinitions) {
  const FrameSequence clip = stretched_sphere(3, 2.0);
  const WeldedTopology topology = weld_topology({clip});
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  const std::vector<double> positions = welded_positions(clip.frame(0), topology);
  const size_t count = positions.size() / 3;
  std::vector<uint32_t> vertices(count);
  for (size_t v = 0; v < count; ++v) vertices[v] = uint32_t(v);
  std::mt19937 random(5);
  for (const int levels : {3, 1000}) {
    std::vector<double> f(count);
    for (double& value : f) value = double(random() % unsigned(levels));
    for (const double radius : {0.05, 0.3, 1.0, double(INFINITY)}) {
      std::vector<uint32_t> expected;
      for (uint32_t v : vertices) {
        bool ring_maximum = true;  // the 1-ring first, as maxima() does (a longer edge than the radius counts too)
        for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
          const uint32_t u = adjacency.neighbour[i];
          ring_maximum = ring_maximum && (f[u] < f[v] || (f[u] == f[v] && v < u));
        }
        if (!ring_maximum) continue;
        const std::vector<double> near = edge_path_distances(positions, adjacency, v, radius);
        bool maximum = true;
        for (uint32_t u : vertices)
          if (near[u] <= radius && u != v && (f[u] > f[v] || (f[u] == f[v] && u < v))) maximum = false;
        if (maximum) expected.push_back(v);
      }
      EXPECT_EQ(maxima(f, vertices, positions, adjacency, radius), expected) << levels << " levels, radius " << radius;
      EXPECT_FALSE(expected.empty());
    }
  }
}

TEST(Diffusion, ComponentsAreTreatedSeparately) {
  // Two shapes side by side: each gets its own farthest points, feature points and μ.
  FrameSequence a = stretched_sphere(2, 3.0), b = stretched_sphere(2, 3.0);
  FrameSequence both = a;
  both.vertex_count = a.vertex_count * 2;
  for (size_t i = 0; i < b.positions.size(); ++i) both.positions.push_back(b.positions[i] + (i % 3 == 1 ? 10.0f : 0.0f));
  for (uint32_t index : b.triangles) both.triangles.push_back(index + uint32_t(a.vertex_count));
  const WeldedTopology topology = weld_topology({both});
  ASSERT_EQ(topology.component_count, 2u);
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  MorseFunction morse;
  ASSERT_TRUE(diffusion_morse_function(welded_positions(both.frame(0), topology), topology, adjacency,
                                       DiffusionSettings(), morse).ok());
  ASSERT_EQ(morse.farthest_points.size(), 2u);
  EXPECT_NE(topology.component[morse.farthest_points[0][0]], topology.component[morse.farthest_points[1][0]]);
  // The second shape is the first moved by 10 along y: the same μ, vertex for vertex, up to the float
  // rounding of the moved positions (about 1e-6 relative).
  for (size_t w = 0; w < a.vertex_count; ++w)
    EXPECT_NEAR(morse.mu[topology.welded_index[w]], morse.mu[topology.welded_index[w + a.vertex_count]],
                1e-5 * morse.mu[topology.welded_index[w]]);
}

}  // namespace
}  // namespace segmorph
