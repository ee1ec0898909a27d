#include "bake/bake.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <new>

#include "accessor.h"
#include "common/topology.h"
#include "decode/normals.h"

namespace segmorph {
namespace {

bool all_zero(const std::vector<float>& values) {
  for (float v : values)
    if (v != 0) return false;
  return true;
}

// An object-valued extras with `key` set to `value` (other members kept).
tinygltf::Value with_member(const tinygltf::Value& extras, const std::string& key, tinygltf::Value value) {
  tinygltf::Value::Object object;
  if (extras.IsObject()) object = extras.Get<tinygltf::Value::Object>();
  object[key] = std::move(value);
  return tinygltf::Value(std::move(object));
}

// Nodes reachable from each scene's roots.
std::vector<std::vector<bool>> scene_members(const tinygltf::Model& model) {
  std::vector<std::vector<bool>> members;
  for (const tinygltf::Scene& scene : model.scenes) {
    std::vector<bool> in(model.nodes.size(), false);
    std::vector<int> stack(scene.nodes.begin(), scene.nodes.end());
    while (!stack.empty()) {
      const int n = stack.back();
      stack.pop_back();
      if (n < 0 || size_t(n) >= in.size() || in[size_t(n)]) continue;
      in[size_t(n)] = true;
      stack.insert(stack.end(), model.nodes[size_t(n)].children.begin(), model.nodes[size_t(n)].children.end());
    }
    members.push_back(std::move(in));
  }
  return members;
}

// The baked primitive: base frame, derived normals and tangents, one target per frame but the first.
tinygltf::Primitive bake_primitive(const tinygltf::Primitive& original, const SampledPrimitive& sampled, bool skinned,
                                   bool write_frames, AccessorWriter& writer) {
  tinygltf::Primitive primitive = original;
  primitive.targets.clear();
  if (skinned)
    for (auto it = primitive.attributes.begin(); it != primitive.attributes.end();)
      it = (it->first.rfind("JOINTS_", 0) == 0 || it->first.rfind("WEIGHTS_", 0) == 0) ? primitive.attributes.erase(it)
                                                                                        : std::next(it);

  const FrameSequence& first = sampled.clips[0];
  const size_t vertex_count = first.vertex_count;
  const float* base = first.frame(0);
  primitive.attributes["POSITION"] =
      writer.add_floats(base, vertex_count, TINYGLTF_TYPE_VEC3, true, TINYGLTF_TARGET_ARRAY_BUFFER);

  const bool has_normals = !sampled.rest_normals.empty();
  AnimationDecoder* decoder = sampled.normals.get();
  WeldedTopology topology;
  std::vector<float> base_normals, frame_normals(vertex_count * 3);
  std::vector<double> base_geometric;
  // A frame's normals: a decoded primitive's turned by its decoder from the rest mesh (the Draco base) as every
  // runtime turns them, a sampled one's from the base frame's.
  auto turn = [&](const float* frame, float* out) {
    if (!decoder) return deform_normals(base_geometric, base_normals.data(), frame, topology, out);
    // The arguments are the decoder's own mesh's: it fails only when memory runs out.
    if (!decoder->turn_normals(sampled.rest_normals.data(), frame, 1, out, vertex_count * 3).ok())
      throw std::bad_alloc();
  };
  if (has_normals || !sampled.rest_tangents.empty()) {
    // The primitive's own welding and rest surface: a sampled primitive's normals turn on them, and any tangents.
    std::vector<double> rest_geometric;
    if (!decoder || !sampled.rest_tangents.empty()) {
      topology = weld_topology(sampled.clips);
      rest_geometric = welded_vertex_normals(sampled.rest_positions.data(), topology);
    }
    if (has_normals) {
      base_normals.resize(vertex_count * 3);
      if (decoder) {
        turn(base, base_normals.data());
      } else {
        deform_normals(rest_geometric, sampled.rest_normals.data(), base, topology, base_normals.data());
        base_geometric = welded_vertex_normals(base, topology);
      }
      primitive.attributes["NORMAL"] =
          writer.add_floats(base_normals.data(), vertex_count, TINYGLTF_TYPE_VEC3, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    }
    if (!sampled.rest_tangents.empty()) {
      // Tangents turn with the surface from rest to the base frame; their handedness (w) is kept.
      std::vector<float> directions(vertex_count * 3), turned(vertex_count * 3), tangents = sampled.rest_tangents;
      for (size_t v = 0; v < vertex_count; ++v)
        for (int c = 0; c < 3; ++c) directions[v * 3 + size_t(c)] = tangents[v * 4 + size_t(c)];
      deform_normals(rest_geometric, directions.data(), base, topology, turned.data());
      for (size_t v = 0; v < vertex_count; ++v)
        for (int c = 0; c < 3; ++c) tangents[v * 4 + size_t(c)] = turned[v * 3 + size_t(c)];
      primitive.attributes["TANGENT"] =
          writer.add_floats(tangents.data(), vertex_count, TINYGLTF_TYPE_VEC4, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    }
  }

  std::vector<float> delta(vertex_count * 3);
  for (size_t c = 0; c < sampled.clips.size(); ++c)
    for (size_t f = (c == 0 ? 1 : 0); f < sampled.clips[c].frame_count; ++f) {
      const float* frame = sampled.clips[c].frame(f);
      std::map<std::string, int> target;
      if (!write_frames) {
        target["POSITION"] = writer.add_zeros(vertex_count, TINYGLTF_TYPE_VEC3, true);
        if (has_normals) target["NORMAL"] = writer.add_zeros(vertex_count, TINYGLTF_TYPE_VEC3, false);
        primitive.targets.push_back(std::move(target));
        continue;
      }
      for (size_t i = 0; i < delta.size(); ++i) delta[i] = frame[i] - base[i];
      target["POSITION"] = all_zero(delta) ? writer.add_zeros(vertex_count, TINYGLTF_TYPE_VEC3, true)
                                           : writer.add_floats(delta.data(), vertex_count, TINYGLTF_TYPE_VEC3, true, 0);
      if (has_normals) {
        turn(frame, frame_normals.data());
        for (size_t i = 0; i < delta.size(); ++i) delta[i] = frame_normals[i] - base_normals[i];
        target["NORMAL"] = all_zero(delta) ? writer.add_zeros(vertex_count, TINYGLTF_TYPE_VEC3, false)
                                           : writer.add_floats(delta.data(), vertex_count, TINYGLTF_TYPE_VEC3, false, 0);
      }
      primitive.targets.push_back(std::move(target));
    }
  return primitive;
}

}  // namespace

int source_node(const tinygltf::Node& node) {
  if (!node.extras.IsObject() || !node.extras.Has("segmorph")) return -1;
  const tinygltf::Value& provenance = node.extras.Get("segmorph");
  return provenance.IsObject() && provenance.Has("source_node") && provenance.Get("source_node").IsNumber()
             ? provenance.Get("source_node").GetNumberAsInt()
             : -1;
}

namespace {

// The references bake_model follows, checked first: decode_compressed_model gets there without analyze_scene, and
// analyze_scene checks skins only on nodes with a mesh.
Status check_references(const tinygltf::Model& model) {
  NodeGraph graph;
  SEGMORPH_RETURN_IF_ERROR(build_node_graph(model, graph));
  for (size_t n = 0; n < model.nodes.size(); ++n)
    if (model.nodes[n].skin >= 0 && size_t(model.nodes[n].skin) >= model.skins.size())
      return Status(StatusCode::bad_data, "node " + std::to_string(n) + " names a skin that does not exist");
  for (size_t s = 0; s < model.skins.size(); ++s)
    for (int joint : model.skins[s].joints)
      if (joint < 0 || size_t(joint) >= model.nodes.size())
        return Status(StatusCode::bad_data, "skin " + std::to_string(s) + " names a joint that does not exist");
  return Status::Ok();
}

// What baking the nodes changed, for the channels: the node carrying each original animated node's baked mesh, the
// skins baked, the number of targets of each sampled node.
struct Baked {
  std::vector<int> host;  // original animated node -> node carrying its baked mesh (-1: not baked)
  std::vector<bool> skin;
  std::vector<size_t> target_count;
};

// Bakes sampled node i: a new mesh of morph targets, named after the clips' frames; a skinned node's goes on a new
// root node (skinned vertices are in model space), an unskinned node's stays on the node.
void bake_node(tinygltf::Model& model, const Scene& scene, const SampledNode& sampled, size_t i, bool write_frames,
               const std::vector<std::vector<bool>>& members, AccessorWriter& writer, Baked& baked) {
  const AnimatedNode& node = *sampled.node;
  const bool skinned = node.skin >= 0;
  tinygltf::Mesh mesh = model.meshes[size_t(node.mesh)];
  mesh.weights.clear();
  std::vector<tinygltf::Value> names;
  for (size_t c = 0; c < node.clips.size(); ++c) {
    const FrameSequence& clip = sampled.primitives[0].clips[c];
    for (size_t f = (c == 0 ? 1 : 0); f < clip.frame_count; ++f)
      names.emplace_back(scene.clips[size_t(node.clips[c])].name + " frame " + std::to_string(f));
  }
  baked.target_count[i] = names.size();
  mesh.extras = with_member(mesh.extras, "targetNames", tinygltf::Value(names));
  for (size_t p = 0; p < mesh.primitives.size(); ++p)
    mesh.primitives[p] = bake_primitive(mesh.primitives[p], sampled.primitives[p], skinned, write_frames, writer);
  model.meshes.push_back(std::move(mesh));
  const int mesh_index = int(model.meshes.size()) - 1;

  // Where the node came from, unless it already says (a decoded file keeps the original's index).
  const tinygltf::Value& existing = model.nodes[size_t(node.node)].extras;
  tinygltf::Value::Object provenance;
  provenance["source_node"] = tinygltf::Value(node.node);
  if (existing.IsObject() && existing.Has("segmorph") && existing.Get("segmorph").IsObject())
    provenance = existing.Get("segmorph").Get<tinygltf::Value::Object>();
  if (!skinned) {
    tinygltf::Node& original = model.nodes[size_t(node.node)];
    original.mesh = mesh_index;
    original.weights.clear();
    original.extras = with_member(original.extras, "segmorph", tinygltf::Value(provenance));
    baked.host[size_t(node.node)] = node.node;
    return;
  }
  tinygltf::Node host;
  host.name = model.nodes[size_t(node.node)].name;
  host.mesh = mesh_index;
  host.extras = with_member(host.extras, "segmorph", tinygltf::Value(provenance));
  tinygltf::Node& original = model.nodes[size_t(node.node)];
  original.mesh = -1;
  original.skin = -1;
  original.weights.clear();
  model.nodes.push_back(std::move(host));
  baked.host.push_back(-1);
  baked.host[size_t(node.node)] = int(model.nodes.size()) - 1;
  for (size_t s = 0; s < model.scenes.size(); ++s)
    if (members[s][size_t(node.node)]) model.scenes[s].nodes.push_back(baked.host[size_t(node.node)]);
  baked.skin[size_t(node.skin)] = true;
}

// Nodes whose transforms still matter: they or a descendant carry a mesh, camera or extension, or are joints of a
// skin still in use. `baked_joint`: the joints of baked skins.
std::vector<bool> needed_nodes(const tinygltf::Model& model, const std::vector<bool>& baked_skin,
                               std::vector<bool>& baked_joint) {
  std::vector<bool> needed(model.nodes.size(), false), live_joint(model.nodes.size(), false);
  baked_joint.assign(model.nodes.size(), false);
  for (const tinygltf::Node& node : model.nodes)
    if (node.skin >= 0)
      for (int joint : model.skins[size_t(node.skin)].joints) live_joint[size_t(joint)] = true;
  for (size_t s = 0; s < model.skins.size(); ++s)
    if (baked_skin[s])
      for (int joint : model.skins[s].joints) baked_joint[size_t(joint)] = true;
  std::vector<int> parent(model.nodes.size(), -1);
  for (size_t n = 0; n < model.nodes.size(); ++n)
    for (int child : model.nodes[n].children) parent[size_t(child)] = int(n);
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tinygltf::Node& node = model.nodes[n];
    if (node.mesh >= 0 || node.camera >= 0 || !node.extensions.empty() || live_joint[n])
      for (int m = int(n); m >= 0 && !needed[size_t(m)]; m = parent[size_t(m)]) needed[size_t(m)] = true;
  }
  return needed;
}

// Clip c of sampled node i as a weights channel of its animation: one-hot sparse weights on the clip's targets.
tinygltf::AnimationChannel clip_channel(tinygltf::Animation& animation, const SampledNode& sampled, size_t c,
                                        size_t targets, int host, AccessorWriter& writer) {
  const FrameSequence& clip = sampled.primitives[0].clips[c];
  // Target of frame f of this clip: frames of earlier clips come first; the node's very first frame is the base.
  size_t first_target = 0;
  for (size_t d = 0; d < c; ++d) first_target += sampled.primitives[0].clips[d].frame_count;
  std::vector<uint32_t> indices;
  std::vector<float> ones;
  for (size_t f = 0; f < clip.frame_count; ++f) {
    if (c == 0 && f == 0) continue;
    indices.push_back(uint32_t(f * targets + first_target + f - 1));
    ones.push_back(1.0f);
  }
  tinygltf::AnimationSampler sampler;
  sampler.input = writer.add_floats(clip.times.data(), clip.frame_count, TINYGLTF_TYPE_SCALAR, true, 0);
  sampler.output = indices.empty() ? writer.add_zeros(clip.frame_count * targets, TINYGLTF_TYPE_SCALAR, false)
                                   : writer.add_sparse_floats(clip.frame_count * targets, TINYGLTF_TYPE_SCALAR, indices, ones);
  sampler.interpolation = sampled.clip_is_step[c] ? "STEP" : "LINEAR";
  animation.samplers.push_back(sampler);
  tinygltf::AnimationChannel channel;
  channel.sampler = int(animation.samplers.size()) - 1;
  channel.target_node = host;
  channel.target_path = "weights";
  return channel;
}

// Each animation: the weights channels of baked nodes and the channels of joints that matter to nothing go; each
// clip of a baked node becomes a weights channel on its host.
void rebuild_channels(tinygltf::Model& model, const Scene& scene, const std::vector<const SampledNode*>& sampled,
                      const Baked& baked, AccessorWriter& writer) {
  std::vector<bool> baked_joint;
  const std::vector<bool> needed = needed_nodes(model, baked.skin, baked_joint);
  for (size_t a = 0; a < model.animations.size(); ++a) {
    tinygltf::Animation& animation = model.animations[a];
    std::vector<tinygltf::AnimationChannel> channels;
    for (const tinygltf::AnimationChannel& channel : animation.channels) {
      const int n = channel.target_node;
      const bool valid = n >= 0 && size_t(n) < baked.host.size();
      if (valid && channel.target_path == "weights" && baked.host[size_t(n)] >= 0) continue;  // replaced below
      if (valid && channel.target_path != "weights" && baked_joint[size_t(n)] && !needed[size_t(n)]) continue;
      channels.push_back(channel);
    }
    for (size_t i = 0; i < sampled.size(); ++i) {
      const AnimatedNode& node = *sampled[i]->node;
      for (size_t c = 0; c < node.clips.size(); ++c) {
        if (size_t(scene.clips[size_t(node.clips[c])].animation) != a) continue;
        if (baked.target_count[i] == 0) continue;  // a single frame: nothing to play
        channels.push_back(
            clip_channel(animation, *sampled[i], c, baked.target_count[i], baked.host[size_t(node.node)], writer));
      }
    }
    animation.channels = std::move(channels);
  }
}

// Bakes `count` nodes, node i given by next(i, node) just before it is baked and left to done(i) after; the channels
// read only the nodes' clip times and frame counts.
Status bake_nodes(tinygltf::Model& model, const Scene& scene, size_t count,
                  const std::function<Status(size_t i, const SampledNode*& node)>& next,
                  const std::function<void(size_t i)>& done, size_t expected_bytes, bool write_frames = true) {
  SEGMORPH_RETURN_IF_ERROR(check_references(model));
  AccessorWriter writer(model);
  writer.reserve(expected_bytes);
  const std::vector<std::vector<bool>> members = scene_members(model);
  Baked baked;
  baked.host.assign(model.nodes.size(), -1);
  baked.skin.assign(model.skins.size(), false);
  baked.target_count.assign(count, 0);
  std::vector<const SampledNode*> sampled(count, nullptr);
  for (size_t i = 0; i < count; ++i) {
    SEGMORPH_RETURN_IF_ERROR(next(i, sampled[i]));
    bake_node(model, scene, *sampled[i], i, write_frames, members, writer, baked);
    if (done) done(i);
  }
  rebuild_channels(model, scene, sampled, baked, writer);
  return Status::Ok();
}

}  // namespace

Status bake_model(tinygltf::Model& model, const Scene& scene, const std::vector<SampledNode>& sampled) {
  return bake_nodes(
      model, scene, sampled.size(),
      [&](size_t i, const SampledNode*& node) {
        node = &sampled[i];
        return Status::Ok();
      },
      {}, 0);
}

Status bake_model(tinygltf::Model& model, const Scene& scene, const std::vector<const SampledNode*>& sampled,
                  bool write_frames) {
  return bake_nodes(
      model, scene, sampled.size(),
      [&](size_t i, const SampledNode*& node) {
        node = sampled[i];
        return Status::Ok();
      },
      {}, 0, write_frames);
}

Status bake_model(tinygltf::Model& model, const Scene& scene, const NodeSampler& sample, size_t expected_bytes) {
  std::vector<SampledNode> nodes(scene.animated.size());
  return bake_nodes(
      model, scene, nodes.size(),
      [&](size_t i, const SampledNode*& node) {
        node = &nodes[i];
        return sample(i, nodes[i]);
      },
      [&](size_t i) {  // the frames go; the clips' times and frame counts stay for the channels
        for (SampledPrimitive& primitive : nodes[i].primitives)
          for (FrameSequence& clip : primitive.clips) std::vector<float>().swap(clip.positions);
      },
      expected_bytes);
}

size_t baked_bytes(const tinygltf::Model& model, const Scene& scene, const SampleSettings& settings) {
  size_t bytes = 0;
  for (const AnimatedNode& node : scene.animated) {
    size_t frames = 0;
    for (int clip : node.clips) frames += frame_times(scene, model, node, clip, settings).size();
    for (const tinygltf::Primitive& primitive : model.meshes[size_t(node.mesh)].primitives) {
      // An attribute's element count, as far as its bufferView holds them (a damaged file reserves no more than it
      // has; reading it fails later, with the reason).
      const auto count = [&](const char* name) -> size_t {
        const auto found = primitive.attributes.find(name);
        if (found == primitive.attributes.end() || found->second < 0 || size_t(found->second) >= model.accessors.size())
          return 0;
        const tinygltf::Accessor& accessor = model.accessors[size_t(found->second)];
        const unsigned char* data = nullptr;
        size_t size = 0;
        const size_t element = size_t(bytes_of_component(accessor.componentType) * components_of_type(accessor.type));
        if (element == 0 || !buffer_view_bytes(model, accessor.bufferView, name, &data, &size).ok()) return 0;
        return std::min(accessor.count, size / element);
      };
      const size_t vertices = count("POSITION"), normals = count("NORMAL") ? 1 : 0;
      bytes += vertices * 4 * (3 + 3 * normals + (count("TANGENT") ? 4 : 0));  // the base
      bytes += (frames > 0 ? frames - 1 : 0) * vertices * 4 * 3 * (1 + normals);
    }
  }
  return bytes + bytes / 16 + (size_t(1) << 20);
}

std::vector<std::vector<float>> target_displacements(const FrameSequence& frames, const std::vector<float>& base) {
  std::vector<std::vector<float>> deltas(frames.frame_count, std::vector<float>(base.size()));
  for (size_t t = 0; t < frames.frame_count; ++t)
    for (size_t i = 0; i < base.size(); ++i) deltas[t][i] = frames.frame(t)[i] - base[i];
  return deltas;
}

}  // namespace segmorph
