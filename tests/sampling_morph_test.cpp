// Sampling of morph-target animation: weights interpolation, default weights, targets without POSITION.
// Expected positions are worked out by hand from the glTF 2.0 specification, with the arithmetic in comments;
// none is recomputed with the code under test.
#include "sampling_fixtures.h"

namespace segmorph {
namespace {

// ----- Morph targets ---------------------------------------------------------------------------------------

TEST(SamplingMorph, LinearWeightsBetweenAndAtKeys) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  // Weights (0, 0) at t = 0, (1, 0) at t = 1, (0, 1) at t = 2.
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1, 2}, {0, 0, 1, 0, 0, 1});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(4), scene, sampled)));
  ASSERT_EQ(sampled.primitives.size(), 1u);
  ASSERT_EQ(sampled.primitives[0].clips.size(), 1u);
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.25f, 0.5f, 0.75f, 1, 1.25f, 1.5f, 1.75f, 2}));
  EXPECT_EQ(frames.vertex_count, 3u);
  EXPECT_EQ(frames.triangles, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_FALSE(sampled.clip_is_step[0]);

  // t = 0.5: weights (0.5, 0): v0 = (0.1 + 0.1, 0, 0.5), v1 = (1, 0, 1), v2 = (0.5, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 2, 0, {0.2, 0, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 2, 1, {1, 0, 1}));
  EXPECT_TRUE(VertexNear(frames, 2, 2, {0.5, 1, 0}));
  // t = 0.75: weights (0.75, 0): v0 = (0.1 + 0.15, 0, 0.75), v1 = (1, 0, 1.5), v2 = (0.75, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 3, 0, {0.25, 0, 0.75}));
  EXPECT_TRUE(VertexNear(frames, 3, 1, {1, 0, 1.5}));
  EXPECT_TRUE(VertexNear(frames, 3, 2, {0.75, 1, 0}));
  // t = 1.5: weights (0.5, 0.5): v0 = (0.2, 1, 0.5), v1 = (0.5, 0, 1), v2 = (0.5, 1, 2).
  EXPECT_TRUE(VertexNear(frames, 6, 0, {0.2, 1, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 6, 1, {0.5, 0, 1}));
  EXPECT_TRUE(VertexNear(frames, 6, 2, {0.5, 1, 2}));

  // At the keys the weights are one-hot and each position is base + delta with a single float rounding:
  // 0.1f + 0.2f = 0.3000000045 exactly, whose nearest float is 0.3f (0.3000000119; the one below is 0.2999999821).
  EXPECT_TRUE(VertexEq(frames, 0, 0, {0.1f, 0, 0}));
  EXPECT_TRUE(VertexEq(frames, 0, 1, {1, 0, 0}));
  EXPECT_TRUE(VertexEq(frames, 0, 2, {0, 1, 0}));
  EXPECT_TRUE(VertexEq(frames, 4, 0, {0.3f, 0, 1}));
  EXPECT_TRUE(VertexEq(frames, 4, 1, {1, 0, 2}));
  EXPECT_TRUE(VertexEq(frames, 4, 2, {1, 1, 0}));
  EXPECT_TRUE(VertexEq(frames, 8, 0, {0.1f, 2, 0}));
  EXPECT_TRUE(VertexEq(frames, 8, 1, {0, 0, 0}));
  EXPECT_TRUE(VertexEq(frames, 8, 2, {0, 1, 4}));
}

TEST(SamplingMorph, StepWeightsHoldUntilTheNextKey) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1, 2}, {0, 0, 1, 0, 0, 1}, "STEP");
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(4), scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.25f, 0.5f, 0.75f, 1, 1.25f, 1.5f, 1.75f, 2}));
  EXPECT_TRUE(sampled.clip_is_step[0]);

  // t = 0.75: still key 0's weights (0, 0): the base.
  EXPECT_TRUE(VertexEq(frames, 3, 0, {0.1f, 0, 0}));
  EXPECT_TRUE(VertexEq(frames, 3, 1, {1, 0, 0}));
  EXPECT_TRUE(VertexEq(frames, 3, 2, {0, 1, 0}));
  // t = 1 and t = 1.75: key 1's weights (1, 0): v0 = (0.1 + 0.2, 0, 1), v1 = (1, 0, 2), v2 = (1, 1, 0).
  for (size_t f : {4, 7}) {
    EXPECT_TRUE(VertexEq(frames, f, 0, {0.3f, 0, 1}));
    EXPECT_TRUE(VertexEq(frames, f, 1, {1, 0, 2}));
    EXPECT_TRUE(VertexEq(frames, f, 2, {1, 1, 0}));
  }
  // t = 2: key 2's weights (0, 1).
  EXPECT_TRUE(VertexEq(frames, 8, 0, {0.1f, 2, 0}));
  EXPECT_TRUE(VertexEq(frames, 8, 1, {0, 0, 0}));
  EXPECT_TRUE(VertexEq(frames, 8, 2, {0, 1, 4}));
}

TEST(SamplingMorph, CubicSplineWeightsFollowTheHermiteCurve) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  // Keys at t = 0 and t = 2 (interval dt = 2), each (in-tangent a, value v, out-tangent b) of 2 weights.
  // a0 and b1 lie outside the interval and must not matter, so they are large.
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 2},
                   {/* a0 */ 5, 5, /* v0 */ 0, 0, /* b0 */ 1, 0.5f,  //
                    /* a1 */ 2, -1, /* v1 */ 1, 0.5f, /* b1 */ 7, 7},
                   "CUBICSPLINE");
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(2), scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.5f, 1, 1.5f, 2}));

  // w(u) = h00 v0 + h10 dt b0 + h01 v1 + h11 dt a1, with h00 = 2u³ - 3u² + 1, h10 = u³ - 2u² + u,
  // h01 = -2u³ + 3u², h11 = u³ - u² (glTF 2.0, Appendix C).
  // t = 0.5, u = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = -0.046875.
  //   w0 = 0 + 0.140625·2·1 + 0.15625·1 - 0.046875·2·2 = 0.28125 + 0.15625 - 0.1875 = 0.25
  //   w1 = 0 + 0.140625·2·0.5 + 0.15625·0.5 + 0.046875·2·1 = 0.140625 + 0.078125 + 0.09375 = 0.3125
  //   v0 = (0.1 + 0.05, 0.625, 0.25), v1 = (1 - 0.3125, 0, 0.5), v2 = (0.25, 1, 1.25).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {0.15, 0.625, 0.25}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {0.6875, 0, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {0.25, 1, 1.25}));
  // t = 1, u = 0.5: h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125.
  //   w0 = 0 + 0.125·2·1 + 0.5·1 - 0.125·2·2 = 0.25 + 0.5 - 0.5 = 0.25
  //   w1 = 0 + 0.125·2·0.5 + 0.5·0.5 + 0.125·2·1 = 0.125 + 0.25 + 0.25 = 0.625
  //   v0 = (0.15, 1.25, 0.25), v1 = (0.375, 0, 0.5), v2 = (0.25, 1, 2.5).
  EXPECT_TRUE(VertexNear(frames, 2, 0, {0.15, 1.25, 0.25}));
  EXPECT_TRUE(VertexNear(frames, 2, 1, {0.375, 0, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 2, 2, {0.25, 1, 2.5}));
  // t = 2: the last key's value (1, 0.5): v0 = (0.3, 1, 1), v1 = (0.5, 0, 2), v2 = (1, 1, 2).
  EXPECT_TRUE(VertexNear(frames, 4, 0, {0.3, 1, 1}));
  EXPECT_TRUE(VertexNear(frames, 4, 1, {0.5, 0, 2}));
  EXPECT_TRUE(VertexNear(frames, 4, 2, {1, 1, 2}));
}

// A morph triangle skinned to one joint at the origin (no inverse bind matrices), with `mesh_weights` and
// `node_weights` as default weights; the only clip translates the joint from (0, 0, 0) at t = 0 to
// (10, 0, 0) at t = 1 and animates no weights.
GltfBuilder static_morph_in_skinned_primitive(const std::vector<double>& mesh_weights,
                                              const std::vector<double>& node_weights) {
  GltfBuilder gltf;
  const int mesh = add_morph_mesh(gltf);
  gltf.model.meshes[size_t(mesh)].weights = mesh_weights;
  gltf.set_skin_attributes(
      mesh, 0,
      gltf.add_uints({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE),
      gltf.add_vec4({1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}));
  const int joint = gltf.add_node();
  gltf.add_root(joint);
  const int node = gltf.add_mesh_node(mesh, gltf.add_skin({joint}));
  gltf.model.nodes[size_t(node)].weights = node_weights;
  gltf.add_root(node);
  gltf.add_channel(gltf.add_animation(), joint, "translation", {0, 1}, {0, 0, 0, 10, 0, 0});
  return gltf;
}

TEST(SamplingMorph, DefaultWeightsComeFromTheMeshWhenNotAnimated) {
  const GltfBuilder gltf = static_morph_in_skinned_primitive({0.5, 0.25}, {});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  EXPECT_TRUE(scene.animated[0].morphed);
  EXPECT_FALSE(scene.animated[0].weights_animated);
  EXPECT_TRUE(scene.animated[0].skin_animated);
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // Weights (0.5, 0.25): v0 = (0.1 + 0.1, 0.5, 0.5), v1 = (1 - 0.25, 0, 1), v2 = (0.5, 1, 1); + (10, 0, 0) at t = 1.
  EXPECT_TRUE(VertexNear(frames, 0, 0, {0.2, 0.5, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {0.75, 0, 1}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {0.5, 1, 1}));
  EXPECT_TRUE(VertexNear(frames, 1, 0, {10.2, 0.5, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {10.75, 0, 1}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {10.5, 1, 1}));
}

TEST(SamplingMorph, NodeWeightsOverrideMeshWeights) {
  const GltfBuilder gltf = static_morph_in_skinned_primitive({0.5, 0.25}, {0, 1});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // Weights (0, 1): v0 = (0.1, 2, 0), v1 = (0, 0, 0), v2 = (0, 1, 4); + (10, 0, 0) at t = 1.
  EXPECT_TRUE(VertexNear(frames, 0, 0, {0.1, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {0, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {0, 1, 4}));
  EXPECT_TRUE(VertexNear(frames, 1, 0, {10.1, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {10, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {10, 1, 4}));
}

TEST(SamplingMorph, TargetWithoutPositionMovesNothing) {
  GltfBuilder gltf;
  // The morph triangle's base, with normals; target 0 has only NORMAL deltas, target 1 the usual POSITION deltas.
  const int mesh = gltf.add_mesh(gltf.add_vec3({0.1f, 0, 0, 1, 0, 0, 0, 1, 0}));
  gltf.set_attribute(mesh, "NORMAL", gltf.add_vec3({0, 0, 1, 0, 0, 1, 0, 0, 1}));
  gltf.add_target(mesh, {{"NORMAL", gltf.add_vec3({1, 0, -1, 1, 0, -1, 1, 0, -1})}});
  gltf.add_target(mesh, {{"POSITION", gltf.add_vec3({0, 2, 0, -1, 0, 0, 0, 0, 4})}});
  const int node = gltf.add_mesh_node(mesh);
  gltf.add_root(node);
  // Weights (1, 0.5) at t = 0 and (1, 1) at t = 1: target 0's full weight moves no vertex.
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1}, {1, 0.5f, 1, 1});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // t = 0: base + 0.5 target 1: v0 = (0.1, 1, 0), v1 = (0.5, 0, 0), v2 = (0, 1, 2).
  EXPECT_TRUE(VertexNear(frames, 0, 0, {0.1, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {0.5, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {0, 1, 2}));
  // t = 1: base + target 1: v0 = (0.1, 2, 0), v1 = (0, 0, 0), v2 = (0, 1, 4).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {0.1, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {0, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {0, 1, 4}));
  EXPECT_EQ(sampled.primitives[0].rest_normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}));
}

}  // namespace
}  // namespace segmorph
