#include "verify/comparison.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <map>
#include <sstream>

#include "accessor.h"
#include "bake/bake.h"
#include "common/parallel.h"
#include "encode/metrics.h"
#include "verify/correspondence.h"

namespace segmorph {
namespace {

// The matrix (column-major, homogeneous) from a node's sampling space to model space: sample_node gives
// skinned vertices in model space and morph-only ones in mesh space.
Eigen::Matrix4d sampling_to_model(const AnimatedNode& node, const std::vector<Eigen::Matrix4d>& static_global) {
  return node.skin >= 0 ? Eigen::Matrix4d::Identity() : static_global[size_t(node.node)];
}

void transform_positions(const Eigen::Matrix4d& transform, std::vector<FrameSequence>& clips) {
  for (FrameSequence& clip : clips)
    for (size_t i = 0; i + 2 < clip.positions.size(); i += 3) {
      float* p = &clip.positions[i];
      const Eigen::Vector4d moved = transform * Eigen::Vector4d(p[0], p[1], p[2], 1.0);
      for (int k = 0; k < 3; ++k) p[k] = float(moved[k]);
    }
}

// The animation of `other` that plays clip `clip` of `reference`: the one of the same name when exactly one
// has it, else the one of the same index; -1 when there is none.
int counterpart_clip(const Scene& reference, int clip, const Scene& other) {
  const std::string& name = reference.clips[size_t(clip)].name;
  int found = -1, count = 0;
  for (size_t c = 0; c < other.clips.size(); ++c)
    if (other.clips[c].name == name) found = int(c), ++count;
  if (count == 1) return found;
  return size_t(clip) < other.clips.size() ? clip : -1;
}

// Every node of `other` with a mesh, as sample_node takes it: a file that plays the reference's animation may
// have dropped a track that does not move anything (gltfpack drops constant weights), so nodes that analyze_scene
// did not find animated are candidates too.
std::vector<AnimatedNode> mesh_nodes(const tinygltf::Model& model, const Scene& scene) {
  std::vector<AnimatedNode> nodes;
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tinygltf::Node& node = model.nodes[n];
    if (node.mesh < 0 || model.meshes[size_t(node.mesh)].primitives.empty()) continue;
    const auto animated = std::find_if(scene.animated.begin(), scene.animated.end(),
                                       [&](const AnimatedNode& a) { return a.node == int(n); });
    if (animated != scene.animated.end()) {
      nodes.push_back(*animated);
      continue;
    }
    AnimatedNode still;  // analyze_scene has checked its mesh and skin indices
    still.node = int(n);
    still.mesh = node.mesh;
    still.skin = node.skin;
    still.morphed = !model.meshes[size_t(node.mesh)].primitives[0].targets.empty();
    nodes.push_back(still);
  }
  return nodes;
}

// The errors of `other` (the reference's clips sampled at the same times, its vertices in any order) against
// `reference`, vertex v of the reference paired with vertex match[v] of the other.
ErrorMetrics paired_metrics(const std::vector<FrameSequence>& reference, const std::vector<FrameSequence>& other,
                            const std::vector<uint32_t>& match) {
  ErrorAccumulator accumulator;
  for (size_t c = 0; c < reference.size(); ++c) {
    FrameSequence matched = reference[c];
    for (size_t f = 0; f < matched.frame_count; ++f)
      for (size_t v = 0; v < matched.vertex_count; ++v)
        for (int k = 0; k < 3; ++k)
          matched.frame(f)[v * 3 + size_t(k)] = other[c].frame(f)[size_t(match[v]) * 3 + size_t(k)];
    accumulator.add(reference[c], matched);
  }
  return accumulator.result();
}

// The node of `nodes` that bake wrote from the reference's node `node` (extras.segmorph.source_node), or null.
const AnimatedNode* baked_from(int node, const tinygltf::Model& model, const std::vector<AnimatedNode>& nodes) {
  for (const AnimatedNode& candidate : nodes)
    if (source_node(model.nodes[size_t(candidate.node)]) == node) return &candidate;
  return nullptr;
}

// A node of the other file sampled as the counterpart of a reference node: its clips replaced by the
// reference's counterparts, its positions carried into the reference's sampling space.
struct Counterpart {
  AnimatedNode node;  // sampled.node points here: keep it where it is
  SampledNode sampled;
};

Status sample_counterpart(const tinygltf::Model& model, const Scene& scene, const AnimatedNode& node,
                          const std::vector<int>& clips, const std::vector<std::vector<float>>& times,
                          const Eigen::Matrix4d& to_reference, Counterpart& out) {
  out.node = node;
  out.node.clips = clips;
  SEGMORPH_RETURN_IF_ERROR(sample_node(model, scene, out.node, SampleSettings(), out.sampled, &times));
  if (to_reference != Eigen::Matrix4d::Identity())
    for (SampledPrimitive& primitive : out.sampled.primitives) transform_positions(to_reference, primitive.clips);
  return Status::Ok();
}

// How far `other` is from playing `reference`: over up to 32 vertices of the reference, the mean of the
// least sum of squared distances to a vertex of `other` over the frames `frames` names (per clip, indices
// into the reference's frames; `other` holds just those frames, in that order). A cheap screen for pairing
// primitives; match_vertices then pairs the vertices over every frame.
double trajectory_gap(const std::vector<FrameSequence>& reference, const std::vector<std::vector<size_t>>& frames,
                      const std::vector<FrameSequence>& other) {
  const size_t count = reference[0].vertex_count, other_count = other[0].vertex_count;
  if (other_count == 0) return INFINITY;
  const size_t samples = std::min<size_t>(count, 32);
  double total = 0;
  for (size_t s = 0; s < samples; ++s) {
    const size_t v = s * count / samples;
    double nearest = INFINITY;
    for (size_t u = 0; u < other_count && nearest > 0; ++u) {
      double sum = 0;
      for (size_t c = 0; c < frames.size() && sum < nearest; ++c)
        for (size_t i = 0; i < frames[c].size(); ++i) {
          const float* a = reference[c].frame(frames[c][i]) + v * 3;
          const float* b = other[c].frame(i) + u * 3;
          for (int k = 0; k < 3; ++k) sum += (double(a[k]) - b[k]) * (double(a[k]) - b[k]);
        }
      nearest = std::min(nearest, sum);
    }
    total += nearest;
  }
  return total / double(samples);
}

// The root mean square distance of a primitive's positions from their frame's centroid, over the frames `frames`
// names (per clip): the size of its shape, the KG error's scale.
double shape_radius(const std::vector<FrameSequence>& clips, const std::vector<std::vector<size_t>>& frames) {
  double spread = 0;
  size_t count = 0;
  for (size_t c = 0; c < frames.size(); ++c)
    for (size_t f : frames[c]) {
      add_frame_spread(clips[c].frame(f), clips[c].vertex_count, spread);
      count += clips[c].vertex_count;
    }
  return count > 0 ? std::sqrt(spread / double(count)) : 0.0;
}

// Each primitive of `want`'s counterpart (node, primitive) in the other file: the nearest over every node with a
// mesh, screened on the first, middle and last frames of the first clips only. A primitive whose nearest
// counterpart's screened vertices lie farther from its own, in root mean square over the screened frames, than
// kUnpairedRadius times its shape's radius has none (bad_data naming it): the other file does not play it, and
// comparing it with whatever lies nearest would report errors of an unrelated mesh.
constexpr double kUnpairedRadius = 0.5;
Status nearest_counterparts(const tinygltf::Model& other_model, const Scene& other_scene,
                            const std::vector<AnimatedNode>& other_nodes, const SampledNode& want,
                            const std::string& label, const std::vector<int>& clips,
                            const std::vector<std::vector<float>>& times,
                            const std::function<Eigen::Matrix4d(const AnimatedNode&)>& to_reference,
                            std::vector<std::pair<const AnimatedNode*, size_t>>& pairs) {
  std::vector<std::vector<size_t>> screen_frames(times.size());
  std::vector<std::vector<float>> screen_times(times.size());
  for (size_t c = 0; c < times.size(); ++c) {
    const size_t last = times[c].size() - 1;
    screen_frames[c] = c < 4 ? std::vector<size_t>{0, last / 2, last} : std::vector<size_t>{0};
    screen_frames[c].erase(std::unique(screen_frames[c].begin(), screen_frames[c].end()), screen_frames[c].end());
    for (size_t f : screen_frames[c]) screen_times[c].push_back(times[c][f]);
  }
  std::vector<double> nearest(want.primitives.size(), INFINITY);
  for (const AnimatedNode& candidate : other_nodes) {
    Counterpart screened;
    SEGMORPH_RETURN_IF_ERROR(sample_counterpart(other_model, other_scene, candidate, clips, screen_times,
                                                to_reference(candidate), screened));
    for (size_t p = 0; p < want.primitives.size(); ++p)
      for (size_t q = 0; q < screened.sampled.primitives.size(); ++q) {
        const double gap =
            trajectory_gap(want.primitives[p].clips, screen_frames, screened.sampled.primitives[q].clips);
        if (gap < nearest[p]) nearest[p] = gap, pairs[p] = {&candidate, q};
      }
  }
  size_t screened = 0;
  for (const std::vector<size_t>& frames : screen_frames) screened += frames.size();
  for (size_t p = 0; p < want.primitives.size(); ++p) {
    const double distance = std::sqrt(nearest[p] / double(std::max<size_t>(screened, 1)));
    const double radius = shape_radius(want.primitives[p].clips, screen_frames);
    if (pairs[p].first && distance <= kUnpairedRadius * radius) continue;
    std::ostringstream nearest_text;
    nearest_text << std::setprecision(3) << (radius > 0 ? distance / radius : INFINITY);
    return Status(StatusCode::bad_data,
                  "has no primitive that plays primitive " + std::to_string(p) + " of " + label +
                      ": the nearest by trajectory is " + nearest_text.str() +
                      " times its size away (the files do not play the same animation)");
  }
  return Status::Ok();
}

}  // namespace

namespace {

// What every reference node's comparison reads.
struct ComparisonInputs {
  const tinygltf::Model& reference_model;
  const Scene& reference_scene;
  const tinygltf::Model& other_model;
  const Scene& other_scene;
  std::vector<Eigen::Matrix4d> reference_global, other_global;
  std::vector<AnimatedNode> other_nodes;
  bool encoded_from_reference;
  const VertexMatches* matches;  // read only while nodes are compared
  size_t vertex_threads = 1;     // for one primitive's vertex pairing: the threads the nodes leave
};

// One reference node compared: its primitives' comparisons, and the vertex pairings it made that `matches` lacked.
struct NodeComparison {
  Status status;
  std::vector<PrimitiveComparison> primitives;
  std::vector<std::pair<std::pair<int, size_t>, std::vector<uint32_t>>> new_matches;
};

void compare_node(const ComparisonInputs& in, const SampledNode& want, NodeComparison& out) {
  const AnimatedNode& node = *want.node;
  const std::string label = node_name(in.reference_model, node.node);
  auto fail = [&](Status status) { out.status = std::move(status); };
  // The other's animations for the reference's clips, sampled at the reference's times.
  std::vector<int> clips;
  std::vector<std::vector<float>> times;
  for (size_t c = 0; c < node.clips.size(); ++c) {
    const int clip = counterpart_clip(in.reference_scene, node.clips[c], in.other_scene);
    if (clip < 0)
      return fail(
          Status(StatusCode::bad_data,
                 "has no animation \"" + in.reference_scene.clips[size_t(node.clips[c])].name + "\" for " + label));
    clips.push_back(clip);
    times.push_back(want.primitives[0].clips[c].times);
  }
  const Eigen::Matrix4d reference_to_model = sampling_to_model(node, in.reference_global);
  auto to_reference = [&](const AnimatedNode& other) {
    const Eigen::Matrix4d other_to_model = sampling_to_model(other, in.other_global);
    return other_to_model == reference_to_model ? Eigen::Matrix4d::Identity().eval()
                                                : (reference_to_model.inverse() * other_to_model).eval();
  };

  // Each primitive's counterpart (node, primitive): the baked node's, the same node in segmorph's own encode,
  // else the nearest (nearest_counterparts).
  std::vector<std::pair<const AnimatedNode*, size_t>> pairs(want.primitives.size(), {nullptr, 0});
  const auto same_node = std::find_if(in.other_nodes.begin(), in.other_nodes.end(),
                                      [&](const AnimatedNode& other) { return other.node == node.node; });
  if (const AnimatedNode* baked = baked_from(node.node, in.other_model, in.other_nodes)) {
    if (in.other_model.meshes[size_t(baked->mesh)].primitives.size() != want.primitives.size())
      return fail(Status(StatusCode::bad_data, label + ": the primitives differ"));
    for (size_t p = 0; p < pairs.size(); ++p) pairs[p] = {baked, p};
  } else if (in.encoded_from_reference && same_node != in.other_nodes.end() &&
             in.other_model.meshes[size_t(same_node->mesh)].primitives.size() == want.primitives.size()) {
    for (size_t p = 0; p < pairs.size(); ++p) pairs[p] = {&*same_node, p};
  } else {
    const Status found =
        nearest_counterparts(in.other_model, in.other_scene, in.other_nodes, want, label, clips, times, to_reference,
                             pairs);
    if (!found.ok()) return fail(found);
  }

  std::map<const AnimatedNode*, Counterpart> sampled;  // every frame of each node paired with
  for (size_t p = 0; p < want.primitives.size(); ++p) {
    if (!pairs[p].first) return fail(Status(StatusCode::bad_data, "has no vertices for " + label));
    auto it = sampled.find(pairs[p].first);
    if (it == sampled.end()) {
      it = sampled.emplace(pairs[p].first, Counterpart()).first;
      const Status counterpart = sample_counterpart(in.other_model, in.other_scene, *pairs[p].first, clips, times,
                                                    to_reference(*pairs[p].first), it->second);
      if (!counterpart.ok()) return fail(counterpart);
    }
    const std::vector<FrameSequence>& a = want.primitives[p].clips;
    const std::vector<FrameSequence>& b = it->second.sampled.primitives[pairs[p].second].clips;
    if (b[0].vertex_count == 0) return fail(Status(StatusCode::bad_data, "has no vertices for " + label));

    // The other's vertices in the reference's order.
    const std::vector<uint32_t>* match = nullptr;
    if (in.matches) {
      const auto found = in.matches->find({node.node, p});
      if (found != in.matches->end() && found->second.size() == a[0].vertex_count &&
          std::all_of(found->second.begin(), found->second.end(), [&](uint32_t v) { return v < b[0].vertex_count; }))
        match = &found->second;
    }
    if (!match) {
      out.new_matches.push_back({{node.node, p}, match_vertices(a, b, in.vertex_threads)});
      match = &out.new_matches.back().second;
    }
    PrimitiveComparison compared;
    compared.node = node.node, compared.mesh = node.mesh, compared.primitive = int(p);
    compared.other_node = pairs[p].first->node, compared.other_mesh = pairs[p].first->mesh;
    compared.other_primitive = int(pairs[p].second);
    compared.metrics = paired_metrics(a, b, *match);
    out.primitives.push_back(compared);
  }
}

}  // namespace

Status compare_animation(const tinygltf::Model& reference_model, const Scene& reference_scene,
                         const std::vector<SampledNode>& reference, const tinygltf::Model& other_model,
                         const Scene& other_scene, AnimationComparison& result, bool encoded_from_reference,
                         VertexMatches* matches, size_t threads) {
  result = AnimationComparison();
  ComparisonInputs in{reference_model,        reference_scene, other_model, other_scene, {}, {}, {},
                      encoded_from_reference, matches};
  evaluate_global_transforms(reference_model, reference_scene.graph, nullptr, 0, in.reference_global);
  evaluate_global_transforms(other_model, other_scene.graph, nullptr, 0, in.other_global);
  in.other_nodes = mesh_nodes(other_model, other_scene);
  in.vertex_threads = std::max<size_t>(1, thread_count(threads) / std::max<size_t>(reference.size(), 1));

  // The nodes are compared on up to `threads` threads; their results are gathered in node order.
  std::vector<NodeComparison> nodes(reference.size());
  parallel_ranges(reference.size(), thread_count(threads), [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) compare_node(in, reference[i], nodes[i]);
  });
  for (size_t i = 0; i < reference.size(); ++i) {
    if (!nodes[i].status.ok()) return nodes[i].status;
    if (matches)
      for (auto& [key, match] : nodes[i].new_matches) (*matches)[key] = std::move(match);
    for (size_t p = 0; p < nodes[i].primitives.size(); ++p) {
      const std::vector<FrameSequence>& a = reference[i].primitives[p].clips;
      for (const FrameSequence& clip : a) {
        result.vertex_frames += double(clip.vertex_count * clip.frame_count);
        if (result.vertices == 0) result.frames += clip.frame_count;  // counted on the first primitive
      }
      result.vertices += a[0].vertex_count;
      const ErrorMetrics& metrics = nodes[i].primitives[p].metrics;
      result.primitives.push_back(nodes[i].primitives[p]);
      result.worst.kg_percent = std::max(result.worst.kg_percent, metrics.kg_percent);
      result.worst.rmse_over_diagonal = std::max(result.worst.rmse_over_diagonal, metrics.rmse_over_diagonal);
      result.worst.max_error_over_diagonal =
          std::max(result.worst.max_error_over_diagonal, metrics.max_error_over_diagonal);
    }
  }
  return Status::Ok();
}

namespace {

// The POSITION (V × 3) of primitive `primitive` of node `node`'s mesh.
Status rigid_positions(const tinygltf::Model& model, int node, int primitive, std::vector<float>& positions) {
  const tinygltf::Mesh& mesh = model.meshes[size_t(model.nodes[size_t(node)].mesh)];
  const std::string what = "node " + std::to_string(node) + " primitive " + std::to_string(primitive);
  if (size_t(primitive) >= mesh.primitives.size()) return Status(StatusCode::bad_data, what + " does not exist");
  const auto position = mesh.primitives[size_t(primitive)].attributes.find("POSITION");
  if (position == mesh.primitives[size_t(primitive)].attributes.end())
    return Status(StatusCode::bad_data, what + " has no POSITION");
  int components = 0;
  SEGMORPH_RETURN_IF_ERROR(read_floats(model, position->second, what + " POSITION", positions, &components));
  if (components != 3 || positions.empty()) return Status(StatusCode::bad_data, what + ": no VEC3 positions");
  return Status::Ok();
}

// `positions` (V × 3) moved by node `node`'s global transforms at `times` of `clip` (one frame of the static pose
// when clip is null): one clip of a rigid primitive in model space.
FrameSequence moved_positions(const tinygltf::Model& model, const NodeGraph& graph, int node,
                              const std::vector<float>& positions, const Clip* clip, const std::vector<float>& times) {
  FrameSequence out;
  out.vertex_count = positions.size() / 3;
  out.times = clip ? times : std::vector<float>{0.0f};
  out.frame_count = out.times.size();
  out.positions.resize(out.frame_count * out.vertex_count * 3);
  for (size_t f = 0; f < out.frame_count; ++f) {
    const Eigen::Matrix4d transform = evaluate_global_transform(model, graph, clip, out.times[f], node);
    for (size_t v = 0; v < out.vertex_count; ++v) {
      const float* p = &positions[v * 3];
      const Eigen::Vector4d moved = transform * Eigen::Vector4d(p[0], p[1], p[2], 1.0);
      for (int k = 0; k < 3; ++k) out.frame(f)[v * 3 + size_t(k)] = float(moved[k]);
    }
  }
  return out;
}

}  // namespace

Status compare_rigid_primitive(const tinygltf::Model& reference_model, const Scene& reference_scene,
                               const tinygltf::Model& other_model, const Scene& other_scene, int node, int primitive,
                               ErrorMetrics& metrics) {
  for (const tinygltf::Model* model : {&reference_model, &other_model})
    if (node < 0 || size_t(node) >= model->nodes.size() || model->nodes[size_t(node)].mesh < 0)
      return Status(StatusCode::bad_data, "node " + std::to_string(node) + " has no mesh in both files");
  std::vector<float> reference_positions, other_positions;
  SEGMORPH_RETURN_IF_ERROR(rigid_positions(reference_model, node, primitive, reference_positions));
  SEGMORPH_RETURN_IF_ERROR(rigid_positions(other_model, node, primitive, other_positions));
  // The clips that move the node: a translation, rotation or scale track of it or of an ancestor.
  std::vector<bool> moves(reference_model.nodes.size(), false);
  for (int n = node; n >= 0; n = reference_scene.graph.parent[size_t(n)]) moves[size_t(n)] = true;
  std::vector<FrameSequence> reference, other;
  for (size_t c = 0; c < reference_scene.clips.size(); ++c) {
    std::vector<float> keys;
    for (const Track& track : reference_scene.clips[c].tracks)
      if (track.path != TargetPath::weights && moves[size_t(track.node)])
        keys.insert(keys.end(), track.curve.times.begin(), track.curve.times.end());
    if (keys.empty()) continue;
    const int counterpart = counterpart_clip(reference_scene, int(c), other_scene);
    if (counterpart < 0)
      return Status(StatusCode::bad_data, "the encoded file has no animation for " + reference_scene.clips[c].name);
    const std::vector<float> times = sampling_times(std::move(keys), SampleSettings());
    reference.push_back(moved_positions(reference_model, reference_scene.graph, node, reference_positions,
                                        &reference_scene.clips[c], times));
    other.push_back(moved_positions(other_model, other_scene.graph, node, other_positions,
                                    &other_scene.clips[size_t(counterpart)], times));
  }
  if (reference.empty()) {  // nothing moves it: its rest pose
    reference.push_back(
        moved_positions(reference_model, reference_scene.graph, node, reference_positions, nullptr, {}));
    other.push_back(moved_positions(other_model, other_scene.graph, node, other_positions, nullptr, {}));
  }
  metrics = paired_metrics(reference, other, match_vertices(reference, other));
  return Status::Ok();
}

}  // namespace segmorph
