// Sampling of skinned animation: joint channels, hierarchy, inverse bind matrices, joint and weight encodings.
// Expected positions are worked out by hand from the glTF 2.0 specification, with the arithmetic in comments;
// none is recomputed with the code under test.
#include "sampling_fixtures.h"

namespace segmorph {
namespace {

// ----- Skins -----------------------------------------------------------------------------------------------

TEST(SamplingSkin, LinearTranslationOfAJoint) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  move_joint1(gltf, skin, gltf.add_animation());
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(2), scene, sampled)));
  EXPECT_EQ(scene.animated[0].node, skin.mesh_node);
  EXPECT_EQ(scene.animated[0].skin, skin.skin);
  EXPECT_EQ(scene.animated[0].kind(), "skinned");
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.5f, 1}));
  // v0 = (1, 0, 0), v1 = (2t, 2, 0), v2 = (t, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 0, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {0, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {0, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {1, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {0.5, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 2, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 2, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 2, 2, {1, 1, 0}));
}

// Joint 1 rotated about Z through its rest position (0, 1, 0): its skinning matrix is
// translate(0, 1, 0) · Rz(θ) · translate(0, -1, 0), so v1 = (0, 2, 0), one unit above the joint, goes to
// (-sin θ, 1 + cos θ, 0). v0 is on the fixed joint 0 and v2 lies on the rotation axis: both stay.
void expect_joint1_rotation(const FrameSequence& frames) {
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.25f, 0.5f, 0.75f, 1}));
  // t = 0.25: slerp turns at constant angular speed, θ = 22.5°. (nlerp would give 21.6°, x = -0.368.)
  EXPECT_TRUE(VertexNear(frames, 1, 1, {-kSin22_5, 1 + kCos22_5, 0}));
  // t = 0.5: θ = 45°.
  EXPECT_TRUE(VertexNear(frames, 2, 1, {-kHalfSqrt2, 1 + kHalfSqrt2, 0}));
  // t = 1: θ = 90°.
  EXPECT_TRUE(VertexNear(frames, 4, 1, {-1, 1, 0}));
  for (size_t f = 0; f < 5; ++f) {
    EXPECT_TRUE(VertexNear(frames, f, 0, {1, 0, 0}));
    EXPECT_TRUE(VertexNear(frames, f, 2, {0, 1, 0}));
  }
}

TEST(SamplingSkin, LinearRotationIsSlerp) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // Identity at t = 0, 90° about Z, (0, 0, sin 45°, cos 45°), at t = 1.
  const float h = float(kHalfSqrt2);
  gltf.add_channel(gltf.add_animation(), skin.joint1, "rotation", {0, 1}, {0, 0, 0, 1, 0, 0, h, h});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(4), scene, sampled)));
  expect_joint1_rotation(sampled.primitives[0].clips[0]);
}

TEST(SamplingSkin, LinearRotationTakesTheShortestPath) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // The same 90° as -q: the same rotation, but the long way round (135° at t = 0.5) if the sign is not flipped.
  const float h = float(kHalfSqrt2);
  gltf.add_channel(gltf.add_animation(), skin.joint1, "rotation", {0, 1}, {0, 0, 0, 1, 0, 0, -h, -h});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(4), scene, sampled)));
  expect_joint1_rotation(sampled.primitives[0].clips[0]);
}

TEST(SamplingSkin, StepTranslationHoldsUntilTheNextKey) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  gltf.add_channel(gltf.add_animation(), skin.joint1, "translation", {0, 1, 2}, {0, 1, 0, 2, 1, 0, 4, 1, 0}, "STEP");
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(2), scene, sampled)));
  EXPECT_TRUE(sampled.clip_is_step[0]);
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.5f, 1, 1.5f, 2}));
  // T - (0, 1, 0) is (0, 0, 0) on [0, 1), (2, 0, 0) on [1, 2), (4, 0, 0) from t = 2;
  // v1 = (0, 2, 0) + T - (0, 1, 0), v2 = (0, 1, 0) + (T - (0, 1, 0)) / 2.
  EXPECT_TRUE(VertexNear(frames, 1, 1, {0, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {0, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 2, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 2, 2, {1, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 3, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 3, 2, {1, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 4, 1, {4, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 4, 2, {2, 1, 0}));
}

TEST(SamplingSkin, CubicSplineTranslationFollowsTheHermiteCurve) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // Keys at t = 0 and t = 2 (dt = 2); a0 and b1 lie outside the interval and must not matter.
  gltf.add_channel(gltf.add_animation(), skin.joint1, "translation", {0, 2},
                   {/* a0 */ 9, 9, 9, /* v0 */ 0, 1, 0, /* b0 */ 1, 0, 0,  //
                    /* a1 */ 0, 0, 1, /* v1 */ 2, 1, 0, /* b1 */ 9, 9, 9},
                   "CUBICSPLINE");
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(2), scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.5f, 1, 1.5f, 2}));
  // T(u) = h00 v0 + h10 dt b0 + h01 v1 + h11 dt a1 (Hermite basis as in the cubic-spline weights test).
  // t = 0.5, u = 0.25: T = 0.84375 (0, 1, 0) + 0.28125 (1, 0, 0) + 0.15625 (2, 1, 0) - 0.09375 (0, 0, 1)
  //                      = (0.59375, 1, -0.09375).
  // v1 = (0, 2, 0) + T - (0, 1, 0), v2 = (0, 1, 0) + (T - (0, 1, 0)) / 2.
  EXPECT_TRUE(VertexNear(frames, 1, 1, {0.59375, 2, -0.09375}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {0.296875, 1, -0.046875}));
  // t = 1, u = 0.5: T = 0.5 (0, 1, 0) + 0.25 (1, 0, 0) + 0.5 (2, 1, 0) - 0.25 (0, 0, 1) = (1.25, 1, -0.25).
  EXPECT_TRUE(VertexNear(frames, 2, 1, {1.25, 2, -0.25}));
  EXPECT_TRUE(VertexNear(frames, 2, 2, {0.625, 1, -0.125}));
  // t = 2: the last key's value T = (2, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 4, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 4, 2, {1, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 2, 0, {1, 0, 0}));
}

TEST(SamplingSkin, AncestorTransformsOfTheJointsApply) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // A parent above joint 0: rotated 90° about Z, translated to (0, 0, 5) at t = 0 and (0, 0, 9) at t = 1
  // (its rotation is not animated and keeps the node's value): P(x, y, z) = (-y, x, z + 5 + 4t).
  const int parent = gltf.add_node({0, 0, 5}, {0, 0, std::sqrt(0.5), std::sqrt(0.5)});
  gltf.add_child(parent, skin.joint0);
  gltf.model.scenes[0].nodes[0] = parent;
  const int animation = gltf.add_animation();
  move_joint1(gltf, skin, animation);
  gltf.add_channel(animation, parent, "translation", {0, 1}, {0, 0, 5, 0, 0, 9});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // Skinning matrices: joint 0 → P, joint 1 → P · translate(2t, 0, 0).
  // t = 0: v0 = P(1, 0, 0) = (0, 1, 5), v1 = P(0, 2, 0) = (-2, 0, 5), v2 = P(0, 1, 0) = (-1, 0, 5).
  EXPECT_TRUE(VertexNear(frames, 0, 0, {0, 1, 5}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {-2, 0, 5}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {-1, 0, 5}));
  // t = 1: v0 = P(1, 0, 0) = (0, 1, 9), v1 = P(2, 2, 0) = (-2, 2, 9),
  //        v2 = (P(0, 1, 0) + P(2, 1, 0)) / 2 = ((-1, 0, 9) + (-1, 2, 9)) / 2 = (-1, 1, 9).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {0, 1, 9}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {-2, 2, 9}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {-1, 1, 9}));
}

TEST(SamplingSkin, AbsentInverseBindMatricesAreIdentity) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf, /*inverse_bind_matrices=*/false);
  move_joint1(gltf, skin, gltf.add_animation());
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // Joint 1's skinning matrix is its global transform translate(T), T = (2t, 1, 0):
  // v1 = (0, 2, 0) + T, v2 = ((0, 1, 0) + (0, 1, 0) + T) / 2.
  EXPECT_TRUE(VertexNear(frames, 0, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {0, 3, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {0, 1.5, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 3, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {1, 1.5, 0}));
}

TEST(SamplingSkin, TransformOfTheSkinnedMeshNodeIsIgnored) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // glTF 2.0 (Skins): only the joint transforms are applied; the skinned mesh node's own transform is ignored.
  gltf.model.nodes[size_t(skin.mesh_node)].translation = {100, 0, 0};
  gltf.model.nodes[size_t(skin.mesh_node)].scale = {3, 3, 3};
  move_joint1(gltf, skin, gltf.add_animation());
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // As in LinearTranslationOfAJoint: v0 = (1, 0, 0), v1 = (2t, 2, 0), v2 = (t, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 0, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {0, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {0, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {1, 1, 0}));
}

TEST(SamplingSkin, JointGivenByAMatrix) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // Joint 0 = translate(5, 0, 0) · Rz(90°), column-major: M(x, y, z) = (5 - y, x, z). Read row-major by mistake it
  // would rotate by -90° and lose the translation.
  gltf.model.nodes[size_t(skin.joint0)].matrix = {0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1};
  move_joint1(gltf, skin, gltf.add_animation());
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 1}));
  // Skinning matrices: joint 0 → M, joint 1 → M · translate(2t, 0, 0).
  // t = 0: v0 = M(1, 0, 0) = (5, 1, 0), v1 = M(0, 2, 0) = (3, 0, 0), v2 = M(0, 1, 0) = (4, 0, 0).
  EXPECT_TRUE(VertexNear(frames, 0, 0, {5, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 1, {3, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 0, 2, {4, 0, 0}));
  // t = 1: v1 = M(2, 2, 0) = (3, 2, 0), v2 = (M(0, 1, 0) + M(2, 1, 0)) / 2 = ((4, 0, 0) + (4, 2, 0)) / 2 = (4, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {5, 1, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {3, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {4, 1, 0}));
}

// Samples the two-joint skin, whose JOINTS/WEIGHTS a test has replaced, with joint 1 moved by move_joint1, and
// returns the frame at t = 1, where joint 1's skinning matrix is translate(2, 0, 0) and joint 0's the identity.
FrameSequence sample_moved_skin(GltfBuilder& gltf, const TwoJointSkin& skin) {
  move_joint1(gltf, skin, gltf.add_animation());
  Scene scene;
  SampledNode sampled;
  const Status status = analyze_and_sample(gltf.model, {}, scene, sampled);
  EXPECT_TRUE(IsOk(status));
  if (!status.ok()) return FrameSequence();
  EXPECT_EQ(sampled.primitives[0].clips[0].times, (std::vector<float>{0, 1}));
  return sampled.primitives[0].clips[0];
}

TEST(SamplingSkin, SecondJointsAndWeightsSetApplies) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int u16 = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  // v0: joint 0 in set 0. v1: joint 1 in set 1 (set 0 all zero). v2: 0.25 joint 0 in set 0, 0.75 joint 1 in set 1.
  gltf.set_skin_attributes(skin.mesh, 0, gltf.add_uints({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, TINYGLTF_TYPE_VEC4, u16),
                           gltf.add_vec4({1, 0, 0, 0, 0, 0, 0, 0, 0.25f, 0, 0, 0}));
  gltf.set_skin_attributes(skin.mesh, 1, gltf.add_uints({0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, TINYGLTF_TYPE_VEC4, u16),
                           gltf.add_vec4({0, 0, 0, 0, 1, 0, 0, 0, 0.75f, 0, 0, 0}));
  const FrameSequence frames = sample_moved_skin(gltf, skin);
  // t = 1: v0 = (1, 0, 0), v1 = (0, 2, 0) + (2, 0, 0), v2 = (0, 1, 0) + 0.75 (2, 0, 0) = (1.5, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {1.5, 1, 0}));
}

TEST(SamplingSkin, U8JointsAndNormalizedU8Weights) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int u8 = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  // v2's weights are 64/255 and 191/255 (sum 1).
  gltf.set_skin_attributes(skin.mesh, 0, gltf.add_uints({0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0}, TINYGLTF_TYPE_VEC4, u8),
                           gltf.add_normalized({255, 0, 0, 0, 255, 0, 0, 0, 64, 191, 0, 0}, TINYGLTF_TYPE_VEC4, u8));
  const FrameSequence frames = sample_moved_skin(gltf, skin);
  // t = 1: v2 = (0, 1, 0) + (191/255) (2, 0, 0) = (382/255, 1, 0) = (1.49803922, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {1.49803922, 1, 0}));
}

TEST(SamplingSkin, U16JointsAndNormalizedU16Weights) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int u16 = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  // v2's weights are 10000/65535 and 55535/65535 (sum 1). Their bytes differ (0x2710, 0xD8EF), so reading
  // only the low or only the high byte would change the ratio.
  gltf.set_skin_attributes(
      skin.mesh, 0, gltf.add_uints({0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0}, TINYGLTF_TYPE_VEC4, u16),
      gltf.add_normalized({65535, 0, 0, 0, 65535, 0, 0, 0, 10000, 55535, 0, 0}, TINYGLTF_TYPE_VEC4, u16));
  const FrameSequence frames = sample_moved_skin(gltf, skin);
  // t = 1: v2 = (0, 1, 0) + (55535/65535) (2, 0, 0) = (111070/65535, 1, 0) = (1.69481956, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {1.69481956, 1, 0}));
}

TEST(SamplingSkin, WeightsNotSummingToOneAreDividedByTheirSum) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // v0 (2) → 1, v1 (0.5) → 1, v2 (0.5, 1.5) → (0.25, 0.75), as three.js's SkinnedMesh.normalizeSkinWeights does.
  gltf.set_skin_attributes(
      skin.mesh, 0,
      gltf.add_uints({0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0}, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT),
      gltf.add_vec4({2, 0, 0, 0, 0.5f, 0, 0, 0, 0.5f, 1.5f, 0, 0}));
  const FrameSequence frames = sample_moved_skin(gltf, skin);
  // t = 1: v0 = (1, 0, 0), v1 = (2, 2, 0), v2 = (0, 1, 0) + 0.75 (2, 0, 0) = (1.5, 1, 0).
  // (Unnormalized: v0 = (2, 0, 0), v1 = (1, 1, 0), v2 = (3, 2, 0).)
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {1.5, 1, 0}));
}

TEST(SamplingSkin, AllZeroWeightsFollowTheFirstJointTheVertexNames) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // v0 names joints (0, 1, 0, 0) and v2 names (1, 0, 0, 0), both with weights all zero. three.js
  // (SkinnedMesh.normalizeSkinWeights) sets their weights to (1, 0, 0, 0): each follows JOINTS_0's first entry.
  gltf.set_skin_attributes(
      skin.mesh, 0,
      gltf.add_uints({0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT),
      gltf.add_vec4({0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0}));
  const FrameSequence frames = sample_moved_skin(gltf, skin);
  // t = 1: v0 follows joint 0: (1, 0, 0); v1 = (2, 2, 0); v2 follows joint 1: (0, 1, 0) + (2, 0, 0) = (2, 1, 0).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {1, 0, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {2, 2, 0}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {2, 1, 0}));
}

TEST(SamplingSkin, MorphIsAppliedBeforeSkinning) {
  GltfBuilder gltf;
  const int mesh = add_morph_mesh(gltf);
  gltf.set_skin_attributes(
      mesh, 0,
      gltf.add_uints({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE),
      gltf.add_vec4({1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}));
  const int joint = gltf.add_node();
  gltf.add_root(joint);
  const int node = gltf.add_mesh_node(mesh, gltf.add_skin({joint}));
  gltf.add_root(node);
  // The joint (at the origin, no inverse bind matrices) turns 0° → 90° about Z while the weights go (0, 0) → (1, 0).
  const int animation = gltf.add_animation();
  const float h = float(kHalfSqrt2);
  gltf.add_channel(animation, joint, "rotation", {0, 1}, {0, 0, 0, 1, 0, 0, h, h});
  gltf.add_channel(animation, node, "weights", {0, 1}, {0, 0, 1, 0});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, at_fps(2), scene, sampled)));
  EXPECT_EQ(scene.animated[0].kind(), "morph+skinned");
  const FrameSequence& frames = sampled.primitives[0].clips[0];
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.5f, 1}));
  // t = 0.5: weights (0.5, 0) morph v0 = (0.2, 0, 0.5), v1 = (1, 0, 1), v2 = (0.5, 1, 0); then Rz(45°),
  // (x, y) → ((x - y)/√2, (x + y)/√2): v0 = (0.2/√2, 0.2/√2, 0.5) = (0.14142136, 0.14142136, 0.5),
  // v1 = (0.70710678, 0.70710678, 1), v2 = (-0.5/√2, 1.5/√2, 0) = (-0.35355339, 1.06066017, 0).
  EXPECT_TRUE(VertexNear(frames, 1, 0, {0.14142136, 0.14142136, 0.5}));
  EXPECT_TRUE(VertexNear(frames, 1, 1, {0.70710678, 0.70710678, 1}));
  EXPECT_TRUE(VertexNear(frames, 1, 2, {-0.35355339, 1.06066017, 0}));
  // t = 1: weights (1, 0) morph v0 = (0.3, 0, 1), v1 = (1, 0, 2), v2 = (1, 1, 0); then Rz(90°), (x, y) → (-y, x).
  // (Skinning first and morphing after would give v0 = (0, 0.1, 0) + (0.2, 0, 1) = (0.2, 0.1, 1).)
  EXPECT_TRUE(VertexNear(frames, 2, 0, {0, 0.3, 1}));
  EXPECT_TRUE(VertexNear(frames, 2, 1, {0, 1, 2}));
  EXPECT_TRUE(VertexNear(frames, 2, 2, {-1, 1, 0}));
}

}  // namespace
}  // namespace segmorph
