// The extension's JSON side in memory: what compress_model writes around the streams (placeholder channels) and
// the validity rules decode_compressed_model checks (spec/README.md, "Validity").
#include "decoding/decode_file.h"
#include "encoding/compress_primitives.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "accessor.h"
#include "bake/bake.h"
#include "gltf/delivered_size.h"
#include "gltf/load.h"
#include "gltf/save.h"
#include "gltf_builder.h"
#include "pipeline.h"
#include "sampling/sample.h"
#include "segmorph_extension.h"
#include "test_files.h"
#include "verify/comparison.h"

namespace segmorph {
namespace {

// `path` loaded, baked and compressed as `segmorph encode --targets bake` does; `edit` changes the loaded model
// first.
tinygltf::Model encoded(const std::string& path, void (*edit)(tinygltf::Model&) = nullptr) {
  tinygltf::Model model;
  Scene scene;
  Status status = load_gltf(path, model);
  if (status.ok() && edit) edit(model);
  if (status.ok()) status = analyze_scene(model, scene);
  std::vector<SampledNode> sampled(scene.animated.size());
  for (size_t i = 0; status.ok() && i < sampled.size(); ++i)
    status = sample_node(model, scene, scene.animated[i], SampleSettings(), sampled[i]);
  if (status.ok()) status = bake_model(model, scene, sampled);
  CompressReport report;
  DracoSettings draco;
  std::vector<const SampledNode*> nodes;
  for (const SampledNode& node : sampled) nodes.push_back(&node);
  if (status.ok()) status = compress_model(model, nodes, CodecSettings(), draco, report, [](const std::string&) {});
  EXPECT_TRUE(status.ok()) << status.message();
  return model;
}

std::string simple_morph() { return std::string(SEGMORPH_SAMPLES_DIR) + "/SimpleMorph/SimpleMorph.gltf"; }
std::string rigged_simple() { return std::string(SEGMORPH_SAMPLES_DIR) + "/RiggedSimple/RiggedSimple.glb"; }

// The node of the first mesh whose primitives carry the extension.
int compressed_node(const tinygltf::Model& model) {
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const int mesh = model.nodes[n].mesh;
    if (mesh >= 0 && model.meshes[size_t(mesh)].primitives[0].extensions.count(kExtensionName)) return int(n);
  }
  return -1;
}

// A morph-animated grid of n × n vertices, saved as a .gltf, with `extra` vertices (copies of grid vertices: their
// positions and target displacements) and `extra_triangles` (indices into grid + extra).
std::string grid_with_copies(const std::string& name, const std::vector<uint32_t>& copied_from,
                             const std::vector<uint32_t>& extra_triangles) {
  const uint32_t n = 8;
  std::vector<float> positions, target;
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const float x = float(i) / float(n - 1), y = float(j) / float(n - 1);
      positions.insert(positions.end(), {x, y, 0});
      target.insert(target.end(), {0, 0.1f * x * y, 0.3f * std::sin(3 * x) * y});
    }
  for (uint32_t v : copied_from) {
    positions.insert(positions.end(), positions.begin() + v * 3, positions.begin() + v * 3 + 3);
    target.insert(target.end(), target.begin() + v * 3, target.begin() + v * 3 + 3);
  }
  std::vector<uint32_t> triangles;
  for (uint32_t j = 0; j + 1 < n; ++j)
    for (uint32_t i = 0; i + 1 < n; ++i) {
      const uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      triangles.insert(triangles.end(), {a, b, d, a, d, c});
    }
  triangles.insert(triangles.end(), extra_triangles.begin(), extra_triangles.end());
  test::GltfBuilder gltf;
  const int mesh = gltf.add_mesh(gltf.add_vec3(positions),
                                 gltf.add_uints(triangles, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
  gltf.add_target(mesh, {{"POSITION", gltf.add_vec3(target)}});
  gltf.model.meshes[size_t(mesh)].weights = {0};
  const int node = gltf.add_mesh_node(mesh);
  gltf.add_root(node);
  std::vector<float> times, weights;
  for (int k = 0; k <= 10; ++k) times.push_back(float(k) / 10), weights.push_back(std::sin(float(k) / 3));
  gltf.add_channel(gltf.add_animation(), node, "weights", times, weights);
  gltf.model.asset.version = "2.0";
  const std::string path = testing::temporary_path(name);
  EXPECT_TRUE(save_gltf(gltf.model, path).ok());
  return path;
}

// The decoded `model` against the file at `path`, as verify compares them.
void compare_decoded(const std::string& path, const tinygltf::Model& model, AnimationComparison& comparison) {
  tinygltf::Model original;
  Scene original_scene, decoded_scene;
  ASSERT_TRUE(load_gltf(path, original).ok());
  ASSERT_TRUE(analyze_scene(original, original_scene).ok());
  std::vector<SampledNode> sampled(original_scene.animated.size());
  for (size_t i = 0; i < sampled.size(); ++i)
    ASSERT_TRUE(sample_node(original, original_scene, original_scene.animated[i], SampleSettings(), sampled[i]).ok());
  ASSERT_TRUE(analyze_scene(model, decoded_scene).ok());
  ASSERT_TRUE(compare_animation(original, original_scene, sampled, model, decoded_scene, comparison).ok());
}

// Copies of a vertex are coded once, but never two corners of one triangle: Draco drops a triangle with a repeated
// vertex, and a vertex only such triangles use would go with it, and its animation (a grid with 400 copies in
// such triangles measured KG 28 %). Grid 8 × 8 (98 triangles), plus a copy of vertex 0 in a triangle with vertex
// 0, and three copies of vertex 5 forming a triangle of their own: every triangle and every motion survives.
// The codec's progress as printed: nothing in a primitive's first seconds, then each new stage and a stage's
// fraction at most every kCodecProgressSeconds.
// --targets auto keeps the file smaller as delivered: the estimate counts float keys that repeat (a weights
// animation) far below their bytes, and bytes without structure (a range coder's output) at their size.
TEST(Compressed, DeliveredEstimateShrinksRepeatedFloatsAndKeepsEntropyCodedBytes) {
  std::vector<unsigned char> keys(4096), noise(4096);
  for (size_t i = 0; i < keys.size() / 4; ++i) {
    const float weight = i % 8 < 4 ? 0.0f : 1.0f;
    std::memcpy(&keys[i * 4], &weight, 4);
  }
  uint32_t state = 12345;
  for (unsigned char& byte : noise) byte = uint8_t((state = state * 1664525u + 1013904223u) >> 24);
  EXPECT_LT(compressed_estimate(keys.data(), keys.size()), 0.1 * double(keys.size()));
  EXPECT_GT(compressed_estimate(noise.data(), noise.size()), 0.9 * double(noise.size()));
  EXPECT_LE(compressed_estimate(noise.data(), noise.size()), double(noise.size()));
  tinygltf::Model model;
  ASSERT_TRUE(load_gltf(std::string(SEGMORPH_SAMPLES_DIR) + "/AnimatedMorphCube/AnimatedMorphCube.glb", model).ok());
  const size_t delivered = glb_delivered_estimate(model), size = glb_size(model);
  EXPECT_GT(delivered, 0u);
  EXPECT_LT(delivered, size);
}

TEST(Compressed, CodecProgressIsQuietAtFirstThenNamesEachStage) {
  std::vector<std::string> lines;
  double seconds = 100;  // the clock codec_progress reads, moved by hand
  const CodecProgress report = codec_progress([&](const std::string& line) { lines.push_back(line); },
                                              "mesh 0 primitive 0", [&] { return seconds; });
  report("segmentation: heat diffusion", -1);
  seconds += kCodecQuietSeconds - 0.01;
  report("segmentation: Morse levels", -1);
  EXPECT_TRUE(lines.empty()) << "quiet for the first kCodecQuietSeconds";
  seconds += 0.02;
  report("rate control: measuring 12 steps", 0.25);
  report("rate control: measuring 12 steps", 0.5);  // the same stage, too soon
  seconds += kCodecProgressSeconds;
  report("rate control: measuring 12 steps", 0.75);  // the same stage, late enough
  report("writing the stream", -1);                   // a new stage: at once
  EXPECT_EQ(lines, (std::vector<std::string>{"mesh 0 primitive 0: rate control: measuring 12 steps (25 %)",
                                             "mesh 0 primitive 0: rate control: measuring 12 steps (75 %)",
                                             "mesh 0 primitive 0: writing the stream"}));
  EXPECT_FALSE(codec_progress({}, "mesh 0 primitive 0"));  // no printer, no callback
}

TEST(Compressed, CopiesMergeButNeverTwoCornersOfOneTriangle) {
  const std::string path = grid_with_copies("copies.gltf", {0, 5, 5, 5}, {0, 64, 1, 65, 66, 67});
  tinygltf::Model model = encoded(path);
  ASSERT_TRUE(decode_compressed_model(model).ok());
  size_t triangles = 0;
  for (const tinygltf::Mesh& mesh : model.meshes)
    for (const tinygltf::Primitive& primitive : mesh.primitives)
      if (!primitive.targets.empty()) triangles = size_t(model.accessors[size_t(primitive.indices)].count) / 3;
  EXPECT_EQ(triangles, 98u + 2u);
  AnimationComparison comparison;
  compare_decoded(path, model, comparison);
  EXPECT_LE(comparison.worst.kg_percent, 0.15);
}

// A primitive whose vertices are all copies of one still encodes (merged, its one triangle would have none left).
TEST(Compressed, PrimitiveOfCopiesOnlyEncodes) {
  test::GltfBuilder gltf;
  const int mesh = gltf.add_mesh(gltf.add_vec3({1, 2, 3, 1, 2, 3, 1, 2, 3}));
  gltf.add_target(mesh, {{"POSITION", gltf.add_vec3({0, 0, 1, 0, 0, 1, 0, 0, 1})}});
  gltf.model.meshes[size_t(mesh)].weights = {0};
  const int node = gltf.add_mesh_node(mesh);
  gltf.add_root(node);
  gltf.add_channel(gltf.add_animation(), node, "weights", {0, 0.5f, 1}, {0, 1, 0});
  gltf.model.asset.version = "2.0";
  const std::string path = testing::temporary_path("all_copies.gltf");
  ASSERT_TRUE(save_gltf(gltf.model, path).ok());
  tinygltf::Model model = encoded(path);
  ASSERT_TRUE(decode_compressed_model(model).ok());
  // It plays the original: the three copies at (1, 2, 3), lifted by up to 1 (before, only the decode's status was
  // checked).
  AnimationComparison comparison;
  compare_decoded(path, model, comparison);
  ASSERT_EQ(comparison.primitives.size(), 1u);
  EXPECT_EQ(comparison.vertices, 3u);
  EXPECT_GT(comparison.frames, 2u);
  EXPECT_LE(comparison.worst.max_error, 1e-3) << "in model units: the motion is 1";
}

// glTF forbids animating a node that has a matrix: the placeholder goes to an empty child made for it.
TEST(Compressed, PlaceholderOfANodeWithAMatrixTargetsAnEmptyChild) {
  tinygltf::Model model = encoded(simple_morph(), [](tinygltf::Model& m) {
    for (tinygltf::Node& node : m.nodes)
      if (node.mesh >= 0) {
        node.matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.5, 0, 0, 1};
        node.translation.clear();
      }
  });
  const int host = compressed_node(model);
  ASSERT_GE(host, 0);
  ASSERT_FALSE(model.nodes[size_t(host)].matrix.empty());
  size_t placeholders = 0;
  for (const tinygltf::Animation& animation : model.animations)
    for (const tinygltf::AnimationChannel& channel : animation.channels) {
      EXPECT_NE(channel.target_node, host) << "a channel animates a node with a matrix";
      if (!is_placeholder_channel(channel)) continue;
      ++placeholders;
      const tinygltf::Node& stand_in = model.nodes[size_t(channel.target_node)];
      EXPECT_EQ(stand_in.name, "segmorph placeholder");
      EXPECT_TRUE(stand_in.matrix.empty() && stand_in.mesh < 0 && stand_in.children.empty());
      const std::vector<int>& children = model.nodes[size_t(host)].children;
      EXPECT_NE(std::find(children.begin(), children.end(), channel.target_node), children.end());
    }
  EXPECT_EQ(placeholders, model.animations.size());
  EXPECT_TRUE(decode_compressed_model(model).ok());
}

// The positions-only decode of `model` against its decode: the same POSITION data (rest and targets), and no NORMAL
// target where the decode has one on every target. Returns the targets seen.
size_t expect_positions_of_the_decode(const tinygltf::Model& model) {
  tinygltf::Model whole = model, positions = model;
  EXPECT_TRUE(decode_compressed_model(whole).ok());
  EXPECT_TRUE(decode_compressed_positions(positions).ok());
  EXPECT_EQ(whole.meshes.size(), positions.meshes.size());
  size_t targets = 0, normal_targets = 0;
  for (size_t m = 0; m < std::min(whole.meshes.size(), positions.meshes.size()); ++m) {
    EXPECT_EQ(whole.meshes[m].primitives.size(), positions.meshes[m].primitives.size());
    for (size_t p = 0; p < std::min(whole.meshes[m].primitives.size(), positions.meshes[m].primitives.size()); ++p) {
      const tinygltf::Primitive& a = whole.meshes[m].primitives[p];
      const tinygltf::Primitive& b = positions.meshes[m].primitives[p];
      EXPECT_EQ(a.targets.size(), b.targets.size());
      std::vector<float> x, y;
      EXPECT_TRUE(read_floats(whole, a.attributes.at("POSITION"), "whole", x).ok());
      EXPECT_TRUE(read_floats(positions, b.attributes.at("POSITION"), "positions", y).ok());
      EXPECT_EQ(x, y);
      for (size_t t = 0; t < std::min(a.targets.size(), b.targets.size()); ++t) {
        ++targets;
        normal_targets += a.targets[t].count("NORMAL");
        EXPECT_EQ(b.targets[t].count("NORMAL"), 0u);
        EXPECT_TRUE(read_floats(whole, a.targets[t].at("POSITION"), "whole", x).ok());
        EXPECT_TRUE(read_floats(positions, b.targets[t].at("POSITION"), "positions", y).ok());
        EXPECT_EQ(x, y) << "mesh " << m << " primitive " << p << " target " << t;
      }
    }
  }
  EXPECT_EQ(normal_targets, targets);  // a decode turns the normals of every frame (target)
  return targets;
}

// What the encoder's own measurements decode: the same positions as a decode, without the normals' morph targets
// (turning every frame's normals is most of a decode's work there): baked frames of a skin, and kept morph targets.
TEST(Compressed, PositionsOnlyDecodeHasTheDecodesPositionsAndNoNormalTargets) {
  const tinygltf::Model frames = encoded(rigged_simple());
  EXPECT_GT(expect_positions_of_the_decode(frames), 0u);
  tinygltf::Model positions = frames;
  ASSERT_TRUE(decode_compressed_positions(positions).ok());
  tinygltf::Model whole = frames;
  ASSERT_TRUE(decode_compressed_model(whole).ok());
  AnimationComparison measured, reference;
  compare_decoded(rigged_simple(), positions, measured);
  compare_decoded(rigged_simple(), whole, reference);
  EXPECT_EQ(measured.worst.kg_percent, reference.worst.kg_percent);

  // AnimatedMorphCube's targets carry NORMAL: encoded keeping them.
  Model original, kept;
  const std::string cube = std::string(SEGMORPH_SAMPLES_DIR) + "/AnimatedMorphCube/AnimatedMorphCube.glb";
  ASSERT_TRUE(Model::load(cube, original).ok());
  EncodeSettings settings;
  settings.targets = EncodeSettings::Targets::keep;
  ASSERT_TRUE(encode(original, settings, kept).ok());
  EXPECT_GT(expect_positions_of_the_decode(kept.data().gltf), 0u);
}

// Rules 1, 3 and 7: a compressed primitive is a triangle list, its node has no skin, clip times are FLOAT SCALAR.
TEST(Compressed, DecodeRefusesWhatTheValidityRulesForbid) {
  const tinygltf::Model good = encoded(rigged_simple());
  const int host = compressed_node(good);
  ASSERT_GE(host, 0);
  const int mesh = good.nodes[size_t(host)].mesh;
  {
    tinygltf::Model model = good;
    EXPECT_TRUE(decode_compressed_model(model).ok());
  }
  {
    tinygltf::Model model = good;
    model.meshes[size_t(mesh)].primitives[0].mode = TINYGLTF_MODE_LINE;
    const Status status = decode_compressed_model(model);
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find("only triangle primitives"), std::string::npos) << status.message();
  }
  {
    tinygltf::Model model = good;
    model.skins.emplace_back();
    model.skins.back().joints = {host};
    model.nodes[size_t(host)].skin = int(model.skins.size()) - 1;
    const Status status = decode_compressed_model(model);
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find("must not have a skin"), std::string::npos) << status.message();
  }
  {
    tinygltf::Model model = good;
    CompressedPrimitive compressed;
    ASSERT_TRUE(parse_compressed_primitive(
                    model.meshes[size_t(mesh)].primitives[0].extensions.at(kExtensionName), compressed)
                    .ok());
    // A copy of the clip's times (which the placeholder channel also reads) as unsigned bytes.
    tinygltf::Accessor bytes = model.accessors[size_t(compressed.clips[0].times)];
    bytes.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    bytes.minValues.clear();
    bytes.maxValues.clear();
    model.accessors.push_back(bytes);
    compressed.clips[0].times = int(model.accessors.size()) - 1;
    for (tinygltf::Primitive& primitive : model.meshes[size_t(mesh)].primitives)
      primitive.extensions[kExtensionName] = compressed_primitive_value(compressed);
    const Status status = decode_compressed_model(model);
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find("FLOAT SCALAR"), std::string::npos) << status.message();
  }
}

}  // namespace
}  // namespace segmorph
