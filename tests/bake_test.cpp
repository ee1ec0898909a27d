#include "bake/bake.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <memory>

#include "accessor.h"
#include "gltf/load.h"
#include "gltf/packing.h"
#include "gltf/save.h"
#include "sampling/sample.h"
#include "test_files.h"

namespace segmorph {
namespace {

using testing::bundled_samples;
using testing::have_shared_samples;
using testing::shared_samples;
using testing::temporary_path;

// A loaded and sampled file. Not movable: sampled nodes point into scene.
struct Sampled {
  tinygltf::Model model;
  Scene scene;
  std::vector<SampledNode> nodes;
};

std::unique_ptr<Sampled> sample_file(const std::string& path, Status* status) {
  auto sampled = std::make_unique<Sampled>();
  *status = load_gltf(path, sampled->model);
  if (status->ok()) *status = analyze_scene(sampled->model, sampled->scene);
  if (!status->ok()) return sampled;
  sampled->nodes.resize(sampled->scene.animated.size());
  for (size_t i = 0; i < sampled->nodes.size() && status->ok(); ++i)
    *status = sample_node(sampled->model, sampled->scene, sampled->scene.animated[i], SampleSettings(), sampled->nodes[i]);
  return sampled;
}

// One unit in the last place of the larger of |base| and |frame|: how far base + delta can be from a frame
// that float addition cannot reach exactly (a frame near zero when the base is not).
float within_ulp(float base, float frame) {
  const float larger = std::max(std::fabs(base), std::fabs(frame));
  return std::nextafter(larger, INFINITY) - larger;
}

// Bakes `path`, reads the result back and checks that it plays the frames sampled from the input: bit for bit
// where base + delta can represent them (always when `exact`, as for sequences stored that way), otherwise
// within one ulp of the base coordinate.
void expect_bake_round_trip(const std::string& path, bool exact) {
  SCOPED_TRACE(path);
  Status status;
  std::unique_ptr<Sampled> original = sample_file(path, &status);
  // Only the file of morph targets without an animation has nothing to bake (before, any file that reported it
  // passed: a regression that made every sample report it would have gone unseen).
  if (path.find("MorphPrimitivesTest") != std::string::npos) {
    EXPECT_EQ(status.code(), StatusCode::nothing_to_do) << status.message();
    return;
  }
  ASSERT_TRUE(status.ok()) << status.message();

  std::unique_ptr<Sampled> to_bake = sample_file(path, &status);
  ASSERT_TRUE(status.ok());
  ASSERT_TRUE(bake_model(to_bake->model, to_bake->scene, to_bake->nodes).ok());
  const std::string baked_path = temporary_path("round_trip.glb");
  ASSERT_TRUE(save_gltf(to_bake->model, baked_path).ok());

  std::unique_ptr<Sampled> baked = sample_file(baked_path, &status);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(baked->nodes.size(), original->nodes.size());
  EXPECT_TRUE(baked->model.skins.empty() || !original->model.skins.empty());

  for (const SampledNode& expected : original->nodes) {
    const SampledNode* actual = nullptr;
    for (const SampledNode& candidate : baked->nodes)
      if (source_node(baked->model.nodes[size_t(candidate.node->node)]) == expected.node->node) actual = &candidate;
    ASSERT_NE(actual, nullptr) << "node " << expected.node->node << " has no baked counterpart";
    EXPECT_EQ(actual->node->kind(), "morph");
    ASSERT_EQ(actual->node->clips.size(), expected.node->clips.size());
    ASSERT_EQ(actual->primitives.size(), expected.primitives.size());
    for (size_t p = 0; p < expected.primitives.size(); ++p)
      for (size_t c = 0; c < expected.node->clips.size(); ++c) {
        const FrameSequence& want = expected.primitives[p].clips[c];
        const FrameSequence& got = actual->primitives[p].clips[c];
        EXPECT_EQ(got.times, want.times) << "primitive " << p << " clip " << c;
        ASSERT_EQ(got.positions.size(), want.positions.size());
        const float* base = expected.primitives[p].clips[0].frame(0);
        const size_t values = want.vertex_count * 3;
        size_t inexact = 0, too_far = 0;
        for (size_t i = 0; i < want.positions.size(); ++i) {
          inexact += got.positions[i] != want.positions[i];
          too_far += std::fabs(got.positions[i] - want.positions[i]) > within_ulp(base[i % values], want.positions[i]);
        }
        EXPECT_EQ(too_far, 0u) << "primitive " << p << " clip " << c << ": values off by more than an ulp";
        if (exact) {
          EXPECT_EQ(inexact, 0u) << "primitive " << p << " clip " << c << ": values that differ";
        }
        EXPECT_EQ(got.triangles, want.triangles);
      }
  }

  // The weights are sparse: no animation output of the baked channels has a dense bufferView.
  for (const tinygltf::Animation& animation : baked->model.animations)
    for (const tinygltf::AnimationChannel& channel : animation.channels)
      if (channel.target_path == "weights") {
        const tinygltf::Accessor& output = baked->model.accessors[size_t(animation.samplers[size_t(channel.sampler)].output)];
        EXPECT_EQ(output.bufferView, -1);
      }
  // Nothing else is lost: materials, textures and images pass through, image bytes unchanged.
  EXPECT_EQ(baked->model.materials.size(), original->model.materials.size());
  EXPECT_EQ(baked->model.textures.size(), original->model.textures.size());
  ASSERT_EQ(baked->model.images.size(), original->model.images.size());
  EXPECT_EQ(baked->model.animations.size(), original->model.animations.size());
}

// Float numbers are written in the fewest digits that read back as the same float; a number that is not a float
// keeps every digit.
TEST(GltfWriter, FloatNumbersAreShortAndReadBackAsTheSameFloat) {
  tinygltf::Model model;
  tinygltf::Node node;
  const double rotation_w = double(0.99999988f);  // 1 − 2^-23: 0.9999998807907104 as a double, "0.9999999" as a float
  node.rotation = {0.0, 0.0, double(0.0004882812f), rotation_w};
  node.translation = {1234567.123456789, double(-0.1f), 0.0};  // a double (georeferenced, say), then a float
  node.name = "n";
  model.nodes.push_back(node);
  model.scenes.push_back(tinygltf::Scene());
  model.scenes[0].nodes = {0};
  model.defaultScene = 0;
  model.asset.version = "2.0";
  const std::string path = temporary_path("short_numbers.gltf");
  ASSERT_TRUE(save_gltf(model, path).ok());
  std::ifstream file(path);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("0.9999999\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("0.9999998807907104"), std::string::npos) << text;
  EXPECT_NE(text.find("-0.1,"), std::string::npos) << text;
  EXPECT_NE(text.find("1234567.123456789"), std::string::npos) << text;
  tinygltf::Model read;
  ASSERT_TRUE(load_gltf(path, read).ok());
  ASSERT_EQ(read.nodes.size(), 1u);
  EXPECT_EQ(float(read.nodes[0].rotation[3]), 0.99999988f);
  EXPECT_EQ(float(read.nodes[0].rotation[2]), 0.0004882812f);
  EXPECT_EQ(float(read.nodes[0].translation[1]), -0.1f);
  EXPECT_EQ(read.nodes[0].translation[0], 1234567.123456789);
}

TEST(Bake, BundledSamplesRoundTrip) {
  const std::vector<std::string> files = bundled_samples();
  ASSERT_GE(files.size(), 5u) << "samples/ is missing files";
  for (const std::string& path : files) expect_bake_round_trip(path, false);
}

TEST(Bake, SharedSamplesRoundTrip) {
  if (!have_shared_samples()) GTEST_SKIP() << "../shared/samples is absent: the large samples are not tested";
  for (const std::string& path : shared_samples())
    expect_bake_round_trip(path, path.find("/sequences/") != std::string::npos);
}

// baked_bytes bounds what a bake adds to the buffer, so that bake grows it once: growing by doubling copies the
// buffer and holds both copies for a moment (a 230 MB bake peaked at 366 MB that way; 257 MB with the room
// reserved). Sampled one node at a time, as the tool bakes. (The bound may be well above: deltas that turn out all
// zero take no bytes, RobotExpressive adds 15.5 MB to 36.1 MB reserved; room never written costs no memory.)
TEST(Bake, ReservedRoomHoldsWhatTheBakeAdds) {
  std::vector<std::string> files = bundled_samples();
  if (have_shared_samples())
    for (const std::string& path : shared_samples()) files.push_back(path);
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    tinygltf::Model model;
    Scene scene;
    ASSERT_TRUE(load_gltf(path, model).ok());
    if (analyze_scene(model, scene).code() == StatusCode::nothing_to_do) continue;
    const size_t before = model.buffers.empty() ? 0 : model.buffers.back().data.size();
    const size_t room = baked_bytes(model, scene, SampleSettings());
    ASSERT_TRUE(bake_model(model, scene, [&](size_t i, SampledNode& node) {
                  return sample_node(model, scene, scene.animated[i], SampleSettings(), node);
                }, room).ok());
    const size_t added = model.buffers.back().data.size() - before;
    EXPECT_GT(added, 0u);
    EXPECT_LE(added, room);
    EXPECT_EQ(model.buffers.back().data.capacity(), before + room) << "the buffer grew past its reservation";
  }
}

// release_target_data frees the released targets' bytes and keeps everything else as it was, every index kept: the
// other accessors read the same values, the targets read as zeros, and the file saves. An accessor a target shares
// with a kept use keeps its data.
TEST(GltfWriter, ReleasedTargetDataLeavesTheRestAsItWas) {
  tinygltf::Model model;
  ASSERT_TRUE(load_gltf(std::string(SEGMORPH_SAMPLES_DIR) + "/WavingFlag/flag.glb", model).ok());
  tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
  ASSERT_EQ(primitive.targets.size(), 3u);  // each accessor in a bufferView of its own, as Blender writes them
  const int shared = primitive.targets[1].at("POSITION");
  primitive.attributes["TEXCOORD_9"] = shared;  // the second target's accessor, used elsewhere too
  std::vector<std::vector<float>> before(model.accessors.size());
  size_t bytes_before = 0, bytes_after = 0;
  for (size_t a = 0; a < model.accessors.size(); ++a) ASSERT_TRUE(read_floats(model, int(a), "a", before[a]).ok());
  for (const tinygltf::Buffer& buffer : model.buffers) bytes_before += buffer.data.size();
  release_target_data(model, {true});
  for (const tinygltf::Buffer& buffer : model.buffers) bytes_after += buffer.data.size();
  std::vector<int> released;  // the five target accessors but the shared one
  for (const auto& target : primitive.targets)
    for (const auto& attribute : target)
      if (attribute.second != shared) released.push_back(attribute.second);
  ASSERT_EQ(released.size(), 5u);
  size_t released_bytes = 0;
  for (int a : released) {
    EXPECT_EQ(model.accessors[size_t(a)].bufferView, -1);
    released_bytes += before[size_t(a)].size() * sizeof(float);
  }
  EXPECT_EQ(bytes_after + released_bytes, bytes_before);
  for (size_t a = 0; a < model.accessors.size(); ++a) {
    std::vector<float> after;
    ASSERT_TRUE(read_floats(model, int(a), "a", after).ok());
    if (std::find(released.begin(), released.end(), int(a)) != released.end())
      EXPECT_EQ(after, std::vector<float>(before[a].size(), 0.0f));
    else
      EXPECT_EQ(after, before[a]) << "accessor " << a;
  }
  const std::string path = temporary_path("released_targets.glb");
  ASSERT_TRUE(save_gltf(model, path).ok());
  tinygltf::Model read;
  EXPECT_TRUE(load_gltf(path, read).ok());
}

// The sequences are one-hot morph animations whose frame f is exactly base + target f-1 at time f/30.
TEST(Bake, SequencesSampleToTheirStoredFrames) {
  if (!have_shared_samples()) GTEST_SKIP() << "../shared/samples is absent: the sequences are not tested";
  const std::vector<std::string> files = testing::gltf_files_under(std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/sequences");
  ASSERT_EQ(files.size(), 3u);
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    Status status;
    std::unique_ptr<Sampled> sampled = sample_file(path, &status);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(sampled->nodes.size(), 1u);
    const tinygltf::Primitive& primitive = sampled->model.meshes[0].primitives[0];
    const FrameSequence& clip = sampled->nodes[0].primitives[0].clips[0];
    ASSERT_EQ(clip.frame_count, primitive.targets.size() + 1);
    std::vector<float> base, delta;
    ASSERT_TRUE(read_floats(sampled->model, primitive.attributes.at("POSITION"), "base", base).ok());
    for (size_t f = 0; f < clip.frame_count; ++f) {
      EXPECT_EQ(clip.times[f], float(f / 30.0)) << "frame " << f;
      if (f > 0) {
        ASSERT_TRUE(read_floats(sampled->model, primitive.targets[f - 1].at("POSITION"), "target", delta).ok());
      }
      size_t mismatches = 0;
      for (size_t i = 0; i < base.size(); ++i) mismatches += clip.frame(f)[i] != (f ? base[i] + delta[i] : base[i]);
      ASSERT_EQ(mismatches, 0u) << "frame " << f;
    }
  }
}

TEST(Bake, SkinnedNodesLoseTheirSkinAndJointChannels) {
  Status status;
  std::unique_ptr<Sampled> sampled = sample_file(std::string(SEGMORPH_SAMPLES_DIR) + "/Fox/Fox.glb", &status);
  ASSERT_TRUE(status.ok()) << status.message();
  const size_t nodes_before = sampled->model.nodes.size();
  ASSERT_TRUE(bake_model(sampled->model, sampled->scene, sampled->nodes).ok());
  repack(sampled->model);
  tinygltf::Model& model = sampled->model;
  EXPECT_TRUE(model.skins.empty());
  EXPECT_EQ(model.nodes.size(), nodes_before + 1);  // the baked mesh's new root
  for (const tinygltf::Mesh& mesh : model.meshes)
    for (const tinygltf::Primitive& primitive : mesh.primitives) {
      EXPECT_EQ(primitive.attributes.count("JOINTS_0"), 0u);
      EXPECT_EQ(primitive.attributes.count("WEIGHTS_0"), 0u);
      EXPECT_EQ(primitive.indices, -1);  // Fox has no index buffer, and keeps none
    }
  // The joints moved nothing else, so each clip is left with its one weights channel.
  ASSERT_EQ(model.animations.size(), 3u);
  for (const tinygltf::Animation& animation : model.animations) {
    ASSERT_EQ(animation.channels.size(), 1u);
    EXPECT_EQ(animation.channels[0].target_path, "weights");
    EXPECT_EQ(animation.channels[0].target_node, int(nodes_before));
  }
  // The new node is a scene root.
  const std::vector<int>& roots = model.scenes[size_t(std::max(model.defaultScene, 0))].nodes;
  EXPECT_NE(std::find(roots.begin(), roots.end(), int(nodes_before)), roots.end());
}

TEST(Bake, RigidMeshesOnJointsKeepTheirChannels) {
  if (!have_shared_samples()) GTEST_SKIP() << "../shared/samples is absent";
  // RobotExpressive has meshes parented to bones without skinning (the head's morphed parts among them):
  // their bones must keep animating.
  Status status;
  std::unique_ptr<Sampled> sampled =
      sample_file(std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/gltf/RobotExpressive/RobotExpressive.glb", &status);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(bake_model(sampled->model, sampled->scene, sampled->nodes).ok());
  const tinygltf::Model& model = sampled->model;
  std::vector<int> parent(model.nodes.size(), -1);
  for (size_t n = 0; n < model.nodes.size(); ++n)
    for (int child : model.nodes[n].children) parent[size_t(child)] = int(n);
  size_t rigid = 0;
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    if (model.nodes[n].mesh < 0 || parent[n] < 0) continue;
    ++rigid;
    for (int a = parent[n]; a >= 0; a = parent[size_t(a)])
      for (size_t c = 0; c < sampled->scene.clips.size(); ++c) {
        bool original = false, kept = false;
        for (const Track& track : sampled->scene.clips[c].tracks) original = original || (track.node == a && track.path != TargetPath::weights);
        for (const tinygltf::AnimationChannel& channel : model.animations[c].channels)
          kept = kept || (channel.target_node == a && channel.target_path != "weights");
        EXPECT_EQ(kept, original) << "ancestor " << a << " of mesh node " << n << " in clip " << c;
      }
  }
  EXPECT_GT(rigid, 0u);
}

}  // namespace
}  // namespace segmorph
