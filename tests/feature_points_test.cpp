#include "encode/segmentation/feature_points.h"

#include <gtest/gtest.h>

namespace segmorph {
namespace {

// A path of n vertices one unit apart on the x axis.
struct Path {
  std::vector<double> positions;
  VertexAdjacency adjacency;
  std::vector<uint32_t> vertices;
};

Path path(uint32_t n) {
  Path p;
  p.adjacency.offset.push_back(0);
  for (uint32_t v = 0; v < n; ++v) {
    p.positions.insert(p.positions.end(), {double(v), 0.0, 0.0});
    if (v > 0) p.adjacency.neighbour.push_back(v - 1);
    if (v + 1 < n) p.adjacency.neighbour.push_back(v + 1);
    p.adjacency.offset.push_back(uint32_t(p.adjacency.neighbour.size()));
    p.vertices.push_back(v);
  }
  return p;
}

TEST(FeaturePoints, FarthestPointsOfAPathAreItsEnds) {
  const Path p = path(9);
  const std::array<uint32_t, 2> ends = farthest_points(p.positions, p.adjacency, {4, 0, 1, 2, 3, 5, 6, 7, 8});
  EXPECT_EQ(std::min(ends[0], ends[1]), 0u);
  EXPECT_EQ(std::max(ends[0], ends[1]), 8u);
}

TEST(FeaturePoints, MaximaWithinTheRadiusGiveWayToTheLargest) {
  const Path p = path(9);
  //                          0    1    2    3    4    5    6    7    8
  const std::vector<double> f{0.0, 5.0, 1.0, 4.0, 0.0, 0.0, 2.0, 0.0, 3.0};
  // Every ring maximum (1, 3, 6, 8) survives a radius below two edges.
  EXPECT_EQ(maxima(f, p.vertices, p.positions, p.adjacency, 1.5), (std::vector<uint32_t>{1, 3, 6, 8}));
  // Within two edges, 3 gives way to 1 and 6 to 8.
  EXPECT_EQ(maxima(f, p.vertices, p.positions, p.adjacency, 2.0), (std::vector<uint32_t>{1, 8}));
}

TEST(FeaturePoints, EqualMaximaGoToTheLowestIndex) {
  const Path p = path(5);
  const std::vector<double> f{0.0, 1.0, 0.0, 1.0, 0.0};
  EXPECT_EQ(maxima(f, p.vertices, p.positions, p.adjacency, 1.0), (std::vector<uint32_t>{1, 3}));
  EXPECT_EQ(maxima(f, p.vertices, p.positions, p.adjacency, 2.0), (std::vector<uint32_t>{1}));
}

TEST(FeaturePoints, OnlyTipsBothFunctionsFindAreKept) {
  const Path p = path(9);
  const std::vector<double> f1{3.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0};  // maxima 0, 4, 8
  const std::vector<double> f2{0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0};  // maxima 1, 8
  EXPECT_EQ(feature_points(f1, f2, p.vertices, p.positions, p.adjacency, 1.0, {3, 5}),
            (std::vector<uint32_t>{0, 8}));
  // With no tip in common, the two farthest points stand in.
  const std::vector<double> f3{0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 5.0, 4.0};  // maximum 6 only
  EXPECT_EQ(feature_points(f1, f3, p.vertices, p.positions, p.adjacency, 1.0, {3, 5}),
            (std::vector<uint32_t>{3, 5}));
}

}  // namespace
}  // namespace segmorph
