#include "moving_meshes.h"

#include <algorithm>
#include <cmath>

#include "accessor.h"
#include "animation.h"
#include "compressed.h"
#include "segmorph_extension.h"

namespace segmorph {
namespace {

constexpr int kMinPositionBits = 8, kMaxPositionBits = 22;

bool is_triangle_list(const tinygltf::Primitive& primitive) {
  return primitive.mode == -1 || primitive.mode == TINYGLTF_MODE_TRIANGLES;
}

// Weights as normalized bytes: each vertex's weights (over every WEIGHTS_n set, in order) normalized to sum 1 (glTF
// requires it; some files, CesiumMan's, are off by up to 70 %), rounded to 1/255, the largest taking up the
// rounding so that the bytes sum to exactly 255. A vertex whose weights are all zero keeps them.
void quantize_weights(std::vector<BaseMeshAttribute*>& sets, size_t vertex_count) {
  for (size_t v = 0; v < vertex_count; ++v) {
    float* largest = nullptr;
    double sum = 0;
    long quantized_sum = 0;
    for (BaseMeshAttribute* set : sets)
      for (int c = 0; c < set->components; ++c) {
        float& w = set->values[v * size_t(set->components) + size_t(c)];
        w = std::max(w, 0.0f);
        sum += w;
        if (!largest || w > *largest) largest = &w;
      }
    for (BaseMeshAttribute* set : sets)
      for (int c = 0; c < set->components; ++c) {
        float& w = set->values[v * size_t(set->components) + size_t(c)];
        w = sum > 0 ? float(std::lround(double(w) / sum * 255)) : 0.0f;
        quantized_sum += long(w);
      }
    if (sum > 0) *largest = float(std::clamp(long(*largest) + 255 - quantized_sum, 0L, 255L));
  }
  for (BaseMeshAttribute* set : sets) {
    set->type = AttributeType::uint8;
    set->normalized = true;
  }
}

// The primitive's vertices as a base mesh: joints as integers, weights as normalized bytes, the rest as floats.
Status read_primitive(const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& what,
                      BaseMesh& mesh) {
  mesh = BaseMesh();
  auto position = primitive.attributes.find("POSITION");
  if (position == primitive.attributes.end()) return Status(StatusCode::bad_data, what + " has no POSITION");
  std::vector<BaseMeshAttribute*> weights;
  for (const auto& [semantic, index] : primitive.attributes) {
    BaseMeshAttribute attribute;
    attribute.semantic = semantic;
    if (semantic.rfind("JOINTS_", 0) == 0) {
      std::vector<uint32_t> joints;
      SEGMORPH_RETURN_IF_ERROR(read_uints(model, index, what + " " + semantic, joints, &attribute.components));
      const bool bytes = std::all_of(joints.begin(), joints.end(), [](uint32_t j) { return j <= 255; });
      if (!std::all_of(joints.begin(), joints.end(), [](uint32_t j) { return j <= 65535; }))
        return Status(StatusCode::unsupported, what + " " + semantic + " names a joint beyond 65535");
      attribute.values.assign(joints.begin(), joints.end());
      attribute.type = bytes ? AttributeType::uint8 : AttributeType::uint16;
    } else {
      SEGMORPH_RETURN_IF_ERROR(read_floats(model, index, what + " " + semantic, attribute.values, &attribute.components));
    }
    if (semantic == "POSITION") {
      if (attribute.components != 3) return Status(StatusCode::bad_data, what + " POSITION is not VEC3");
      mesh.vertex_count = attribute.values.size() / 3;
      mesh.attributes.insert(mesh.attributes.begin(), std::move(attribute));
    } else {
      mesh.attributes.push_back(std::move(attribute));
    }
  }
  for (BaseMeshAttribute& attribute : mesh.attributes) {
    if (attribute.values.size() != mesh.vertex_count * size_t(attribute.components))
      return Status(StatusCode::bad_data, what + " " + attribute.semantic + " has another vertex count than POSITION");
    if (attribute.semantic.rfind("WEIGHTS_", 0) == 0) weights.push_back(&attribute);
  }
  quantize_weights(weights, mesh.vertex_count);
  // A joint whose weight is zero becomes joint 0, as glTF recommends (validators warn otherwise).
  for (const BaseMeshAttribute* set : weights) {
    const std::string joints_name = "JOINTS_" + set->semantic.substr(8);
    for (BaseMeshAttribute& joints : mesh.attributes)
      if (joints.semantic == joints_name && joints.components == set->components)
        for (size_t i = 0; i < joints.values.size(); ++i)
          if (set->values[i] == 0) joints.values[i] = 0;
  }
  if (primitive.indices >= 0) {
    SEGMORPH_RETURN_IF_ERROR(read_uints(model, primitive.indices, what + " indices", mesh.triangles));
  } else {
    mesh.triangles.resize(mesh.vertex_count);
    for (size_t v = 0; v < mesh.vertex_count; ++v) mesh.triangles[v] = uint32_t(v);
  }
  if (mesh.triangles.size() % 3 != 0) return Status(StatusCode::bad_data, what + " is a triangle list of a count not divisible by 3");
  for (uint32_t v : mesh.triangles)
    if (v >= mesh.vertex_count) return Status(StatusCode::bad_data, what + " has an index beyond its vertices");
  return Status::Ok();
}

// Position bits that put Draco's step near step_ratio × `spread`, or the spread of `positions` about their
// centroid when `spread` is 0.
int position_bits_for(const std::vector<float>& positions, double step_ratio, double spread) {
  const size_t count = positions.size() / 3;
  if (count == 0) return kMinPositionBits;
  double centroid[3] = {0, 0, 0}, low[3], high[3];
  for (int c = 0; c < 3; ++c) low[c] = INFINITY, high[c] = -INFINITY;
  for (size_t v = 0; v < count; ++v)
    for (int c = 0; c < 3; ++c) {
      const double x = positions[v * 3 + size_t(c)];
      centroid[c] += x / double(count);
      low[c] = std::min(low[c], x);
      high[c] = std::max(high[c], x);
    }
  if (!(spread > 0)) {
    for (size_t v = 0; v < count; ++v)
      for (int c = 0; c < 3; ++c) spread += std::pow(positions[v * 3 + size_t(c)] - centroid[c], 2) / double(count);
    spread = std::sqrt(spread);
  }
  const double extent = std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2]});
  const double step = step_ratio * spread;
  if (!(extent > 0) || !(step > 0)) return kMinPositionBits;
  return int(std::clamp(std::ceil(std::log2(extent / step + 1)), double(kMinPositionBits), double(kMaxPositionBits)));
}

int component_type_of(const BaseMeshAttribute& attribute) {
  switch (attribute.type) {
    case AttributeType::uint8:
      return TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    case AttributeType::uint16:
      return TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    default:
      return TINYGLTF_COMPONENT_TYPE_FLOAT;
  }
}

Status compress_primitive(tinygltf::Model& model, tinygltf::Primitive& primitive, const std::string& what,
                          DracoSettings settings, double step_ratio, double rigid_spread, MovingMeshReport& report) {
  BaseMesh original;
  SEGMORPH_RETURN_IF_ERROR(read_primitive(model, primitive, what, original));
  std::vector<uint32_t> first;
  const BaseMesh mesh = merge_copies(original, {}, first);
  const bool skinned = primitive.attributes.count("JOINTS_0") > 0;
  settings.share_values = true;
  if (settings.position_bits == 0)
    settings.position_bits = position_bits_for(mesh.attributes[0].values, step_ratio, skinned ? 0 : rigid_spread);
  std::vector<uint8_t> bytes;
  DracoPrimitive draco;
  Status status = encode_draco_base_mesh(mesh, settings, bytes, draco.attributes);
  BaseMesh decoded;
  if (status.ok()) status = decode_draco_base_mesh(bytes.data(), bytes.size(), draco.attributes, decoded);
  if (!status.ok()) return Status(status.code(), what + ": " + status.message());

  // The accessors describe what Draco decodes to; POSITION keeps its bounds, as glTF requires.
  AccessorWriter writer(model);
  for (const BaseMeshAttribute& attribute : decoded.attributes) {
    if (attribute.semantic == "POSITION") {
      primitive.attributes["POSITION"] =
          writer.add_described(attribute.values.data(), decoded.vertex_count, TINYGLTF_TYPE_VEC3);
      continue;
    }
    tinygltf::Accessor accessor;
    accessor.componentType = component_type_of(attribute);
    accessor.normalized = attribute.normalized;
    accessor.count = decoded.vertex_count;
    accessor.type = type_of_components(attribute.components);
    model.accessors.push_back(accessor);
    primitive.attributes[attribute.semantic] = int(model.accessors.size()) - 1;
  }
  primitive.indices = writer.add_described_indices(decoded.triangles.size(), decoded.vertex_count);
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  draco.buffer_view = writer.add_view(bytes.data(), bytes.size(), 0);
  primitive.extensions[kDracoExtensionName] = draco_primitive_value(draco);
  ++report.primitives;
  report.bytes += bytes.size();
  return Status::Ok();
}

}  // namespace

std::vector<bool> moving_meshes(const tinygltf::Model& model, const std::vector<int>& kept_skins) {
  const size_t node_count = model.nodes.size();
  std::vector<bool> animated(node_count, false), kept(node_count, false);
  for (int node : kept_skins)
    if (node >= 0 && size_t(node) < node_count) kept[size_t(node)] = true;
  for (const tinygltf::Animation& animation : model.animations)
    for (const tinygltf::AnimationChannel& channel : animation.channels)
      if (channel.target_node >= 0 && size_t(channel.target_node) < node_count && channel.target_path != "weights")
        animated[size_t(channel.target_node)] = true;
  // A node moves when it or an ancestor is animated (the graph is a forest: load_gltf's analysis checked it).
  NodeGraph graph;
  std::vector<bool> moves(node_count, false);
  if (build_node_graph(model, graph).ok())
    for (int n : graph.order)
      moves[size_t(n)] = animated[size_t(n)] || (graph.parent[size_t(n)] >= 0 && moves[size_t(graph.parent[size_t(n)])]);

  std::vector<bool> take(model.meshes.size(), false), refused(model.meshes.size(), false);
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    const tinygltf::Mesh& mesh = model.meshes[m];
    for (const tinygltf::Primitive& primitive : mesh.primitives)
      if (!primitive.targets.empty() || !is_triangle_list(primitive) || !primitive.extensions.empty() ||
          primitive.attributes.count("POSITION") == 0)
        refused[m] = true;
    if (mesh.primitives.empty()) refused[m] = true;
  }
  for (size_t n = 0; n < node_count; ++n) {
    const tinygltf::Node& node = model.nodes[n];
    if (node.mesh < 0 || size_t(node.mesh) >= model.meshes.size()) continue;
    const bool qualifies = kept[n] || (moves[n] && node.skin < 0);
    if (qualifies) take[size_t(node.mesh)] = true;
    else refused[size_t(node.mesh)] = true;
  }
  for (size_t m = 0; m < take.size(); ++m) take[m] = take[m] && !refused[m];
  return take;
}

Status compress_moving_meshes(tinygltf::Model& model, const std::vector<bool>& meshes, const DracoSettings& settings,
                              double step_ratio, double rigid_spread, MovingMeshReport& report) {
  // rigid_spread is in model units; a mesh's positions are in those of its node (the first that uses it).
  NodeGraph graph;
  SEGMORPH_RETURN_IF_ERROR(build_node_graph(model, graph));
  std::vector<Eigen::Matrix4d> global;
  evaluate_global_transforms(model, graph, nullptr, 0, global);
  std::vector<double> scale(model.meshes.size(), 0);
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const int mesh = model.nodes[n].mesh;
    if (mesh < 0 || size_t(mesh) >= scale.size() || scale[size_t(mesh)] > 0) continue;
    scale[size_t(mesh)] = largest_scale(global[n]);
  }
  bool any = false;
  for (size_t m = 0; m < meshes.size() && m < model.meshes.size(); ++m) {
    if (!meshes[m]) continue;
    const double mesh_spread = scale[m] > 0 && std::isfinite(scale[m]) ? rigid_spread / scale[m] : 0;
    for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      // compress_primitive appends accessors and views, never meshes: the reference stays valid.
      tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
      SEGMORPH_RETURN_IF_ERROR(compress_primitive(model, primitive,
                                                  "mesh " + std::to_string(m) + " primitive " + std::to_string(p),
                                                  settings, step_ratio, mesh_spread, report));
      any = true;
    }
  }
  if (any) declare_extension(model, kDracoExtensionName, true);
  return Status::Ok();
}

}  // namespace segmorph
