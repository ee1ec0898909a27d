// Frame times, the search for animated nodes, and bad data refused by sampling.
// Expected positions are worked out by hand from the glTF 2.0 specification, with the arithmetic in comments;
// none is recomputed with the code under test.
#include "sampling_fixtures.h"

#include <cstring>

namespace segmorph {
namespace {

// ----- Transforms ------------------------------------------------------------------------------------------

TEST(SamplingTransforms, OneNodesTransformIsTheWholeEvaluationsExactly) {
  // A chain of three (joint0 → joint1 → a child with a matrix), each level animated, and a node beside them: the
  // transform of one node computed alone is the same numbers as in the whole graph's, between keys and past them.
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int child = gltf.add_node({0.5f, 0.25f, 0});
  gltf.add_child(skin.joint1, child);
  gltf.model.nodes[size_t(child)].translation.clear();
  gltf.model.nodes[size_t(child)].matrix = {0.9, 0.1, 0, 0, -0.1, 0.9, 0.2, 0, 0, -0.2, 1.1, 0, 0.3, 0.7, -0.4, 1};
  const int beside = gltf.add_node({2, 0, 0});
  const int animation = gltf.add_animation();
  gltf.add_channel(animation, skin.joint0, "rotation", {0, 1, 2}, {0, 0, 0, 1, 0, 0.38f, 0, 0.92f, 0.2f, 0, 0, 0.98f});
  gltf.add_channel(animation, skin.joint1, "translation", {0, 0.7f, 2}, {0, 1, 0, 0.3f, 1.2f, 0, 0, 0.8f, 0.5f});
  gltf.add_channel(animation, skin.joint1, "scale", {0, 2}, {1, 1, 1, 1.5f, 0.5f, 1});
  gltf.add_channel(animation, beside, "translation", {0, 2}, {2, 0, 0, 3, 1, 0});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  ASSERT_EQ(scene.clips.size(), 1u);
  std::vector<Eigen::Matrix4d> global;
  const std::vector<const Clip*> clips = {nullptr, &scene.clips[0]};
  for (const Clip* clip : clips)
    for (double t : {0.0, 0.35, 1.0, 1.61, 2.0, 3.5}) {
      evaluate_global_transforms(gltf.model, scene.graph, clip, t, global);
      for (int node = 0; node < int(gltf.model.nodes.size()); ++node) {
        const Eigen::Matrix4d alone = evaluate_global_transform(gltf.model, scene.graph, clip, t, node);
        EXPECT_EQ(0, std::memcmp(alone.data(), global[size_t(node)].data(), sizeof(double) * 16))
            << "node " << node << " at " << t << (clip ? "" : " (rest pose)");
      }
    }
}

// ----- Frame times -----------------------------------------------------------------------------------------

TEST(SamplingFrameTimes, DefaultIsTheUnionOfKeyTimesOfChannelsThatMoveTheNode) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int animation = gltf.add_animation();
  gltf.add_channel(animation, skin.joint1, "translation", {0, 1, 2}, {0, 1, 0, 0, 1, 0, 0, 1, 0});
  gltf.add_channel(animation, skin.joint0, "rotation", {0, 0.5f, 2.5f}, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  // {0, 1, 2} ∪ {0, 0.5, 2.5}.
  const std::vector<float> expected{0, 0.5f, 1, 2, 2.5f};
  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[0], 0, {}), expected);
  EXPECT_EQ(sampled.primitives[0].clips[0].times, expected);
  EXPECT_EQ(sampled.primitives[0].clips[0].frame_count, 5u);
}

TEST(SamplingFrameTimes, ChannelsOfOtherNodesDoNotContribute) {
  GltfBuilder gltf;
  const int morph_node = add_morph_node(gltf);
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int rigid = gltf.add_node();
  gltf.add_root(rigid);
  const int animation = gltf.add_animation();
  gltf.add_channel(animation, skin.joint1, "translation", {0, 1}, {0, 1, 0, 2, 1, 0});
  gltf.add_channel(animation, morph_node, "weights", {0, 0.5f, 2}, {0, 0, 1, 0, 0, 1});
  gltf.add_channel(animation, rigid, "translation", {0.25f, 3}, {0, 0, 0, 1, 0, 0});
  // The skinned mesh node's own transform is ignored, so its channel moves nothing either.
  gltf.add_channel(animation, skin.mesh_node, "translation", {0.75f, 4}, {0, 0, 0, 1, 0, 0});
  Scene scene;
  ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
  ASSERT_EQ(scene.animated.size(), 2u);
  ASSERT_EQ(scene.animated[0].node, morph_node);
  ASSERT_EQ(scene.animated[1].node, skin.mesh_node);
  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[0], 0, {}), (std::vector<float>{0, 0.5f, 2}));
  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[1], 0, {}), (std::vector<float>{0, 1}));
}

TEST(SamplingFrameTimes, AboveSixtyKeysPerSecondFallsBackToA30FpsGrid) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  // 35 keys evenly over [0, 0.55] s: 34 intervals in 0.55 s are 61.8 keys per second, above kMaxKeyRate = 60.
  std::vector<float> dense_times, dense_weights;
  for (int k = 0; k < 35; ++k) {
    dense_times.push_back(k == 34 ? 0.55f : float(k * 0.55 / 34));
    dense_weights.insert(dense_weights.end(), {0, 0});
  }
  gltf.add_channel(gltf.add_animation(), node, "weights", dense_times, dense_weights);
  // 61 keys evenly over [0, 1] s: exactly 60 keys per second, kept.
  std::vector<float> limit_times, limit_weights;
  for (int k = 0; k < 61; ++k) {
    limit_times.push_back(k == 60 ? 1.0f : float(k / 60.0));
    limit_weights.insert(limit_weights.end(), {0, 0});
  }
  gltf.add_channel(gltf.add_animation(), node, "weights", limit_times, limit_weights);
  Scene scene;
  ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
  ASSERT_EQ(scene.animated[0].clips, (std::vector<int>{0, 1}));

  // The grid k/30 s for k = 0..16 (16/30 = 0.5333 s is the last before the end), then the end time itself.
  const std::vector<float> grid = frame_times(scene, gltf.model, scene.animated[0], 0, {});
  ASSERT_EQ(grid.size(), 18u);
  for (size_t k = 0; k <= 16; ++k) EXPECT_NEAR(grid[k], double(k) / 30, 1e-6) << "frame " << k;  // seconds
  EXPECT_EQ(grid.back(), 0.55f);

  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[0], 1, {}), limit_times);
}

TEST(SamplingFrameTimes, FpsSettingForcesARegularGrid) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 0.25f}, {0, 0, 1, 0});
  // Eleven keys 0.1 s apart, denser than the grid asked for.
  std::vector<float> times, weights;
  for (int k = 0; k <= 10; ++k) {
    times.push_back(float(k / 10.0));
    weights.insert(weights.end(), {0, 0});
  }
  gltf.add_channel(gltf.add_animation(), node, "weights", times, weights);
  Scene scene;
  ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
  // 10 fps over [0, 0.25]: 0, 0.1, 0.2, then the end 0.25.
  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[0], 0, at_fps(10)),
            (std::vector<float>{0, 0.1f, 0.2f, 0.25f}));
  // 4 fps over [0, 1]: the keys 0.1, 0.2, ... are not frames.
  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[0], 1, at_fps(4)),
            (std::vector<float>{0, 0.25f, 0.5f, 0.75f, 1}));
}

// A key 1e9 s after the others at --fps 30 is 3e10 frames: refused up front, naming the node and clip (before, the
// grid was built, and sampling hung). Without --fps the frames are the keys; at a rate the span allows, a grid.
TEST(SamplingFrameTimes, AGridOfMoreFramesThanAClipMayHaveIsRefused) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  gltf.add_channel(gltf.add_animation("Forever"), node, "weights", {0, 1e9f}, {0, 0, 1, 0});
  Scene scene;
  ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
  const Status refused = check_frame_counts(gltf.model, scene, at_fps(30));
  EXPECT_EQ(refused.code(), StatusCode::invalid_argument);
  EXPECT_NE(refused.message().find("in Forever: its keys span 1e+09 s, 3e+10 frames at --fps 30"), std::string::npos)
      << refused.message();
  EXPECT_TRUE(IsOk(check_frame_counts(gltf.model, scene, {})));
  EXPECT_EQ(frame_times(scene, gltf.model, scene.animated[0], 0, {}), (std::vector<float>{0, 1e9f}));
  EXPECT_TRUE(IsOk(check_frame_counts(gltf.model, scene, at_fps(1e-3))));  // 1e6 frames: the limit
}

// ----- analyze_scene ---------------------------------------------------------------------------------------

TEST(SamplingAnalyze, FileWithoutAnimationIsNothingToDo) {
  GltfBuilder gltf;
  add_morph_node(gltf);
  add_two_joint_skin(gltf);
  Scene scene;
  EXPECT_EQ(analyze_scene(gltf.model, scene).code(), StatusCode::nothing_to_do);
  EXPECT_TRUE(scene.animated.empty());
}

TEST(SamplingAnalyze, AnimationOfAnUnrelatedRigidNodeIsNothingToDo) {
  GltfBuilder gltf;
  add_morph_node(gltf);
  add_two_joint_skin(gltf);
  const int rigid = gltf.add_node();
  gltf.add_root(rigid);
  gltf.add_channel(gltf.add_animation(), rigid, "translation", {0, 1}, {0, 0, 0, 1, 0, 0});
  Scene scene;
  EXPECT_EQ(analyze_scene(gltf.model, scene).code(), StatusCode::nothing_to_do);
  EXPECT_TRUE(scene.animated.empty());
  EXPECT_EQ(scene.clips.size(), 1u);
}

TEST(SamplingAnalyze, NodeListsOnlyTheClipsThatMoveIt) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  const int rigid = gltf.add_node();
  gltf.add_root(rigid);
  gltf.add_channel(gltf.add_animation("first"), node, "weights", {0, 1}, {1, 0, 1, 0});
  gltf.add_channel(gltf.add_animation("rigid only"), rigid, "translation", {0, 1}, {0, 0, 0, 1, 0, 0});
  gltf.add_channel(gltf.add_animation("third"), node, "weights", {0, 2}, {0, 1, 0, 1});
  Scene scene;
  SampledNode sampled;
  ASSERT_TRUE(IsOk(analyze_and_sample(gltf.model, {}, scene, sampled)));
  ASSERT_EQ(scene.clips.size(), 3u);
  EXPECT_EQ(scene.clips[1].name, "rigid only");
  ASSERT_EQ(scene.animated.size(), 1u);
  EXPECT_EQ(scene.animated[0].clips, (std::vector<int>{0, 2}));
  ASSERT_EQ(sampled.primitives[0].clips.size(), 2u);
  // Clip 0 holds weights (1, 0): v2 = (1, 1, 0); clip 1 is animation 2, weights (0, 1): v2 = (0, 1, 4).
  const FrameSequence& first = sampled.primitives[0].clips[0];
  const FrameSequence& third = sampled.primitives[0].clips[1];
  EXPECT_EQ(first.times, (std::vector<float>{0, 1}));
  EXPECT_EQ(third.times, (std::vector<float>{0, 2}));
  EXPECT_TRUE(VertexNear(first, 0, 2, {1, 1, 0}));
  EXPECT_TRUE(VertexNear(third, 0, 2, {0, 1, 4}));
}

TEST(SamplingAnalyze, MorphedNodeAndSkinnedNodeAreTwoAnimatedNodes) {
  GltfBuilder gltf;
  const int morph_node = add_morph_node(gltf);
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  const int animation = gltf.add_animation();
  gltf.add_channel(animation, morph_node, "weights", {0, 1}, {0, 0, 1, 0});
  move_joint1(gltf, skin, animation);
  Scene scene;
  ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
  ASSERT_EQ(scene.animated.size(), 2u);
  EXPECT_EQ(scene.animated[0].node, morph_node);
  EXPECT_EQ(scene.animated[0].skin, -1);
  EXPECT_EQ(scene.animated[0].kind(), "morph");
  EXPECT_EQ(scene.animated[1].node, skin.mesh_node);
  EXPECT_EQ(scene.animated[1].skin, skin.skin);
  EXPECT_EQ(scene.animated[1].kind(), "skinned");
  for (const AnimatedNode& node : scene.animated) {
    SampledNode sampled;
    EXPECT_TRUE(IsOk(sample_node(gltf.model, scene, node, {}, sampled)));
  }
}

// ----- Bad data --------------------------------------------------------------------------------------------

TEST(SamplingBadData, AccessorRunningPastItsBufferView) {
  // Each overrun stays inside buffer 0 (other views follow) and leaves the model otherwise consistent, so
  // only the bufferView bounds check can catch it.
  {
    GltfBuilder gltf;
    const int node = add_morph_node(gltf);
    gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1}, {0, 0, 1, 0});
    // POSITION and both targets hold 3 elements (36 bytes each); claim 4.
    const tinygltf::Primitive& primitive = gltf.primitive(gltf.model.nodes[size_t(node)].mesh);
    gltf.model.accessors[size_t(primitive.attributes.at("POSITION"))].count += 1;
    for (const auto& target : primitive.targets) gltf.model.accessors[size_t(target.at("POSITION"))].count += 1;
    Scene scene;
    ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
    SampledNode sampled;
    EXPECT_EQ(sample_node(gltf.model, scene, scene.animated[0], {}, sampled).code(), StatusCode::bad_data);
  }
  {
    GltfBuilder gltf;
    const int node = add_morph_node(gltf);
    // The output follows the key times in the buffer and starts with 2, so key times read 4 bytes late would
    // be (1, 2): increasing, and as many as before.
    const int sampler = gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1}, {2, 0, 1, 0});
    // The key times fill their 8-byte view; starting 4 bytes in, the second one lies past it.
    gltf.model.accessors[size_t(gltf.model.animations[0].samplers[size_t(sampler)].input)].byteOffset = 4;
    Scene scene;
    EXPECT_EQ(analyze_scene(gltf.model, scene).code(), StatusCode::bad_data);
  }
}

TEST(SamplingBadData, WeightsOutputWithTheWrongCount) {
  {
    // 2 keys × 3 weights for a mesh with 2 morph targets: a consistent channel that does not fit the mesh.
    GltfBuilder gltf;
    const int node = add_morph_node(gltf);
    gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1}, {0, 0, 0, 1, 0, 0});
    Scene scene;
    ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
    SampledNode sampled;
    EXPECT_EQ(sample_node(gltf.model, scene, scene.animated[0], {}, sampled).code(), StatusCode::bad_data);
  }
  {
    // 5 outputs for 2 keys: not a whole number per key.
    GltfBuilder gltf;
    const int node = add_morph_node(gltf);
    gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1}, {0, 0, 1, 0, 0});
    Scene scene;
    EXPECT_EQ(analyze_scene(gltf.model, scene).code(), StatusCode::bad_data);
  }
}

TEST(SamplingBadData, JointIndexPastTheSkinsJointCount) {
  GltfBuilder gltf;
  const TwoJointSkin skin = add_two_joint_skin(gltf);
  // v1 names joint 2 of a skin with joints 0 and 1, with weight 1.
  gltf.set_skin_attributes(
      skin.mesh, 0,
      gltf.add_uints({0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0}, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT),
      gltf.add_vec4({1, 0, 0, 0, 1, 0, 0, 0, 0.5f, 0.5f, 0, 0}));
  move_joint1(gltf, skin, gltf.add_animation());
  Scene scene;
  ASSERT_TRUE(IsOk(analyze_scene(gltf.model, scene)));
  SampledNode sampled;
  EXPECT_EQ(sample_node(gltf.model, scene, scene.animated[0], {}, sampled).code(), StatusCode::bad_data);
}

TEST(SamplingBadData, DecreasingKeyTimes) {
  GltfBuilder gltf;
  const int node = add_morph_node(gltf);
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 1, 0.5f}, {0, 0, 1, 0, 0, 1});
  Scene scene;
  EXPECT_EQ(analyze_scene(gltf.model, scene).code(), StatusCode::bad_data);
}

}  // namespace
}  // namespace segmorph
