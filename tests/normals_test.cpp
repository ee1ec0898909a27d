#include "decode/normals.h"

#include <gtest/gtest.h>

#include <cmath>

namespace segmorph {
namespace {

// A closed octahedron: 6 vertices, 8 triangles, outward winding.
FrameSequence octahedron() {
  FrameSequence clip;
  clip.vertex_count = 6;
  clip.frame_count = 1;
  clip.positions = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  clip.times = {0};
  clip.triangles = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  return clip;
}

TEST(Normals, GeometricNormalsOfAnOctahedronPointOutward) {
  const FrameSequence clip = octahedron();
  const WeldedTopology topology = weld_topology({clip});
  const std::vector<double> normals = welded_vertex_normals(clip.positions.data(), topology);
  for (size_t v = 0; v < 6; ++v) {
    const double* n = &normals[topology.welded_index[v] * 3];
    const float* p = &clip.positions[v * 3];
    EXPECT_GT(n[0] * p[0] + n[1] * p[1] + n[2] * p[2], 0) << "vertex " << v;
  }
}

TEST(Normals, RigidRotationTurnsAuthoredNormalsWithTheSurface) {
  const FrameSequence clip = octahedron();
  const WeldedTopology topology = weld_topology({clip});
  // Authored normals deliberately not the geometric ones: tilted towards +z.
  std::vector<float> rest_normals(18);
  for (size_t v = 0; v < 6; ++v) {
    double n[3] = {clip.positions[v * 3], clip.positions[v * 3 + 1], clip.positions[v * 3 + 2] + 0.5};
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int c = 0; c < 3; ++c) rest_normals[v * 3 + size_t(c)] = float(n[c] / length);
  }
  // Rotate the whole shape by 90° about z: (x, y, z) -> (-y, x, z).
  std::vector<float> rotated(18), expected(18), out(18);
  for (size_t v = 0; v < 6; ++v) {
    rotated[v * 3] = -clip.positions[v * 3 + 1];
    rotated[v * 3 + 1] = clip.positions[v * 3];
    rotated[v * 3 + 2] = clip.positions[v * 3 + 2];
    expected[v * 3] = -rest_normals[v * 3 + 1];
    expected[v * 3 + 1] = rest_normals[v * 3];
    expected[v * 3 + 2] = rest_normals[v * 3 + 2];
  }
  deform_normals(clip.positions.data(), rest_normals.data(), rotated.data(), topology, out.data());
  // The octahedron's vertex normals are along its axes, so the smallest rotation between them is the rigid one
  // for the four equatorial vertices; the poles' normal does not change direction, so theirs stays as is.
  for (size_t v = 0; v < 4; ++v)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[v * 3 + size_t(c)], expected[v * 3 + size_t(c)], 1e-6) << v;
  for (size_t v = 4; v < 6; ++v)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[v * 3 + size_t(c)], rest_normals[v * 3 + size_t(c)], 1e-6) << v;
}

TEST(Normals, UnmovedSurfaceKeepsItsNormalsAndOutputIsUnit) {
  const FrameSequence clip = octahedron();
  const WeldedTopology topology = weld_topology({clip});
  std::vector<float> rest_normals = {2, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1}, out(18);
  deform_normals(clip.positions.data(), rest_normals.data(), clip.positions.data(), topology, out.data());
  EXPECT_FLOAT_EQ(out[0], 1.0f);  // normalized
  for (size_t i = 3; i < 18; ++i) EXPECT_FLOAT_EQ(out[i], rest_normals[i]);
}

TEST(Normals, VertexWithoutTrianglesKeepsItsNormal) {
  FrameSequence clip = octahedron();
  clip.vertex_count = 7;
  clip.positions.insert(clip.positions.end(), {3, 3, 3});
  const WeldedTopology topology = weld_topology({clip});
  std::vector<float> rest_normals(21, 0), moved = clip.positions, out(21);
  rest_normals[18 + 1] = 1;
  moved[18] = 7;
  deform_normals(clip.positions.data(), rest_normals.data(), moved.data(), topology, out.data());
  EXPECT_EQ(out[19], 1.0f);
}

}  // namespace
}  // namespace segmorph
