// GltfBuilder: tinygltf::Model fixtures built in memory for tests, one call per glTF object.
//
// All data goes into buffer 0, one tightly packed bufferView per accessor, each view 4-byte aligned.
// Every call returns the index of what it added, so a test reads like the glTF JSON it builds. Nothing is
// validated: tests of bad data build the model and then break it by hand (model.accessors[i].count += 1).
#pragma once

#include <tiny_gltf.h>

#include <cassert>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace segmorph::test {

class GltfBuilder {
 public:
  tinygltf::Model model;

  GltfBuilder() {
    model.buffers.emplace_back();
    model.scenes.emplace_back();
    model.defaultScene = 0;
  }

  // --- Buffers and accessors -------------------------------------------------------------------------

  // A bufferView over a copy of `bytes` bytes at `data`.
  int add_view(const void* data, size_t bytes) {
    std::vector<unsigned char>& buffer = model.buffers[0].data;
    buffer.resize((buffer.size() + 3) / 4 * 4, 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    const unsigned char* begin = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), begin, begin + bytes);
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size()) - 1;
  }

  // A FLOAT accessor of `type` (TINYGLTF_TYPE_*) over `values`, whose size must be a multiple of the
  // type's component count: count = values.size() / components.
  int add_floats(const std::vector<float>& values, int type) {
    return add_accessor(values.data(), values.size(), TINYGLTF_COMPONENT_TYPE_FLOAT, type, false);
  }
  int add_scalars(const std::vector<float>& values) { return add_floats(values, TINYGLTF_TYPE_SCALAR); }
  int add_vec3(const std::vector<float>& values) { return add_floats(values, TINYGLTF_TYPE_VEC3); }
  int add_vec4(const std::vector<float>& values) { return add_floats(values, TINYGLTF_TYPE_VEC4); }
  // MAT4 accessor: 16 floats per matrix, column-major as glTF stores them.
  int add_mat4(const std::vector<float>& values) { return add_floats(values, TINYGLTF_TYPE_MAT4); }

  // An unsigned integer accessor (indices, joints): component_type is TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
  // _SHORT or _INT, and every value must fit in it.
  int add_uints(const std::vector<uint32_t>& values, int type, int component_type) {
    return add_integers(values, type, component_type, false);
  }

  // A SHORT accessor, not normalized: KHR_mesh_quantization's integer positions and morph deltas.
  int add_shorts(const std::vector<int>& values, int type) {
    std::vector<uint32_t> bits;
    for (int v : values) {
      assert(v >= INT16_MIN && v <= INT16_MAX);
      bits.push_back(uint16_t(int16_t(v)));  // two's complement, stored little-endian by add_integers
    }
    return add_integers(bits, type, TINYGLTF_COMPONENT_TYPE_SHORT, false);
  }

  // A normalized unsigned accessor (weights): `raw` are the stored integers, read as raw / 255 for
  // UNSIGNED_BYTE and raw / 65535 for UNSIGNED_SHORT.
  int add_normalized(const std::vector<uint32_t>& raw, int type, int component_type) {
    return add_integers(raw, type, component_type, true);
  }

  // --- Nodes -------------------------------------------------------------------------------------------

  // A node with optional TRS (empty vectors are absent: identity). rotation is a quaternion (x, y, z, w).
  int add_node(const std::vector<double>& translation = {}, const std::vector<double>& rotation = {},
               const std::vector<double>& scale = {}) {
    tinygltf::Node node;
    node.translation = translation;
    node.rotation = rotation;
    node.scale = scale;
    model.nodes.push_back(node);
    return int(model.nodes.size()) - 1;
  }

  // A node given by a 4×4 matrix, 16 numbers column-major (the translation is elements 12, 13, 14).
  int add_matrix_node(const std::vector<double>& matrix) {
    assert(matrix.size() == 16);
    tinygltf::Node node;
    node.matrix = matrix;
    model.nodes.push_back(node);
    return int(model.nodes.size()) - 1;
  }

  void add_child(int parent, int child) { model.nodes[size_t(parent)].children.push_back(child); }
  void add_root(int node) { model.scenes[0].nodes.push_back(node); }

  // A node instantiating `mesh`, skinned by `skin` when it is not -1.
  int add_mesh_node(int mesh, int skin = -1) {
    const int node = add_node();
    model.nodes[size_t(node)].mesh = mesh;
    model.nodes[size_t(node)].skin = skin;
    return node;
  }

  // --- Meshes and skins ----------------------------------------------------------------------------------

  // A mesh with one triangle-list primitive over the VEC3 accessor `position` (indices -1: none).
  int add_mesh(int position, int indices = -1) {
    tinygltf::Mesh mesh;
    mesh.primitives.emplace_back();
    tinygltf::Primitive& primitive = mesh.primitives.back();
    primitive.attributes["POSITION"] = position;
    primitive.indices = indices;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;  // tinygltf's parser defaults mode to this; its constructor does not
    model.meshes.push_back(mesh);
    return int(model.meshes.size()) - 1;
  }

  tinygltf::Primitive& primitive(int mesh, int p = 0) { return model.meshes[size_t(mesh)].primitives[size_t(p)]; }

  void set_attribute(int mesh, const std::string& name, int accessor, int p = 0) {
    primitive(mesh, p).attributes[name] = accessor;
  }

  // Adds a morph target with the given attributes ({"POSITION", accessor}, {"NORMAL", accessor}, ...).
  void add_target(int mesh, const std::map<std::string, int>& attributes, int p = 0) {
    primitive(mesh, p).targets.push_back(attributes);
  }

  // JOINTS_n and WEIGHTS_n of set `set`.
  void set_skin_attributes(int mesh, int set, int joints, int weights, int p = 0) {
    set_attribute(mesh, "JOINTS_" + std::to_string(set), joints, p);
    set_attribute(mesh, "WEIGHTS_" + std::to_string(set), weights, p);
  }

  // A skin over `joints` (node indices), with a MAT4 accessor of inverse bind matrices or -1 (identity).
  int add_skin(const std::vector<int>& joints, int inverse_bind_matrices = -1) {
    tinygltf::Skin skin;
    skin.joints = joints;
    skin.inverseBindMatrices = inverse_bind_matrices;
    model.skins.push_back(skin);
    return int(model.skins.size()) - 1;
  }

  // --- Animations ------------------------------------------------------------------------------------------

  int add_animation(const std::string& name = "") {
    tinygltf::Animation animation;
    animation.name = name;
    model.animations.push_back(animation);
    return int(model.animations.size()) - 1;
  }

  // A sampler with key `times` and `values` and a channel driving `path` ("translation", "rotation",
  // "scale", "weights") of `node`. values holds one element per key (VEC3, VEC4 quaternion (x, y, z, w), or
  // target-count scalars for weights), or for CUBICSPLINE three per key: in-tangent, value, out-tangent.
  // Returns the sampler index.
  int add_channel(int animation, int node, const std::string& path, const std::vector<float>& times,
                  const std::vector<float>& values, const std::string& interpolation = "LINEAR") {
    const int type = path == "rotation"  ? TINYGLTF_TYPE_VEC4
                     : path == "weights" ? TINYGLTF_TYPE_SCALAR
                                         : TINYGLTF_TYPE_VEC3;
    tinygltf::AnimationSampler sampler;
    sampler.input = add_scalars(times);
    sampler.output = add_floats(values, type);
    sampler.interpolation = interpolation;
    tinygltf::Animation& target = model.animations[size_t(animation)];
    target.samplers.push_back(sampler);
    tinygltf::AnimationChannel channel;
    channel.sampler = int(target.samplers.size()) - 1;
    channel.target_node = node;
    channel.target_path = path;
    target.channels.push_back(channel);
    return channel.sampler;
  }

 private:
  int add_accessor(const void* data, size_t value_count, int component_type, int type, bool normalized) {
    const size_t components = components_of(type);
    assert(components != 0 && value_count % components == 0);
    tinygltf::Accessor accessor;
    accessor.bufferView = add_view(data, value_count * component_bytes(component_type));
    accessor.componentType = component_type;
    accessor.type = type;
    accessor.count = value_count / components;
    accessor.normalized = normalized;
    model.accessors.push_back(accessor);
    return int(model.accessors.size()) - 1;
  }

  int add_integers(const std::vector<uint32_t>& values, int type, int component_type, bool normalized) {
    std::vector<unsigned char> bytes;
    const size_t width = component_bytes(component_type);
    for (uint32_t v : values) {
      assert(width == 4 || v < (uint32_t(1) << (8 * width)));
      for (size_t b = 0; b < width; ++b) bytes.push_back((unsigned char)(v >> (8 * b)));  // little-endian
    }
    return add_accessor(bytes.data(), values.size(), component_type, type, normalized);
  }

  static size_t components_of(int type) {
    switch (type) {
      case TINYGLTF_TYPE_SCALAR:
        return 1;
      case TINYGLTF_TYPE_VEC2:
        return 2;
      case TINYGLTF_TYPE_VEC3:
        return 3;
      case TINYGLTF_TYPE_VEC4:
        return 4;
      case TINYGLTF_TYPE_MAT4:
        return 16;
    }
    return 0;
  }

  static size_t component_bytes(int component_type) {
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return 1;
      case TINYGLTF_COMPONENT_TYPE_SHORT:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return 2;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return 4;
    }
    assert(false && "unsupported component type");
    return 0;
  }
};

}  // namespace segmorph::test
