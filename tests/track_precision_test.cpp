// How finely encode quantizes a file's node tracks (converter/encoding/track_precision.h, coded by
// extensions/track_streams.h): the scene's diagonal, and steps that keep each track's displacement within the distance
// asked, checked on the decoded tracks.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "accessor.h"
#include "encoding/track_precision.h"
#include "gltf_builder.h"
#include "track_streams.h"

namespace segmorph {
namespace {

using test::GltfBuilder;

// A mesh whose bounds are [0, 1]³, on `child`, a child of `root` scaled by `parent_scale`; one animation that moves
// the child's translation, rotation and scale.
struct Scene {
  GltfBuilder gltf;
  int root = -1, child = -1;
  std::vector<float> translation, rotation, scale;
};

void build(Scene& scene, double parent_scale) {
  GltfBuilder& b = scene.gltf;
  const int position = b.add_vec3({0, 0, 0, 1, 0, 0, 0, 1, 1});
  b.model.accessors[size_t(position)].minValues = {0, 0, 0};
  b.model.accessors[size_t(position)].maxValues = {1, 1, 1};
  const int mesh = b.add_mesh(position);
  scene.root = b.add_node({}, {}, {parent_scale, parent_scale, parent_scale});
  scene.child = b.add_mesh_node(mesh);
  b.add_child(scene.root, scene.child);
  b.add_root(scene.root);
  const std::vector<float> times = {0, 0.5f, 1, 1.5f, 2};
  for (size_t k = 0; k < times.size(); ++k) {
    const float t = times[k];
    scene.translation.insert(scene.translation.end(), {0.3f * t, std::sin(t), -0.2f * t * t});
    const float angle = 0.7f * t;
    scene.rotation.insert(scene.rotation.end(), {0, std::sin(angle / 2), 0, std::cos(angle / 2)});
    scene.scale.insert(scene.scale.end(), {1 + 0.1f * t, 1, 1 - 0.05f * t});
  }
  const int animation = b.add_animation("move");
  b.add_channel(animation, scene.child, "translation", times, scene.translation);
  b.add_channel(animation, scene.child, "rotation", times, scene.rotation);
  b.add_channel(animation, scene.child, "scale", times, scene.scale);
}

// The largest difference between sampler `s`'s decoded output and `values`.
double largest_error(const tinygltf::Model& model, int s, const std::vector<float>& values) {
  std::vector<float> decoded;
  EXPECT_TRUE(read_floats(model, model.animations[0].samplers[size_t(s)].output, "test", decoded).ok());
  EXPECT_EQ(decoded.size(), values.size());
  double largest = 0;
  for (size_t i = 0; i < std::min(decoded.size(), values.size()); ++i)
    largest = std::max(largest, std::abs(double(decoded[i]) - values[i]));
  return largest;
}

// The largest angle (radians) between sampler `s`'s decoded quaternions and `values`'.
double largest_angle(const tinygltf::Model& model, int s, const std::vector<float>& values) {
  std::vector<float> decoded;
  EXPECT_TRUE(read_floats(model, model.animations[0].samplers[size_t(s)].output, "test", decoded).ok());
  double largest = 0;
  for (size_t k = 0; k + 4 <= std::min(decoded.size(), values.size()); k += 4) {
    double dot = 0, a = 0, b = 0;
    for (size_t c = 0; c < 4; ++c) {
      dot += double(decoded[k + c]) * values[k + c];
      a += double(decoded[k + c]) * decoded[k + c];
      b += double(values[k + c]) * values[k + c];
    }
    largest = std::max(largest, 2 * std::acos(std::min(1.0, std::abs(dot) / std::sqrt(a * b))));
  }
  return largest;
}

TEST(TrackPrecision, SceneDiagonalIsTheMeshBoundsUnderTheirNodes) {
  Scene scene;
  build(scene, 2);
  EXPECT_NEAR(scene_diagonal(scene.gltf.model), 2 * std::sqrt(3.0), 1e-12);  // [0, 2]³
  scene.gltf.model.nodes[size_t(scene.child)].skin = 0;  // a skinned mesh ignores its node's transform
  EXPECT_NEAR(scene_diagonal(scene.gltf.model), std::sqrt(3.0), 1e-12);
  EXPECT_EQ(scene_diagonal(tinygltf::Model()), 1);  // no mesh bounds
}

// Each path's step as track_precision.h gives it: a rotation's distance / D, a scale's 2 distance / D, a
// translation's distance over its parent's scale; the decoded values within half a step of the originals.
TEST(TrackPrecision, StepsKeepTheDisplacementWithinTheDistance) {
  for (double parent_scale : {1.0, 4.0}) {
    SCOPED_TRACE(parent_scale);
    Scene scene;
    build(scene, parent_scale);
    tinygltf::Model& model = scene.gltf.model;
    const double distance = 1e-3, diagonal = scene_diagonal(model);
    TrackReport report;
    ASSERT_TRUE(compress_tracks(model, TrackPrecision{distance, 0}, report).ok());
    EXPECT_EQ(report.samplers, 3u);
    ASSERT_TRUE(decode_tracks_in_model(model).ok());
    const double translation = largest_error(model, 0, scene.translation);
    const double rotation = largest_error(model, 1, scene.rotation);
    const double scale = largest_error(model, 2, scene.scale);
    EXPECT_LE(translation, distance / parent_scale / 2 * (1 + 1e-6));
    // A rotation's angle error moves a point at half the diagonal by angle × D / 2: within the distance.
    EXPECT_LE(largest_angle(model, 1, scene.rotation) * diagonal / 2, distance);
    EXPECT_LE(rotation, distance / diagonal);  // its components within a step
    EXPECT_LE(scale, distance / diagonal * (1 + 1e-6));
    // Not much finer than that either: the steps are the coarsest the distance allows.
    EXPECT_GT(translation, distance / parent_scale / 2 / 8);
    EXPECT_GT(scale, distance / diagonal / 8);
  }
}

// A track that holds its node's rest value to within half its step is dropped, not coded.
TEST(TrackPrecision, ChannelsThatHoldTheRestValueAreDropped) {
  Scene scene;
  build(scene, 1);
  tinygltf::Model& model = scene.gltf.model;
  scene.gltf.add_channel(0, scene.root, "translation", {0, 1}, {0, 0, 0, 1e-5f, 0, 0});  // rest: no translation
  TrackReport report;
  ASSERT_TRUE(compress_tracks(model, TrackPrecision{1e-3, 0}, report).ok());
  EXPECT_EQ(report.dropped, 1u);
  EXPECT_EQ(report.samplers, 3u);
  for (const tinygltf::AnimationChannel& channel : model.animations[0].channels)
    EXPECT_NE(channel.target_node, scene.root);
}

TEST(TrackPrecision, ADistanceMustBePositive) {
  Scene scene;
  build(scene, 1);
  TrackReport report;
  EXPECT_EQ(compress_tracks(scene.gltf.model, TrackPrecision{0, 0}, report).code(), StatusCode::invalid_argument);
}

}  // namespace
}  // namespace segmorph
