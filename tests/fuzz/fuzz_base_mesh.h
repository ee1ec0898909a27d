// The base mesh the animation-stream fuzzer decodes against, and the seed streams (fuzz_seeds.cpp) are
// encoded against. Small, so that a decode takes microseconds, but with every structure the decoder treats
// specially: groups of vertices with identical base positions (a seam, a three-way split), a second connected
// piece and a vertex no triangle uses.
#pragma once

#include <cassert>
#include <cstdint>
#include <vector>

#include "../test_meshes.h"
#include "common/frame_sequence.h"

namespace segmorph::fuzz {

struct BaseMesh {
  std::vector<float> positions;     // V × 3
  std::vector<uint32_t> triangles;  // T × 3
  size_t vertex_count() const { return positions.size() / 3; }
};

// Vertex numbering of base_mesh(), for the seed animations that move the parts differently.
constexpr uint32_t kSphereVertices = 42;  // 0 .. 41: an icosphere (one subdivision), stretched along x
constexpr uint32_t kSeam = 42;            // 42 .. 45: copies of vertices 0 .. 3
constexpr uint32_t kSplit = 46;           // 46, 47: two more copies of vertex 4 (a group of three)
constexpr uint32_t kLoose = 48;           // 48 .. 50: a triangle apart from the sphere
constexpr uint32_t kIsolated = 51;        // used by no triangle
constexpr uint32_t kBaseVertices = 52;

inline BaseMesh base_mesh() {
  const FrameSequence sphere = testing::stretched_sphere(1, 1.5);
  assert(sphere.vertex_count == kSphereVertices);
  BaseMesh mesh;
  mesh.positions = sphere.positions;
  mesh.triangles = sphere.triangles;
  // A copy takes over its original in every third triangle that uses it (from the `first`-th), as a glTF seam
  // would.
  auto split = [&](uint32_t original, uint32_t copy, size_t first) {
    mesh.positions.insert(mesh.positions.end(), {sphere.positions[original * 3], sphere.positions[original * 3 + 1],
                                                 sphere.positions[original * 3 + 2]});
    size_t uses = 0;
    for (uint32_t& index : mesh.triangles)
      if (index == original && uses++ % 3 == first) index = copy;
  };
  for (uint32_t v = 0; v < 4; ++v) split(v, kSeam + v, 1);
  split(4, kSplit, 1);
  split(4, kSplit + 1, 2);
  mesh.positions.insert(mesh.positions.end(), {3.0f, 0.0f, 0.0f, 3.5f, 0.0f, 0.0f, 3.0f, 0.5f, 0.0f});
  mesh.triangles.insert(mesh.triangles.end(), {kLoose, kLoose + 1, kLoose + 2});
  mesh.positions.insert(mesh.positions.end(), {0.0f, 0.0f, 4.0f});
  assert(mesh.vertex_count() == kBaseVertices);
  return mesh;
}

}  // namespace segmorph::fuzz
