#include "common/topology.h"

#include <gtest/gtest.h>

namespace segmorph {
namespace {

// One clip of V vertices with the given frames (each frame V × 3 floats) and triangles.
FrameSequence make_clip(size_t vertex_count, const std::vector<std::vector<float>>& frames,
                        const std::vector<uint32_t>& triangles) {
  FrameSequence clip;
  clip.vertex_count = vertex_count;
  clip.frame_count = frames.size();
  for (size_t f = 0; f < frames.size(); ++f) {
    clip.positions.insert(clip.positions.end(), frames[f].begin(), frames[f].end());
    clip.times.push_back(float(f));
  }
  clip.triangles = triangles;
  return clip;
}

TEST(Topology, SeamCopiesWeldAndKeepTheirOrder) {
  // Two triangles sharing edge (1,2), the shared corners split as a UV seam would (vertices 3 and 4 copy 1 and 2).
  const std::vector<float> frame = {0, 0, 0, 1, 0, 0, 0, 1, 0, /*copies*/ 1, 0, 0, 0, 1, 0, /*apex*/ 1, 1, 0};
  const FrameSequence clip = make_clip(6, {frame}, {0, 1, 2, 3, 5, 4});
  const WeldedTopology topology = weld_topology({clip});
  ASSERT_EQ(topology.welded_count(), 4u);
  EXPECT_EQ(topology.welded_index, (std::vector<uint32_t>{0, 1, 2, 1, 2, 3}));
  EXPECT_EQ(topology.representative, (std::vector<uint32_t>{0, 1, 2, 5}));
  EXPECT_EQ(topology.triangles, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(topology.component_count, 1u);
}

TEST(Topology, PointsThatTouchOnlyAtRestStayApart) {
  // Vertices 1 and 3 coincide in frame 0 but separate in frame 1 (closed lips that open).
  const std::vector<float> rest = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 2, 0, 0, 1, 1, 0};
  std::vector<float> open = rest;
  open[3 * 3 + 1] = -0.5f;
  const FrameSequence clip = make_clip(6, {rest, open}, {0, 1, 2, 3, 4, 5});
  const WeldedTopology topology = weld_topology({clip});
  EXPECT_EQ(topology.welded_count(), 6u);
  EXPECT_EQ(topology.component_count, 2u);
}

TEST(Topology, WeldingLooksAtEveryClip) {
  const std::vector<float> frame = {0, 0, 0, 1, 0, 0, 1, 0, 0};
  std::vector<float> other = frame;
  other[2 * 3 + 2] = 1;  // vertex 2 leaves vertex 1 in the second clip only
  const std::vector<uint32_t> none;
  EXPECT_EQ(weld_topology({make_clip(3, {frame}, none)}).welded_count(), 2u);
  EXPECT_EQ(weld_topology({make_clip(3, {frame}, none), make_clip(3, {other}, none)}).welded_count(), 3u);
}

TEST(Topology, NegativeZeroWeldsWithZero) {
  const FrameSequence clip = make_clip(2, {{0.0f, 1, 2, -0.0f, 1, 2}}, {});
  EXPECT_EQ(weld_topology({clip}).welded_count(), 1u);
}

TEST(Topology, CollapsedTrianglesAreDroppedAndIsolatedVerticesAreComponents) {
  // Triangle soup: vertices 0..2 form a triangle; 3 and 4 are the same point, so triangle (3,4,5) collapses;
  // vertex 6 is used by no triangle.
  const std::vector<float> frame = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 5, 5, 5, 6, 5, 5, 9, 9, 9};
  const FrameSequence clip = make_clip(7, {frame}, {0, 1, 2, 3, 4, 5});
  const WeldedTopology topology = weld_topology({clip});
  EXPECT_EQ(topology.welded_count(), 6u);
  EXPECT_EQ(topology.triangles.size(), 3u);
  // {0,1,2}, {3/4}, {5}, {6}: the collapsed triangle connects nothing.
  EXPECT_EQ(topology.component_count, 4u);
  EXPECT_EQ(topology.component[topology.welded_index[0]], topology.component[topology.welded_index[2]]);
  EXPECT_NE(topology.component[topology.welded_index[3]], topology.component[topology.welded_index[5]]);
}

TEST(Topology, ManyIdenticalVerticesWeldToOne) {
  // All vertices at one point: one welded vertex, found without comparing every pair.
  const size_t count = 200000;
  const FrameSequence clip = make_clip(count, {std::vector<float>(count * 3, 1.5f)}, {});
  const WeldedTopology topology = weld_topology({clip});
  EXPECT_EQ(topology.welded_count(), 1u);
  EXPECT_EQ(topology.component_count, 1u);
}

}  // namespace
}  // namespace segmorph
