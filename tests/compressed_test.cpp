// The extension's JSON side in memory: what compress_model writes around the streams (placeholder channels) and
// the validity rules decode_compressed_model checks (spec/README.md, "Validity").
#include <gtest/gtest.h>

#include <algorithm>

#include "bake.h"
#include "compressed.h"
#include "gltf_io.h"
#include "sample.h"
#include "segmorph_extension.h"

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
  if (status.ok()) status = compress_model(model, sampled, CodecSettings(), draco, report, [](const std::string&) {});
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
