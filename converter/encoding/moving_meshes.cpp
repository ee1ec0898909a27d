#include "encoding/moving_meshes.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "accessor.h"
#include "common/parallel.h"
#include "encoding/compress_primitives.h"
#include "sampling/animation.h"
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

// One primitive's Draco coding: the mesh read (its copies merged), and what Draco makes of it, until written.
struct CodedPrimitive {
  tinygltf::Primitive* primitive = nullptr;
  std::string what;
  BaseMesh mesh;  // read, copies merged
  DracoSettings settings;
  std::vector<uint8_t> bytes;
  DracoPrimitive draco;
  BaseMesh decoded;
  Status status;
};

// Encodes `coded.mesh` with Draco and decodes it back (no model is touched: runs on any thread).
void code_primitive(CodedPrimitive& coded) {
  Status status = encode_draco_base_mesh(coded.mesh, coded.settings, coded.bytes, coded.draco.attributes);
  if (status.ok()) status = decode_draco_base_mesh(coded.bytes.data(), coded.bytes.size(), coded.draco.attributes,
                                                   coded.decoded);
  if (!status.ok()) coded.status = Status(status.code(), coded.what + ": " + status.message());
}

// Writes a coded primitive to the model: the accessors describe what Draco decodes to; POSITION keeps its bounds, as
// glTF requires.
void write_primitive(tinygltf::Model& model, const CodedPrimitive& coded, MovingMeshReport& report) {
  tinygltf::Primitive& primitive = *coded.primitive;
  const BaseMesh& decoded = coded.decoded;
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
  DracoPrimitive draco = coded.draco;
  draco.buffer_view = writer.add_view(coded.bytes.data(), coded.bytes.size(), 0);
  primitive.extensions[kDracoExtensionName] = draco_primitive_value(draco);
  ++report.primitives;
  report.bytes += coded.bytes.size();
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
                              double step_ratio, double rigid_spread, size_t threads, MovingMeshReport& report) {
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
  // The primitives in order; read and coded a batch of `threads` at once (each coded on a thread of its own), then
  // written in order. Writing appends accessors and views, never meshes: the primitive pointers stay valid.
  std::vector<std::pair<tinygltf::Primitive*, std::string>> primitives;
  std::vector<double> spreads;
  for (size_t m = 0; m < meshes.size() && m < model.meshes.size(); ++m) {
    if (!meshes[m]) continue;
    const double mesh_spread = scale[m] > 0 && std::isfinite(scale[m]) ? rigid_spread / scale[m] : 0;
    for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      primitives.emplace_back(&model.meshes[m].primitives[p], "mesh " + std::to_string(m) + " primitive " +
                                                                  std::to_string(p));
      spreads.push_back(mesh_spread);
    }
  }
  const size_t batch = thread_count(threads);
  for (size_t start = 0; start < primitives.size(); start += batch) {
    std::vector<CodedPrimitive> coded;
    Status unread;  // a primitive that cannot be read ends the batch; its error comes after the earlier ones'
    for (size_t i = start; i < std::min(start + batch, primitives.size()) && unread.ok(); ++i) {
      CodedPrimitive one;
      one.primitive = primitives[i].first;
      one.what = primitives[i].second;
      one.settings = settings;
      one.settings.share_values = true;
      BaseMesh original;
      unread = read_primitive(model, *one.primitive, one.what, original);
      if (!unread.ok()) break;
      std::vector<uint32_t> first;
      one.mesh = merge_copies(original, {}, first);
      const bool skinned = one.primitive->attributes.count("JOINTS_0") > 0;
      if (one.settings.position_bits == 0)
        one.settings.position_bits =
            position_bits_for(one.mesh.attributes[0].values, step_ratio, skinned ? 0 : spreads[i]);
      coded.push_back(std::move(one));
    }
    parallel_ranges(coded.size(), batch, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) code_primitive(coded[i]);
    });
    for (CodedPrimitive& one : coded) {
      SEGMORPH_RETURN_IF_ERROR(one.status);
      write_primitive(model, one, report);
      one = CodedPrimitive();
    }
    SEGMORPH_RETURN_IF_ERROR(unread);
  }
  if (!primitives.empty()) declare_extension(model, kDracoExtensionName, true);
  return Status::Ok();
}

}  // namespace segmorph
