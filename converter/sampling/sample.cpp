#include "sampling/sample.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>

#include "accessor.h"

namespace segmorph {
namespace {

std::string node_label(const tinygltf::Model& model, int node) {
  const std::string& name = model.nodes[size_t(node)].name;
  return "node " + std::to_string(node) + (name.empty() ? "" : " \"" + name + "\"");
}

// Nodes whose transforms move a skin's vertices: its joints and all their ancestors.
std::vector<bool> skin_dependencies(const tinygltf::Model& model, const NodeGraph& graph, int skin) {
  std::vector<bool> relevant(model.nodes.size(), false);
  if (skin < 0) return relevant;
  for (int joint : model.skins[size_t(skin)].joints)
    for (int n = joint; n >= 0 && !relevant[size_t(n)]; n = graph.parent[size_t(n)]) relevant[size_t(n)] = true;
  return relevant;
}

// Calls f(track) for every track of `clip` that moves the vertices of `node`.
template <typename F>
void for_each_moving_track(const tinygltf::Model& model, const NodeGraph& graph, const AnimatedNode& node,
                           const Clip& clip, F f) {
  const std::vector<bool> relevant = skin_dependencies(model, graph, node.skin);
  for (const Track& track : clip.tracks) {
    const bool moves =
        track.path == TargetPath::weights ? (node.morphed && track.node == node.node) : relevant[size_t(track.node)];
    if (moves) f(track);
  }
}

std::vector<float> regular_grid(double start, double end, double fps) {
  std::vector<float> times;
  const double duration = end - start;
  const long steps = long(std::floor(duration * fps + 1e-9));
  for (long k = 0; k <= steps; ++k) times.push_back(float(start + double(k) / fps));
  if (end - double(times.back()) > 1e-6 * std::max(1.0, duration)) times.push_back(float(end));
  // Rounding to float must not produce equal or decreasing times.
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

// The vertex data of one primitive that sampling needs, read and checked once.
struct PrimitiveInput {
  size_t vertex_count = 0;
  std::vector<float> positions;            // V × 3
  std::vector<std::vector<float>> deltas;  // targets × (V × 3); empty vector for a target without POSITION
  std::vector<uint32_t> influence_offset;  // V + 1 offsets into joints/weights (skinned only)
  std::vector<uint32_t> influence_joint;   // index into the skin's joints
  std::vector<double> influence_weight;    // normalized to sum 1 per vertex
};

Status read_skin_influences(const tinygltf::Model& model, const tinygltf::Primitive& primitive, size_t joint_count,
                            const std::string& what, PrimitiveInput& input) {
  const size_t vertex_count = input.vertex_count;
  std::vector<std::vector<std::pair<uint32_t, double>>> per_vertex(vertex_count);
  std::vector<uint32_t> first_joint(vertex_count, 0);  // JOINTS_0.x: what a vertex with no weight follows
  for (int set = 0;; ++set) {
    auto joints_it = primitive.attributes.find("JOINTS_" + std::to_string(set));
    auto weights_it = primitive.attributes.find("WEIGHTS_" + std::to_string(set));
    if (joints_it == primitive.attributes.end() && weights_it == primitive.attributes.end()) break;
    if (joints_it == primitive.attributes.end() || weights_it == primitive.attributes.end())
      return Status(StatusCode::bad_data, what + ": JOINTS_" + std::to_string(set) + " and WEIGHTS_" +
                                              std::to_string(set) + " must come together");
    std::vector<uint32_t> joints;
    std::vector<float> weights;
    int joint_components = 0, weight_components = 0;
    SEGMORPH_RETURN_IF_ERROR(
        read_uints(model, joints_it->second, what + " " + joints_it->first, joints, &joint_components));
    SEGMORPH_RETURN_IF_ERROR(
        read_floats(model, weights_it->second, what + " " + weights_it->first, weights, &weight_components));
    if (joint_components != 4 || weight_components != 4 || joints.size() != vertex_count * 4 ||
        weights.size() != vertex_count * 4)
      return Status(StatusCode::bad_data, what + ": JOINTS_" + std::to_string(set) + "/WEIGHTS_" + std::to_string(set) +
                                              " must be VEC4 with one element per vertex");
    if (set == 0)
      for (size_t v = 0; v < vertex_count; ++v) first_joint[v] = joints[v * 4];
    for (size_t v = 0; v < vertex_count; ++v)
      for (int c = 0; c < 4; ++c) {
        const double weight = weights[v * 4 + size_t(c)];
        const uint32_t joint = joints[v * 4 + size_t(c)];
        if (weight == 0 && !(set == 0 && c == 0)) continue;
        if (joint >= joint_count)
          return Status(StatusCode::bad_data, what + ": vertex " + std::to_string(v) + " names joint " +
                                                  std::to_string(joint) + " of a skin with " +
                                                  std::to_string(joint_count) + " joints");
        if (weight < 0) return Status(StatusCode::bad_data, what + ": negative skin weight");
        if (weight > 0) per_vertex[v].push_back({joint, weight});
      }
  }
  input.influence_offset.assign(1, 0);
  for (size_t v = 0; v < vertex_count; ++v) {
    // Weights that do not sum to 1 are scaled to do so, and a vertex with no weight follows the first
    // joint it names, as three.js's GLTFLoader (SkinnedMesh.normalizeSkinWeights) does.
    double sum = 0;
    for (const auto& influence : per_vertex[v]) sum += influence.second;
    if (sum > 0) {
      for (const auto& influence : per_vertex[v]) {
        input.influence_joint.push_back(influence.first);
        input.influence_weight.push_back(influence.second / sum);
      }
    } else {
      input.influence_joint.push_back(first_joint[v]);
      input.influence_weight.push_back(1.0);
    }
    input.influence_offset.push_back(uint32_t(input.influence_joint.size()));
  }
  return Status::Ok();
}

}  // namespace

Status read_triangles(const tinygltf::Model& model, const tinygltf::Primitive& primitive, size_t vertex_count,
                      const std::string& what, std::vector<uint32_t>& triangles) {
  std::vector<uint32_t> indices;
  if (primitive.indices >= 0) {
    SEGMORPH_RETURN_IF_ERROR(read_uints(model, primitive.indices, what + " indices", indices));
    for (uint32_t i : indices)
      if (i >= vertex_count) return Status(StatusCode::bad_data, what + ": an index exceeds the vertex count");
  } else {
    indices.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) indices[i] = uint32_t(i);
  }
  triangles.clear();
  switch (primitive.mode) {
    case TINYGLTF_MODE_TRIANGLES:
      triangles.assign(indices.begin(), indices.begin() + long(indices.size() / 3 * 3));
      break;
    case TINYGLTF_MODE_TRIANGLE_STRIP:
      for (size_t i = 2; i < indices.size(); ++i) {
        const bool even = i % 2 == 0;  // every other triangle of a strip flips to keep the winding
        triangles.insert(triangles.end(), {indices[i - 2], indices[even ? i - 1 : i], indices[even ? i : i - 1]});
      }
      break;
    case TINYGLTF_MODE_TRIANGLE_FAN:
      for (size_t i = 2; i < indices.size(); ++i)
        triangles.insert(triangles.end(), {indices[i - 1], indices[i], indices[0]});
      break;
    default:
      break;  // points and lines: no surface
  }
  return Status::Ok();
}

std::string node_name(const tinygltf::Model& model, int node) {
  const std::string& name = model.nodes[size_t(node)].name;
  return name.empty() ? "node " + std::to_string(node) : name;
}

std::string AnimatedNode::kind() const {
  if (weights_animated && skin_animated) return "morph+skinned";
  if (skin_animated) return "skinned";
  return "morph";
}

Status analyze_scene(const tinygltf::Model& model, Scene& scene) {
  scene = Scene();
  for (size_t a = 0; a < model.animations.size(); ++a) {
    scene.clips.emplace_back();
    SEGMORPH_RETURN_IF_ERROR(load_clip(model, int(a), scene.clips.back()));
  }
  SEGMORPH_RETURN_IF_ERROR(build_node_graph(model, scene.graph));

  for (size_t s = 0; s < model.skins.size(); ++s)
    for (int joint : model.skins[s].joints)
      if (joint < 0 || size_t(joint) >= model.nodes.size())
        return Status(StatusCode::bad_data, "skin " + std::to_string(s) + " names a joint that does not exist");

  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tinygltf::Node& gltf_node = model.nodes[n];
    if (gltf_node.mesh < 0) continue;
    if (size_t(gltf_node.mesh) >= model.meshes.size())
      return Status(StatusCode::bad_data, node_label(model, int(n)) + " names a mesh that does not exist");
    if (gltf_node.skin >= 0 && size_t(gltf_node.skin) >= model.skins.size())
      return Status(StatusCode::bad_data, node_label(model, int(n)) + " names a skin that does not exist");
    const tinygltf::Mesh& mesh = model.meshes[size_t(gltf_node.mesh)];
    if (mesh.primitives.empty()) continue;
    for (const tinygltf::Primitive& primitive : mesh.primitives)
      if (primitive.targets.size() != mesh.primitives[0].targets.size())
        return Status(StatusCode::bad_data, "mesh " + std::to_string(gltf_node.mesh) +
                                                ": primitives have different numbers of morph targets");

    AnimatedNode node;
    node.node = int(n);
    node.mesh = gltf_node.mesh;
    node.skin = gltf_node.skin;
    node.morphed = !mesh.primitives[0].targets.empty();
    const std::vector<bool> relevant = skin_dependencies(model, scene.graph, node.skin);
    for (size_t c = 0; c < scene.clips.size(); ++c) {
      bool weights = false, skin = false;
      for (const Track& track : scene.clips[c].tracks) {
        if (track.path == TargetPath::weights)
          weights = weights || (node.morphed && track.node == int(n));
        else
          skin = skin || relevant[size_t(track.node)];
      }
      if (weights || skin) node.clips.push_back(int(c));
      node.weights_animated = node.weights_animated || weights;
      node.skin_animated = node.skin_animated || skin;
    }
    if (!node.clips.empty()) scene.animated.push_back(node);
  }
  if (scene.animated.empty())
    return Status(StatusCode::nothing_to_do,
                  model.animations.empty()
                      ? "nothing animated: the file has no animations"
                      : "nothing animated: no animation moves morph weights or skin joints of a mesh");
  return Status::Ok();
}

std::vector<float> frame_times(const Scene& scene, const tinygltf::Model& model, const AnimatedNode& node, int clip,
                               const SampleSettings& settings) {
  std::vector<float> keys;
  for_each_moving_track(model, scene.graph, node, scene.clips[size_t(clip)], [&](const Track& track) {
    keys.insert(keys.end(), track.curve.times.begin(), track.curve.times.end());
  });
  return sampling_times(std::move(keys), settings);
}

Status check_frame_counts(const tinygltf::Model& model, const Scene& scene, const SampleSettings& settings) {
  if (!(settings.fps > 0)) return Status::Ok();
  for (const AnimatedNode& node : scene.animated)
    for (int c : node.clips) {
      double start = INFINITY, end = -INFINITY;
      for_each_moving_track(model, scene.graph, node, scene.clips[size_t(c)], [&](const Track& track) {
        if (track.curve.times.empty()) return;
        start = std::min(start, double(track.curve.times.front()));
        end = std::max(end, double(track.curve.times.back()));
      });
      if (!(end >= start) || (end - start) * settings.fps <= SampleSettings::kMaxGridFrames) continue;
      char line[200];
      std::snprintf(line, sizeof(line), ": its keys span %g s, %.3g frames at --fps %g, above the %g a clip may have",
                    end - start, (end - start) * settings.fps, settings.fps, SampleSettings::kMaxGridFrames);
      return Status(StatusCode::invalid_argument,
                    node_label(model, node.node) + " in " + scene.clips[size_t(c)].name + line);
    }
  return Status::Ok();
}

std::vector<float> sampling_times(std::vector<float> keys, const SampleSettings& settings) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  if (keys.empty()) return keys;
  const double start = keys.front(), end = keys.back();
  if (settings.fps > 0) return regular_grid(start, end, settings.fps);
  if (double(keys.size() - 1) <= SampleSettings::kMaxKeyRate * (end - start) + 1e-9) return keys;
  return regular_grid(start, end, SampleSettings::kDefaultFps);
}

Status read_rest_attributes(const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& what,
                            SampledPrimitive& out) {
  auto position = primitive.attributes.find("POSITION");
  if (position == primitive.attributes.end()) return Status(StatusCode::bad_data, what + " has no POSITION");
  int components = 0;
  SEGMORPH_RETURN_IF_ERROR(read_floats(model, position->second, what + " POSITION", out.rest_positions, &components));
  if (components != 3) return Status(StatusCode::bad_data, what + ": POSITION must be VEC3");
  auto normal = primitive.attributes.find("NORMAL");
  if (normal != primitive.attributes.end()) {
    SEGMORPH_RETURN_IF_ERROR(read_floats(model, normal->second, what + " NORMAL", out.rest_normals, &components));
    if (components != 3 || out.rest_normals.size() != out.rest_positions.size())
      return Status(StatusCode::bad_data, what + ": NORMAL must be VEC3 with one element per vertex");
  }
  auto tangent = primitive.attributes.find("TANGENT");
  if (tangent != primitive.attributes.end()) {
    SEGMORPH_RETURN_IF_ERROR(read_floats(model, tangent->second, what + " TANGENT", out.rest_tangents, &components));
    if (components != 4 || out.rest_tangents.size() != out.rest_positions.size() / 3 * 4)
      return Status(StatusCode::bad_data, what + ": TANGENT must be VEC4 with one element per vertex");
  }
  return Status::Ok();
}

void morph_positions(const std::vector<float>& rest, const std::vector<std::vector<float>>& deltas,
                     const double* weights, std::vector<double>& out) {
  out.assign(rest.begin(), rest.end());
  for (size_t t = 0; t < deltas.size(); ++t) {
    if (weights[t] == 0 || deltas[t].empty()) continue;
    const float* delta = deltas[t].data();
    for (size_t i = 0; i < out.size(); ++i) out[i] += weights[t] * delta[i];
  }
}

namespace {

// Default morph weights: the node's, else the mesh's, else zeros.
Status default_weights(const tinygltf::Node& node, const tinygltf::Mesh& mesh, size_t target_count,
                       const std::string& label, std::vector<double>& weights) {
  weights.assign(target_count, 0.0);
  const std::vector<double>& defaults = !node.weights.empty() ? node.weights : mesh.weights;
  if (defaults.empty()) return Status::Ok();
  if (defaults.size() != target_count)
    return Status(StatusCode::bad_data, label + ": default weights do not match the morph target count");
  weights = defaults;
  return Status::Ok();
}

// The skin's inverse bind matrices (identity when absent), column-major.
Status inverse_bind_matrices(const tinygltf::Model& model, int skin_index, std::vector<Eigen::Matrix4d>& inverse_bind) {
  const tinygltf::Skin& skin = model.skins[size_t(skin_index)];
  inverse_bind.assign(skin.joints.size(), Eigen::Matrix4d::Identity());
  if (skin.inverseBindMatrices < 0) return Status::Ok();
  std::vector<float> matrices;
  int components = 0;
  SEGMORPH_RETURN_IF_ERROR(read_floats(model, skin.inverseBindMatrices,
                                       "skin " + std::to_string(skin_index) + " inverseBindMatrices", matrices,
                                       &components));
  if (components != 16 || matrices.size() < skin.joints.size() * 16)
    return Status(StatusCode::bad_data,
                  "skin " + std::to_string(skin_index) + ": inverseBindMatrices must be MAT4, one per joint");
  for (size_t j = 0; j < skin.joints.size(); ++j)
    for (int i = 0; i < 16; ++i) inverse_bind[j](i % 4, i / 4) = matrices[j * 16 + size_t(i)];
  return Status::Ok();
}

// What sampling a primitive starts from: its rest positions, targets and skin influences (`input`), and `sampled`
// with its rest attributes and one empty clip per clip of the node, each with the primitive's triangles.
Status read_primitive(const tinygltf::Model& model, const AnimatedNode& node, size_t p, size_t target_count,
                      const std::vector<int>* joints, PrimitiveInput& input, SampledPrimitive& sampled) {
  const tinygltf::Primitive& primitive = model.meshes[size_t(node.mesh)].primitives[p];
  const std::string what = "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(p);
  sampled.primitive = int(p);
  SEGMORPH_RETURN_IF_ERROR(read_rest_attributes(model, primitive, what, sampled));
  input.positions = sampled.rest_positions;
  input.vertex_count = input.positions.size() / 3;
  int components = 0;
  input.deltas.resize(target_count);
  for (size_t t = 0; t < target_count; ++t) {
    auto delta = primitive.targets[t].find("POSITION");
    if (delta == primitive.targets[t].end()) continue;
    SEGMORPH_RETURN_IF_ERROR(read_floats(model, delta->second, what + " target " + std::to_string(t) + " POSITION",
                                         input.deltas[t], &components));
    if (components != 3 || input.deltas[t].size() != input.positions.size())
      return Status(StatusCode::bad_data,
                    what + " target " + std::to_string(t) + ": POSITION must be VEC3 with one element per vertex");
  }
  if (joints) SEGMORPH_RETURN_IF_ERROR(read_skin_influences(model, primitive, joints->size(), what, input));
  std::vector<uint32_t> triangles;
  SEGMORPH_RETURN_IF_ERROR(read_triangles(model, primitive, input.vertex_count, what, triangles));
  sampled.clips.resize(node.clips.size());
  for (FrameSequence& sequence : sampled.clips) {
    sequence.vertex_count = input.vertex_count;
    sequence.triangles = triangles;
  }
  return Status::Ok();
}

// What every frame of a node's sampling needs: the primitives' inputs, the static weights, the skin's joints and
// inverse bind matrices.
struct NodeInputs {
  std::vector<PrimitiveInput> primitives;
  std::vector<double> static_weights;
  const std::vector<int>* joints = nullptr;  // null: not skinned
  std::vector<Eigen::Matrix4d> inverse_bind;
};

// What sample_frame computes into, kept from frame to frame.
struct FrameScratch {
  std::vector<double> weights, morphed;
  std::vector<Eigen::Matrix4d> global, joint_matrices;
};

// The frame at `time` of clip c into every primitive's sequence (frame f): the weights (recorded in clip_weights),
// the morph targets, then the skin, as glTF applies them.
void sample_frame(const tinygltf::Model& model, const Scene& scene, const Clip& clip, const Track* weight_track,
                  const NodeInputs& inputs, size_t c, size_t f, float time, FrameScratch& scratch, SampledNode& out) {
  std::vector<double>& weights = scratch.weights;
  std::vector<double>& morphed = scratch.morphed;
  std::vector<Eigen::Matrix4d>& global = scratch.global;
  std::vector<Eigen::Matrix4d>& joint_matrices = scratch.joint_matrices;
  weights.resize(inputs.static_weights.size());
  if (weight_track)
    weight_track->curve.evaluate(time, false, weights.data());
  else
    weights = inputs.static_weights;
  out.clip_weights[c].insert(out.clip_weights[c].end(), weights.begin(), weights.end());
  if (inputs.joints) {
    evaluate_global_transforms(model, scene.graph, &clip, time, global);
    joint_matrices.resize(inputs.joints->size());
    for (size_t j = 0; j < inputs.joints->size(); ++j)
      joint_matrices[j] = global[size_t((*inputs.joints)[j])] * inputs.inverse_bind[j];
  }
  for (size_t p = 0; p < inputs.primitives.size(); ++p) {
    const PrimitiveInput& input = inputs.primitives[p];
    const size_t values = input.vertex_count * 3;
    // Morph first, then skin.
    morph_positions(input.positions, input.deltas, weights.data(), morphed);
    float* frame = out.primitives[p].clips[c].frame(f);
    if (!inputs.joints) {
      for (size_t i = 0; i < values; ++i) frame[i] = float(morphed[i]);
      continue;
    }
    for (size_t v = 0; v < input.vertex_count; ++v) {
      const Eigen::Vector4d rest(morphed[v * 3], morphed[v * 3 + 1], morphed[v * 3 + 2], 1.0);
      Eigen::Vector4d skinned = Eigen::Vector4d::Zero();
      for (uint32_t i = input.influence_offset[v]; i < input.influence_offset[v + 1]; ++i)
        skinned += input.influence_weight[i] * (joint_matrices[input.influence_joint[i]] * rest);
      for (int k = 0; k < 3; ++k) frame[v * 3 + size_t(k)] = float(skinned[k]);
    }
  }
}

// Clip c of the node at its frame times.
Status sample_clip(const tinygltf::Model& model, const Scene& scene, const AnimatedNode& node,
                   const SampleSettings& settings, const NodeInputs& inputs, size_t c,
                   const std::vector<std::vector<float>>* clip_times, SampledNode& out) {
  const Clip& clip = scene.clips[size_t(node.clips[c])];
  const std::vector<float> times =
      clip_times ? (*clip_times)[c] : frame_times(scene, model, node, node.clips[c], settings);
  const Track* weight_track = nullptr;
  bool step = true;
  for_each_moving_track(model, scene.graph, node, clip, [&](const Track& track) {
    if (track.path == TargetPath::weights) weight_track = &track;
    step = step && track.curve.interpolation == Interpolation::step;
  });
  out.clip_is_step.push_back(step);
  const size_t target_count = inputs.static_weights.size();
  if (weight_track && size_t(weight_track->curve.width) != target_count)
    return Status(StatusCode::bad_data, "animation " + std::to_string(clip.animation) + ": weights of " +
                                            node_label(model, node.node) + " have " +
                                            std::to_string(weight_track->curve.width) + " values per key, the mesh " +
                                            std::to_string(target_count) + " morph targets");
  for (SampledPrimitive& sampled : out.primitives) {
    FrameSequence& sequence = sampled.clips[c];
    sequence.frame_count = times.size();
    sequence.times = times;
    sequence.positions.assign(times.size() * sequence.vertex_count * 3, 0.0f);
  }
  FrameScratch scratch;
  for (size_t f = 0; f < times.size(); ++f)
    sample_frame(model, scene, clip, weight_track, inputs, c, f, times[f], scratch, out);
  return Status::Ok();
}

}  // namespace

Status sample_node(const tinygltf::Model& model, const Scene& scene, const AnimatedNode& node,
                   const SampleSettings& settings, SampledNode& out,
                   const std::vector<std::vector<float>>* clip_times) {
  assert(!clip_times || clip_times->size() == node.clips.size());
  out = SampledNode();
  out.node = &node;
  const tinygltf::Mesh& mesh = model.meshes[size_t(node.mesh)];
  const size_t target_count = mesh.primitives[0].targets.size();
  NodeInputs inputs;
  SEGMORPH_RETURN_IF_ERROR(default_weights(model.nodes[size_t(node.node)], mesh, target_count,
                                           node_label(model, node.node), inputs.static_weights));
  if (node.skin >= 0) {
    inputs.joints = &model.skins[size_t(node.skin)].joints;
    SEGMORPH_RETURN_IF_ERROR(inverse_bind_matrices(model, node.skin, inputs.inverse_bind));
  }
  inputs.primitives.resize(mesh.primitives.size());
  out.clip_weights.resize(node.clips.size());
  out.primitives.resize(mesh.primitives.size());
  for (size_t p = 0; p < mesh.primitives.size(); ++p)
    SEGMORPH_RETURN_IF_ERROR(
        read_primitive(model, node, p, target_count, inputs.joints, inputs.primitives[p], out.primitives[p]));
  for (size_t c = 0; c < node.clips.size(); ++c)
    SEGMORPH_RETURN_IF_ERROR(sample_clip(model, scene, node, settings, inputs, c, clip_times, out));
  for (size_t p = 0; p < inputs.primitives.size(); ++p)
    out.primitives[p].target_deltas = std::move(inputs.primitives[p].deltas);
  return Status::Ok();
}

}  // namespace segmorph
