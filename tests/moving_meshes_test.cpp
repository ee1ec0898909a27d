// Meshes that move with their nodes (converter/encoding/moving_meshes.h): which meshes qualify, and their Draco
// encode: positions within the quantization step, joints exact, weights as normalized bytes summing to 255.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "accessor.h"
#include "decoding/decode_file.h"
#include "encoding/moving_meshes.h"
#include "gltf_builder.h"

namespace segmorph {
namespace {

using test::GltfBuilder;

const std::vector<uint32_t> kJoints = {0, 1, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 1, 0, 0, 0};
const std::vector<float> kWeights = {0.5f, 0.25f, 0.25f, 0, 1, 0, 0, 0, 0.3f, 0.3f, 0.4f, 0, 0.9f, 0.1f, 0, 0};

// Two triangles of a unit square, with indices.
int square_mesh(GltfBuilder& b) {
  const int position = b.add_vec3({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  b.model.accessors[size_t(position)].minValues = {0, 0, 0};
  b.model.accessors[size_t(position)].maxValues = {1, 1, 0};
  const int indices = b.add_uints({0, 1, 2, 0, 2, 3}, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  return b.add_mesh(position, indices);
}

// A scene: `moved` (a rigid node a translation channel moves, child of an animated root), `still` (nothing moves it),
// `morphed` (a moved node whose mesh has a morph target) and `skinned` (node 4, whose mesh is skinned by joint 0).
struct Scene {
  GltfBuilder b;
  int moved_mesh = -1, still_mesh = -1, morphed_mesh = -1, skinned_mesh = -1, skinned_node = -1;
};

void build(Scene& s) {
  GltfBuilder& b = s.b;
  const int root = b.add_node();
  b.add_root(root);
  s.moved_mesh = square_mesh(b);
  s.still_mesh = square_mesh(b);
  s.morphed_mesh = square_mesh(b);
  s.skinned_mesh = square_mesh(b);
  const int moved = b.add_mesh_node(s.moved_mesh), still = b.add_mesh_node(s.still_mesh);
  const int morphed = b.add_mesh_node(s.morphed_mesh);
  b.add_child(root, moved);
  b.add_root(still);
  b.add_child(root, morphed);
  b.add_target(s.morphed_mesh, {{"POSITION", b.add_vec3({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1})}});
  const int skin = b.add_skin({root, moved});
  s.skinned_node = b.add_mesh_node(s.skinned_mesh, skin);
  b.add_root(s.skinned_node);
  const int joints = b.add_uints(kJoints, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
  b.set_skin_attributes(s.skinned_mesh, 0, joints, b.add_vec4(kWeights));
  const int animation = b.add_animation("move");
  b.add_channel(animation, root, "translation", {0, 1}, {0, 0, 0, 1, 0, 0});
}

TEST(MovingMeshes, RigidlyMovedAndKeptSkinnedMeshesQualify) {
  Scene s;
  build(s);
  std::vector<bool> meshes = moving_meshes(s.b.model, {});
  EXPECT_TRUE(meshes[size_t(s.moved_mesh)]);
  EXPECT_FALSE(meshes[size_t(s.still_mesh)]);    // nothing moves it
  EXPECT_FALSE(meshes[size_t(s.morphed_mesh)]);  // morph targets need a stream
  EXPECT_FALSE(meshes[size_t(s.skinned_mesh)]);  // its skin is not kept
  meshes = moving_meshes(s.b.model, {s.skinned_node});
  EXPECT_TRUE(meshes[size_t(s.skinned_mesh)]);
}

TEST(MovingMeshes, DracoKeepsPositionsJointsAndWeights) {
  Scene s;
  build(s);
  tinygltf::Model& model = s.b.model;
  std::vector<bool> meshes = moving_meshes(model, {s.skinned_node});
  DracoSettings draco;
  draco.position_bits = 10;
  MovingMeshReport report;
  ASSERT_TRUE(compress_moving_meshes(model, meshes, draco, 0.01, 1.0, 1, report).ok());
  EXPECT_EQ(report.primitives, 2u);
  EXPECT_GT(report.bytes, 0u);
  const tinygltf::Primitive& coded = model.meshes[size_t(s.skinned_mesh)].primitives[0];
  EXPECT_EQ(coded.extensions.count("KHR_draco_mesh_compression"), 1u);
  const tinygltf::Accessor& position = model.accessors[size_t(coded.attributes.at("POSITION"))];
  EXPECT_EQ(position.bufferView, -1);  // the data is in the Draco mesh
  EXPECT_EQ(position.maxValues, (std::vector<double>{1, 1, 0}));
  EXPECT_EQ(model.meshes[size_t(s.still_mesh)].primitives[0].extensions.count("KHR_draco_mesh_compression"), 0u);

  ASSERT_TRUE(decode_draco_primitives(model).ok());
  const tinygltf::Primitive& decoded = model.meshes[size_t(s.skinned_mesh)].primitives[0];
  std::vector<float> positions, weights;
  ASSERT_TRUE(read_floats(model, decoded.attributes.at("POSITION"), "test", positions).ok());
  ASSERT_TRUE(read_floats(model, decoded.attributes.at("WEIGHTS_0"), "test", weights).ok());
  ASSERT_EQ(positions.size(), 12u);
  ASSERT_EQ(weights.size(), 16u);
  // The vertices may come back in another order: each original corner has a decoded one within the step (1 / 2^10).
  for (float x : {0.0f, 1.0f})
    for (float y : {0.0f, 1.0f}) {
      double nearest = INFINITY;
      for (size_t i = 0; i < 4; ++i)
        nearest = std::min(nearest, std::hypot(double(positions[i * 3]) - x, double(positions[i * 3 + 1]) - y,
                                               double(positions[i * 3 + 2])));
      EXPECT_LE(nearest, std::sqrt(2.0) / 1024) << x << " " << y;
    }
  // Each vertex's joints exact and its weights as normalized bytes of sum 255, in whatever vertex order.
  std::vector<uint32_t> joints;
  ASSERT_TRUE(read_uints(model, decoded.attributes.at("JOINTS_0"), "test", joints).ok());
  auto rows = [](const std::vector<uint32_t>& j, const std::vector<float>& w) {
    std::vector<std::vector<long>> out(4);
    for (size_t v = 0; v < 4; ++v)
      for (size_t k = 0; k < 4; ++k)
        out[v].insert(out[v].end(), {long(j[v * 4 + k]), std::lround(w[v * 4 + k] * 100)});
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(rows(joints, weights), rows(kJoints, kWeights));
  for (size_t v = 0; v < 4; ++v) {
    int sum = 0;
    for (size_t j = 0; j < 4; ++j) {
      const double scaled = weights[v * 4 + j] * 255.0;
      EXPECT_NEAR(scaled, std::round(scaled), 1e-3) << "a normalized byte";
      sum += int(std::lround(scaled));
    }
    EXPECT_EQ(sum, 255) << v;
  }
}

}  // namespace
}  // namespace segmorph
