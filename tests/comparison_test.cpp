// verify's pairing of two files: vertices by trajectory (match_vertices), primitives, clips, times and spaces
// (compare_animation), on the kind of file gltfpack writes: nodes reordered and re-parented, positions
// quantized to integers with the dequantization on the node (KHR_mesh_quantization), vertices reordered
// and merged, tracks that move nothing dropped.
#include "verify/comparison.h"

#include <random>

#include "sampling_fixtures.h"
#include "verify/correspondence.h"

namespace segmorph {
namespace {

// A clip of `vertex_count` vertices from frame-major positions.
FrameSequence clip_of(size_t vertex_count, const std::vector<float>& positions) {
  FrameSequence clip;
  clip.vertex_count = vertex_count;
  clip.frame_count = positions.size() / (vertex_count * 3);
  clip.positions = positions;
  for (size_t f = 0; f < clip.frame_count; ++f) clip.times.push_back(float(f));
  return clip;
}

TEST(MatchVertices, TrajectoryWinsOverANearerFirstFrame) {
  // v0 stays at the origin; v1 starts 0.1 away and moves off along x. In the other file quantization has
  // moved the first frames past each other: v1's copy starts nearer v0 than v0's own copy does.
  const FrameSequence reference = clip_of(2, {0, 0, 0, 0.1f, 0, 0,  //
                                              0, 0, 0, 1, 0, 0,     //
                                              0, 0, 0, 2, 0, 0});
  const FrameSequence other = clip_of(2, {0.01f, 0, 0, 0.09f, 0, 0,  // other 0 is v1, other 1 is v0
                                          1, 0, 0, 0, 0, 0,          //
                                          2, 0, 0, 0, 0, 0});
  EXPECT_EQ(match_vertices({reference}, {other}), (std::vector<uint32_t>{1, 0}));
}

TEST(MatchVertices, ReorderedAndMergedDuplicatesPairWithTheirOwnTrajectories) {
  // v2 and v3 are duplicates (a seam); the other file keeps one copy, last, and shuffles the rest.
  const FrameSequence reference = clip_of(4, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0,  //
                                              0, 0, 1, 1, 0, 2, 0, 1, 3, 0, 1, 3});
  const FrameSequence other = clip_of(3, {1, 0, 0, 0, 0, 0, 0, 1, 0,  //
                                          1, 0, 2, 0, 0, 1, 0, 1, 3});
  EXPECT_EQ(match_vertices({reference}, {other}), (std::vector<uint32_t>{1, 0, 2, 2}));
  EXPECT_EQ(match_vertices({reference}, {reference}), (std::vector<uint32_t>{0, 1, 2, 3}));
}

TEST(MatchVertices, FarFromTheOtherFileStillPairs) {
  // A 10 × 10 × 10 lattice, and the same lattice 1e7 away on every axis (a file read in the wrong space):
  // millions of empty cell shells lie between them. The search starts at the first shell that meets the
  // other's box instead of walking out through all of them, and every vertex pairs with the nearest corner,
  // the last.
  std::vector<float> near, far;
  for (int i = 0; i < 1000; ++i)
    for (float c : {float(i % 10), float(i / 10 % 10), float(i / 100)}) near.push_back(c), far.push_back(c + 1e7f);
  EXPECT_EQ(match_vertices({clip_of(1000, far)}, {clip_of(1000, near)}), std::vector<uint32_t>(1000, 999));
}

// The pairing by brute force: for each vertex of `reference`, the vertex of `other` of least trajectory distance,
// the lowest of equals.
std::vector<uint32_t> nearest_trajectories(const std::vector<FrameSequence>& reference,
                                           const std::vector<FrameSequence>& other) {
  std::vector<uint32_t> match(reference[0].vertex_count);
  for (size_t v = 0; v < match.size(); ++v) {
    double best = INFINITY;
    for (uint32_t u = 0; u < other[0].vertex_count; ++u) {
      double sum = 0;
      for (size_t c = 0; c < reference.size(); ++c)
        for (size_t f = 0; f < reference[c].frame_count; ++f)
          for (size_t k = 0; k < 3; ++k) {
            const double d = double(reference[c].frame(f)[v * 3 + k]) - other[c].frame(f)[u * 3 + k];
            sum += d * d;
          }
      if (sum < best) best = sum, match[v] = u;
    }
  }
  return match;
}

TEST(MatchVertices, AgreesWithBruteForceWhateverTheThreadsAndHeldFrames) {
  // Two clips (9 and 4 frames) of 700 vertices: a wavy sheet flat in z at rest (its points fill few grid cells),
  // swept and bent over time, with duplicated vertices (seams). The other file: the vertices shuffled, every
  // duplicate merged but one that is kept twice (a tie), positions moved by noise up to 2 % of the spacing, and a
  // few vertices moved far off (the file does not quite correspond there).
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(-1, 1);
  const size_t rest = 600, count = 700;
  std::vector<std::array<float, 2>> sheet(count);
  for (size_t v = 0; v < rest; ++v) sheet[v] = {float(v % 30) / 30, float(v / 30) / 30};
  for (size_t v = rest; v < count; ++v) sheet[v] = sheet[(v * 7) % rest];  // duplicates
  std::vector<FrameSequence> reference, other;
  std::vector<uint32_t> order(rest);
  for (uint32_t u = 0; u < rest; ++u) order[u] = u;
  std::shuffle(order.begin(), order.end(), random);
  size_t tied = 0;  // the first other vertex not moved far; other vertex 600 duplicates it
  while (order[tied] % 97 == 0) ++tied;
  order.push_back(order[tied]);
  for (size_t frames : {9, 4}) {
    std::vector<float> positions, moved;
    for (size_t f = 0; f < frames; ++f) {
      const float t = float(f) / 8;
      for (size_t v = 0; v < count; ++v) {
        const float x = sheet[v][0], y = sheet[v][1];
        positions.insert(positions.end(), {x + t * y, y, 0.2f * t * std::sin(6 * x + t)});
      }
      for (size_t u = 0; u < order.size(); ++u) {
        const float* p = &positions[(f * count + order[u]) * 3];
        const bool far = order[u] % 97 == 0;
        for (int k = 0; k < 3; ++k) moved.push_back(p[k] + (far ? 3.0f : 0.02f / 30 * unit(random)));
      }
      float* frame = &moved[f * order.size() * 3];
      std::copy(frame + tied * 3, frame + tied * 3 + 3, frame + (order.size() - 1) * 3);
    }
    reference.push_back(clip_of(count, positions));
    other.push_back(clip_of(order.size(), moved));
  }
  const std::vector<uint32_t> expected = nearest_trajectories(reference, other);
  EXPECT_EQ(expected[order[tied]], tied);  // the tie goes to the lower
  EXPECT_EQ(match_vertices(reference, other), expected);
  EXPECT_EQ(match_vertices(reference, other, 2), expected);
  EXPECT_EQ(match_vertices(reference, other, 1, 1), expected);  // one frame held, the rest read in place
  EXPECT_EQ(match_vertices(reference, other, 3, 5 * order.size() * 12), expected);
}

TEST(MatchVertices, OfTwoEquallyNearTrajectoriesTheLowerVertexWins) {
  // The other: a 10 x 10 x 3 lattice, shuffled, moving by exact steps; the reference: 60 points half a spacing along x
  // from lattice points, so each is exactly as near two of them (every value is exact in binary). Whichever of the two
  // the search meets first, the lower index wins.
  std::mt19937 random(11);
  std::vector<uint32_t> order(300);
  for (uint32_t u = 0; u < 300; ++u) order[u] = u;
  std::shuffle(order.begin(), order.end(), random);
  std::vector<float> lattice, probes;
  for (int f = 0; f < 3; ++f) {
    const float dx = 0.25f * float(f), dz = -0.5f * float(f);
    for (uint32_t u : order)
      lattice.insert(lattice.end(), {float(u % 10) + dx, float(u / 10 % 10), float(u / 100) + dz});
    for (int p = 0; p < 60; ++p)
      probes.insert(probes.end(), {float(p % 9) + 0.5f + dx, float(p / 9 % 10), float(p % 3) + dz});
  }
  const std::vector<FrameSequence> reference = {clip_of(60, probes)}, other = {clip_of(300, lattice)};
  EXPECT_EQ(match_vertices(reference, other), nearest_trajectories(reference, other));
}

TEST(MatchVertices, AVertexFarFromEveryOtherStillFindsTheNearest) {
  // The other: 2,000 points on a sphere (a surface: small grid cells); the reference: its centre, far from every
  // point in cells, and a point just off the sphere. Each pairs as brute force pairs it.
  std::vector<float> sphere, probes = {0.01f, 0.02f, 0, 0, 0, 1.05f};
  for (int i = 0; i < 2000; ++i) {
    const double z = 1 - 2 * (i + 0.5) / 2000, r = std::sqrt(1 - z * z), a = i * 2.399963;
    sphere.insert(sphere.end(), {float(r * std::cos(a)), float(r * std::sin(a)), float(z)});
  }
  const std::vector<FrameSequence> reference = {clip_of(2, probes)}, other = {clip_of(2000, sphere)};
  EXPECT_EQ(match_vertices(reference, other), nearest_trajectories(reference, other));
}

// The reference: two morph nodes under the scene root and one animation, "Wave".
//   node 0  translation (2, 0, 0); mesh A, 4 vertices (0, 0, 0) (1, 0, 0) (0, 1, 0) (1, 1, 0.5) and one target
//           moving v0 by (0, 0, 1) and v3 by (0, 0, -1); "Wave" plays its weight 0, 1, 0 at t = 0, 1, 2.
//   node 1  mesh B, 3 vertices (0, 5, 0) (1, 5, 0) (0, 6, 0), one target; "Wave" holds its weight at 0.
tinygltf::Model reference_model() {
  GltfBuilder gltf;
  const int mesh_a =
      gltf.add_mesh(gltf.add_vec3({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0.5f}),
                    gltf.add_uints({0, 1, 2, 1, 3, 2}, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
  gltf.add_target(mesh_a, {{"POSITION", gltf.add_vec3({0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, -1})}});
  const int mesh_b = gltf.add_mesh(gltf.add_vec3({0, 5, 0, 1, 5, 0, 0, 6, 0}));
  gltf.add_target(mesh_b, {{"POSITION", gltf.add_vec3({0, 0, 0.5f, 0, 0, 0, 0, 0, 0})}});
  const int node_a = gltf.add_mesh_node(mesh_a);
  gltf.model.nodes[size_t(node_a)].translation = {2, 0, 0};
  const int node_b = gltf.add_mesh_node(mesh_b);
  gltf.add_root(node_a);
  gltf.add_root(node_b);
  const int wave = gltf.add_animation("Wave");
  gltf.add_channel(wave, node_a, "weights", {0, 1, 2}, {0, 1, 0});
  gltf.add_channel(wave, node_b, "weights", {0, 2}, {0, 0});
  return gltf.model;
}

// The reference as gltfpack would write it (-vp with exact steps): a new root holding the meshes; mesh A
// (node 2) stored as unsigned shorts of step 0.5 and reordered v3 v0 v2 v1, its target as shorts, its node's
// scale 0.5 and translation (2, 0, 0); mesh B (node 1) stored in steps of 0.25 from (0, 5, 0), reordered
// v1 v2 v0, its "Wave" track dropped (constant). "Wave" comes second, after an "Idle" that holds A still, and
// has one more key, on the line between two of the reference's. `v0_delta` is A's target on v0 in steps
// (2 is the reference's motion).
tinygltf::Model quantized_model(int v0_delta = 2) {
  GltfBuilder gltf;
  const int position_a =
      gltf.add_uints({2, 2, 1, 0, 0, 0, 0, 2, 0, 2, 0, 0}, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  const int mesh_a = gltf.add_mesh(position_a);
  gltf.add_target(mesh_a,
                  {{"POSITION", gltf.add_shorts({0, 0, -2, 0, 0, v0_delta, 0, 0, 0, 0, 0, 0}, TINYGLTF_TYPE_VEC3)}});
  const int mesh_b = gltf.add_mesh(
      gltf.add_uints({4, 0, 0, 0, 4, 0, 0, 0, 0}, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
  gltf.add_target(mesh_b, {{"POSITION", gltf.add_shorts({0, 0, 0, 0, 0, 0, 0, 0, 2}, TINYGLTF_TYPE_VEC3)}});
  const int root = gltf.add_node();
  const int node_b = gltf.add_mesh_node(mesh_b);
  gltf.model.nodes[size_t(node_b)].translation = {0, 5, 0};
  gltf.model.nodes[size_t(node_b)].scale = {0.25, 0.25, 0.25};
  const int node_a = gltf.add_mesh_node(mesh_a);
  gltf.model.nodes[size_t(node_a)].translation = {2, 0, 0};
  gltf.model.nodes[size_t(node_a)].scale = {0.5, 0.5, 0.5};
  gltf.add_child(root, node_b);
  gltf.add_child(root, node_a);
  gltf.add_root(root);
  gltf.add_channel(gltf.add_animation("Idle"), node_a, "weights", {0, 1}, {0, 0});
  gltf.add_channel(gltf.add_animation("Wave"), node_a, "weights", {0, 0.5f, 1, 2}, {0, 0.5f, 1, 0});
  return gltf.model;
}

struct Compared {
  Status status;
  AnimationComparison result;
};

Compared compare(const tinygltf::Model& reference, const tinygltf::Model& other, VertexMatches* matches = nullptr) {
  Compared out;
  Scene reference_scene, other_scene;
  std::vector<SampledNode> sampled;
  out.status = analyze_scene(reference, reference_scene);
  if (!out.status.ok()) return out;
  sampled.resize(reference_scene.animated.size());
  for (size_t i = 0; i < sampled.size() && out.status.ok(); ++i)
    out.status = sample_node(reference, reference_scene, reference_scene.animated[i], SampleSettings(), sampled[i]);
  if (out.status.ok()) out.status = analyze_scene(other, other_scene);
  if (out.status.ok())
    out.status = compare_animation(reference, reference_scene, sampled, other, other_scene, out.result, false, matches);
  return out;
}

TEST(CompareAnimation, QuantizedReorderedCopyWithDequantizationOnTheNodeMeasuresZero) {
  const Compared compared = compare(reference_model(), quantized_model());
  ASSERT_TRUE(IsOk(compared.status));
  // Every value is exact in float (steps of 0.25 and 0.5), so the copy plays the reference bit for bit.
  EXPECT_EQ(compared.result.worst.kg_percent, 0);
  EXPECT_EQ(compared.result.worst.max_error_over_diagonal, 0);
  EXPECT_EQ(compared.result.vertices, 7u);
  EXPECT_EQ(compared.result.frames, 3u);           // node 0's frames: t = 0, 1, 2
  EXPECT_EQ(compared.result.vertex_frames, 18.0);  // 4 × 3 + 3 × 2 (node 1's track has keys at 0 and 2)
}

TEST(CompareAnimation, AWrongMotionShowsInTheError) {
  // v0's target is 3 steps of 0.5 instead of 2: at t = 1 v0 is 0.5 off, in mesh A's space as in the
  // reference's (node 0's mesh space, the same scale); A's first-frame diagonal is √(1 + 1 + 0.25) = 1.5.
  const Compared compared = compare(reference_model(), quantized_model(3));
  ASSERT_TRUE(IsOk(compared.status));
  EXPECT_NEAR(compared.result.worst.max_error_over_diagonal, 0.5 / 1.5, 1e-6);
  EXPECT_GT(compared.result.worst.kg_percent, 1);
}

// Kept vertex pairings give what pairing afresh gives, on the file they were made on and on one whose motion differs
// (the kept skins' search compares encodes that differ in their tracks only); a pairing that no longer fits (another
// vertex count) is made again.
TEST(CompareAnimation, KeptVertexPairingsMeasureAsFreshOnes) {
  VertexMatches matches;
  const Compared first = compare(reference_model(), quantized_model(), &matches);
  ASSERT_TRUE(IsOk(first.status));
  EXPECT_FALSE(matches.empty());
  const Compared fresh = compare(reference_model(), quantized_model(3));
  const Compared kept = compare(reference_model(), quantized_model(3), &matches);
  ASSERT_TRUE(IsOk(kept.status));
  EXPECT_EQ(kept.result.worst.kg_percent, fresh.result.worst.kg_percent);
  EXPECT_EQ(kept.result.worst.max_error_over_diagonal, fresh.result.worst.max_error_over_diagonal);
  for (auto& [key, match] : matches) match.push_back(0);  // one vertex too many: made again
  const Compared remade = compare(reference_model(), quantized_model(3), &matches);
  EXPECT_EQ(remade.result.worst.kg_percent, fresh.result.worst.kg_percent);
}

TEST(CompareAnimation, AFileWithoutTheAnimationIsBadData) {
  // The other file has one animation, "Run"; the reference two, "Wave" and "Wave again". "Wave" has no
  // namesake and falls back to index 0; "Wave again" has neither a namesake nor an index 1.
  tinygltf::Model other = quantized_model();
  other.animations.resize(1);
  other.animations[0].name = "Run";
  tinygltf::Model reference = reference_model();
  reference.animations.push_back(reference.animations[0]);
  reference.animations[1].name = "Wave again";
  const Compared compared = compare(reference, other);
  EXPECT_EQ(compared.status.code(), StatusCode::bad_data);
  EXPECT_NE(compared.status.message().find("Wave again"), std::string::npos) << compared.status.message();
}

// A mesh that moves rigidly with its node (encode's "rigid" meshes), measured in model space at the key times of
// the clips that move the node or an ancestor. The node (static translation (5, 0, 0)) is a child of a node that
// "Walk" moves along x by (0, 0, 0), (1, 0, 0), (2, 0, 0) at t = 0, 1, 2; "Blink" moves another node only.
// Vertices (0, 0, 0) (2, 0, 0) (0, 2, 0) (0, 0, 2): centroid (0.5, 0.5, 0.5), Σ |p − c|² = 0.75 + 3 × 2.75 = 9 in
// every frame (a translation keeps it), 27 over the 3 frames. The other file has the vertices in reverse order, the
// last one 0.1 higher in z, and Walk's middle key at 1.2: squared errors 0.01 (t = 0), 3 × 0.04 + 0.05 (t = 1) and
// 0.01 (t = 2), 0.19 in all. KG = 100 × sqrt(0.19 / 27) = 8.38870 %; the largest error sqrt(0.05) = 0.223607.
tinygltf::Model rigid_model(const std::vector<float>& positions, float middle_key) {
  GltfBuilder gltf;
  const int parent = gltf.add_node();
  const int mesh = gltf.add_mesh(gltf.add_vec3(positions));
  const int rigid = gltf.add_mesh_node(mesh);
  gltf.model.nodes[size_t(rigid)].translation = {5, 0, 0};
  gltf.add_child(parent, rigid);
  gltf.add_root(parent);
  const int other = gltf.add_node();
  gltf.add_root(other);
  gltf.add_channel(gltf.add_animation("Blink"), other, "translation", {0, 0.5f, 4}, {0, 0, 0, 0, 1, 0, 0, 0, 0});
  gltf.add_channel(gltf.add_animation("Walk"), parent, "translation", {0, 1, 2}, {0, 0, 0, middle_key, 0, 0, 2, 0, 0});
  return gltf.model;
}

TEST(CompareRigidPrimitive, MeasuresModelSpaceOverTheClipsThatMoveTheNode) {
  const tinygltf::Model reference = rigid_model({0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2}, 1);
  const tinygltf::Model other = rigid_model({0, 0, 2.1f, 0, 2, 0, 2, 0, 0, 0, 0, 0}, 1.2f);
  Scene reference_scene, other_scene;
  ASSERT_TRUE(IsOk(load_clip(reference, 0, reference_scene.clips.emplace_back())));
  ASSERT_TRUE(IsOk(load_clip(reference, 1, reference_scene.clips.emplace_back())));
  ASSERT_TRUE(IsOk(build_node_graph(reference, reference_scene.graph)));
  ASSERT_TRUE(IsOk(load_clip(other, 0, other_scene.clips.emplace_back())));
  ASSERT_TRUE(IsOk(load_clip(other, 1, other_scene.clips.emplace_back())));
  ASSERT_TRUE(IsOk(build_node_graph(other, other_scene.graph)));
  ErrorMetrics metrics;
  ASSERT_TRUE(IsOk(compare_rigid_primitive(reference, reference_scene, other, other_scene, 1, 0, metrics)));
  EXPECT_EQ(metrics.vertices, 4u);
  EXPECT_EQ(metrics.frames, 3u) << "Walk's three keys; Blink does not move the node";
  EXPECT_NEAR(metrics.kg_percent, 8.38870, 1e-4);
  EXPECT_NEAR(metrics.max_error, 0.223607, 1e-5);
  ASSERT_TRUE(IsOk(compare_rigid_primitive(reference, reference_scene, reference, reference_scene, 1, 0, metrics)));
  EXPECT_EQ(metrics.kg_percent, 0);
  EXPECT_FALSE(compare_rigid_primitive(reference, reference_scene, other, other_scene, 0, 0, metrics).ok())
      << "node 0 has no mesh";
}

}  // namespace
}  // namespace segmorph
