#include "accessor.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>

namespace segmorph {
namespace {

// An accessor with no buffer data behind it (all zeros, or sparse) still allocates count elements;
// this bounds what a hostile file can make us allocate that way.
constexpr size_t kMaxUnbackedElements = size_t(1) << 26;

double component_value(const unsigned char* p, int component_type, bool normalized) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      uint8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
  return 0.0;
}

Status accessor_error(int index, const std::string& what, const std::string& message) {
  return Status(StatusCode::bad_data, "accessor " + std::to_string(index) + " (" + what + "): " + message);
}

// Checks that [offset, offset + length) lies inside bufferView `view` and returns a pointer to it.
Status view_range(const tinygltf::Model& model, int view, size_t offset, size_t length, int index,
                  const std::string& what, const unsigned char** data) {
  size_t size = 0;
  SEGMORPH_RETURN_IF_ERROR(
      buffer_view_bytes(model, view, "accessor " + std::to_string(index) + " (" + what + ")", data, &size));
  if (offset > size || length > size - offset)
    return accessor_error(index, what, "data lies outside bufferView " + std::to_string(view));
  *data += offset;
  return Status::Ok();
}

// Reads every element of accessor `index` as doubles and hands each to sink(element, component, value).
template <typename Sink>
Status read_accessor(const tinygltf::Model& model, int index, const std::string& what, int* components_out,
                     size_t* count_out, Sink sink) {
  if (index < 0 || size_t(index) >= model.accessors.size())
    return Status(StatusCode::bad_data, what + " names accessor " + std::to_string(index) + ", which does not exist");
  const tinygltf::Accessor& accessor = model.accessors[size_t(index)];
  const int components = components_of_type(accessor.type);
  const int component_bytes = bytes_of_component(accessor.componentType);
  if (components == 0 || component_bytes == 0) return accessor_error(index, what, "unknown type or componentType");
  // Matrix columns start on 4-byte boundaries (glTF 2.0, "Data Alignment").
  const int rows = accessor.type == TINYGLTF_TYPE_MAT2 ? 2 : accessor.type == TINYGLTF_TYPE_MAT3 ? 3
                 : accessor.type == TINYGLTF_TYPE_MAT4 ? 4 : components;
  const int columns = components / rows;
  const size_t column_bytes = (size_t(rows * component_bytes) + 3) / 4 * 4;
  const size_t element_bytes = columns == 1 ? size_t(components * component_bytes) : column_bytes * columns;
  const size_t count = accessor.count;
  *components_out = components;
  *count_out = count;

  auto read_element = [&](const unsigned char* p, size_t element) {
    for (int c = 0; c < columns; ++c)
      for (int r = 0; r < rows; ++r)
        sink(element, c * rows + r,
             component_value(p + (columns == 1 ? 0 : c * column_bytes) + r * component_bytes, accessor.componentType,
                             accessor.normalized));
  };

  if (accessor.bufferView >= 0) {
    size_t stride = element_bytes;
    if (size_t(accessor.bufferView) < model.bufferViews.size() && model.bufferViews[size_t(accessor.bufferView)].byteStride)
      stride = model.bufferViews[size_t(accessor.bufferView)].byteStride;
    if (stride < element_bytes) return accessor_error(index, what, "byteStride is smaller than one element");
    if (accessor.byteOffset % size_t(component_bytes) != 0)
      return accessor_error(index, what, "byteOffset is not a multiple of the component size");
    if (count != 0 && (count - 1) > (SIZE_MAX - element_bytes) / stride)
      return accessor_error(index, what, "count is too large");
    const size_t span = count == 0 ? 0 : stride * (count - 1) + element_bytes;
    const unsigned char* data = nullptr;
    SEGMORPH_RETURN_IF_ERROR(view_range(model, accessor.bufferView, accessor.byteOffset, span, index, what, &data));
    for (size_t e = 0; e < count; ++e) read_element(data + e * stride, e);
  } else {
    if (count > kMaxUnbackedElements)
      return accessor_error(index, what, "count " + std::to_string(count) + " with no bufferView is absurd");
    for (size_t e = 0; e < count; ++e)
      for (int c = 0; c < components; ++c) sink(e, c, 0.0);
  }

  if (accessor.sparse.isSparse) {
    const auto& sparse = accessor.sparse;
    if (sparse.count < 1 || size_t(sparse.count) > count)
      return accessor_error(index, what, "sparse count is out of range");
    const int index_bytes = bytes_of_component(sparse.indices.componentType);
    if (index_bytes == 0 || sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
        sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
        sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_SHORT)
      return accessor_error(index, what, "sparse indices have an invalid componentType");
    const unsigned char* indices = nullptr;
    const unsigned char* values = nullptr;
    SEGMORPH_RETURN_IF_ERROR(view_range(model, sparse.indices.bufferView, size_t(sparse.indices.byteOffset),
                                        size_t(sparse.count) * size_t(index_bytes), index, what + ", sparse indices",
                                        &indices));
    SEGMORPH_RETURN_IF_ERROR(view_range(model, sparse.values.bufferView, size_t(sparse.values.byteOffset),
                                        size_t(sparse.count) * element_bytes, index, what + ", sparse values", &values));
    double previous = -1;
    for (int i = 0; i < sparse.count; ++i) {
      const double target = component_value(indices + size_t(i) * size_t(index_bytes), sparse.indices.componentType, false);
      if (target >= double(count) || target <= previous)
        return accessor_error(index, what, "sparse indices are out of range or not increasing");
      previous = target;
      read_element(values + size_t(i) * element_bytes, size_t(target));
    }
  }
  return Status::Ok();
}

}  // namespace

Status buffer_view_bytes(const tinygltf::Model& model, int view, const std::string& what, const unsigned char** data,
                         size_t* size) {
  auto error = [&](const std::string& message) {
    return Status(StatusCode::bad_data, what + ": bufferView " + std::to_string(view) + " " + message);
  };
  if (view < 0 || size_t(view) >= model.bufferViews.size()) return error("does not exist");
  const tinygltf::BufferView& bv = model.bufferViews[size_t(view)];
  if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size()) return error("names a missing buffer");
  const tinygltf::Buffer& buffer = model.buffers[size_t(bv.buffer)];
  if (bv.byteOffset > buffer.data.size() || bv.byteLength > buffer.data.size() - bv.byteOffset)
    return error("lies outside its buffer");
  *data = buffer.data.data() + bv.byteOffset;
  *size = bv.byteLength;
  return Status::Ok();
}

int components_of_type(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
  }
  return 0;
}

int type_of_components(int components) {
  switch (components) {
    case 1:
      return TINYGLTF_TYPE_SCALAR;
    case 2:
      return TINYGLTF_TYPE_VEC2;
    case 3:
      return TINYGLTF_TYPE_VEC3;
    default:
      return TINYGLTF_TYPE_VEC4;
  }
}

int bytes_of_component(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
  }
  return 0;
}

Status read_floats(const tinygltf::Model& model, int index, const std::string& what, std::vector<float>& out,
                   int* components) {
  int local_components = 0;
  size_t count = 0;
  bool finite = true;
  out.clear();
  Status status = read_accessor(model, index, what, &local_components, &count, [&](size_t e, int c, double v) {
    if (out.empty()) out.resize(count * size_t(local_components));
    finite = finite && std::isfinite(v);
    out[e * size_t(local_components) + size_t(c)] = float(v);
  });
  if (!status.ok()) return status;
  if (!finite) return accessor_error(index, what, "contains NaN or infinite values");
  out.resize(count * size_t(local_components));
  if (components) *components = local_components;
  return Status::Ok();
}

Status read_uints(const tinygltf::Model& model, int index, const std::string& what, std::vector<uint32_t>& out,
                  int* components) {
  if (index >= 0 && size_t(index) < model.accessors.size()) {
    const int type = model.accessors[size_t(index)].componentType;
    if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      return accessor_error(index, what, "must have an unsigned integer componentType");
    if (model.accessors[size_t(index)].normalized) return accessor_error(index, what, "must not be normalized");
  }
  int local_components = 0;
  size_t count = 0;
  out.clear();
  Status status = read_accessor(model, index, what, &local_components, &count, [&](size_t e, int c, double v) {
    if (out.empty()) out.resize(count * size_t(local_components));
    out[e * size_t(local_components) + size_t(c)] = uint32_t(v);
  });
  if (!status.ok()) return status;
  out.resize(count * size_t(local_components));
  if (components) *components = local_components;
  return Status::Ok();
}

AccessorWriter::AccessorWriter(tinygltf::Model& model) : model_(model) {
  if (model_.buffers.empty()) model_.buffers.emplace_back();
  buffer_ = int(model_.buffers.size()) - 1;
}

void AccessorWriter::reserve(size_t bytes) {
  std::vector<unsigned char>& buffer = model_.buffers[size_t(buffer_)].data;
  buffer.reserve(buffer.size() + bytes);
}

int AccessorWriter::add_view(const void* data, size_t bytes, int target) {
  std::vector<unsigned char>& buffer = model_.buffers[size_t(buffer_)].data;
  buffer.resize((buffer.size() + 3) / 4 * 4, 0);  // 4-byte alignment for every component type
  tinygltf::BufferView view;
  view.buffer = buffer_;
  view.byteOffset = buffer.size();
  view.byteLength = bytes;
  view.target = target;
  buffer.insert(buffer.end(), static_cast<const unsigned char*>(data), static_cast<const unsigned char*>(data) + bytes);
  model_.bufferViews.push_back(view);
  return int(model_.bufferViews.size()) - 1;
}

namespace {

void set_bounds(tinygltf::Accessor& accessor, const float* data, size_t count, int components) {
  accessor.minValues.assign(size_t(components), count ? INFINITY : 0.0);
  accessor.maxValues.assign(size_t(components), count ? -INFINITY : 0.0);
  for (size_t e = 0; e < count; ++e)
    for (int c = 0; c < components; ++c) {
      const double v = data[e * size_t(components) + size_t(c)];
      accessor.minValues[size_t(c)] = std::min(accessor.minValues[size_t(c)], v);
      accessor.maxValues[size_t(c)] = std::max(accessor.maxValues[size_t(c)], v);
    }
}

tinygltf::Accessor float_accessor(size_t count, int type) {
  tinygltf::Accessor accessor;
  accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  accessor.count = count;
  accessor.type = type;
  return accessor;
}

}  // namespace

int AccessorWriter::add_floats(const float* data, size_t count, int type, bool bounds, int target) {
  const int components = components_of_type(type);
  tinygltf::Accessor accessor = float_accessor(count, type);
  accessor.bufferView = add_view(data, count * size_t(components) * sizeof(float), target);
  if (bounds) set_bounds(accessor, data, count, components);
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_normalized_shorts(const float* data, size_t count, int type, bool is_signed) {
  const size_t values = count * size_t(components_of_type(type));
  const double scale = is_signed ? 32767.0 : 65535.0, low = is_signed ? -1.0 : 0.0;
  std::vector<uint16_t> shorts(values);
  for (size_t i = 0; i < values; ++i) {
    const long q = std::lround(std::clamp(double(data[i]), low, 1.0) * scale);
    shorts[i] = is_signed ? uint16_t(int16_t(q)) : uint16_t(q);
  }
  tinygltf::Accessor accessor;
  accessor.componentType = is_signed ? TINYGLTF_COMPONENT_TYPE_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  accessor.normalized = true;
  accessor.count = count;
  accessor.type = type;
  accessor.bufferView = add_view(shorts.data(), values * sizeof(uint16_t), 0);
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_indices(const std::vector<uint32_t>& indices) {
  tinygltf::Accessor accessor;
  accessor.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  accessor.count = indices.size();
  accessor.type = TINYGLTF_TYPE_SCALAR;
  accessor.bufferView = add_view(indices.data(), indices.size() * sizeof(uint32_t), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_described_indices(size_t count, size_t vertex_count) {
  tinygltf::Accessor accessor;
  accessor.componentType =
      vertex_count <= 65535 ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  accessor.count = count;
  accessor.type = TINYGLTF_TYPE_SCALAR;
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_unsigned_integers(const std::vector<uint16_t>& data, int type, int component_type,
                                          bool normalized, int target) {
  assert(component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
         component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  tinygltf::Accessor accessor;
  accessor.componentType = component_type;
  accessor.normalized = normalized;
  accessor.count = data.size() / size_t(components_of_type(type));
  accessor.type = type;
  if (component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
    const std::vector<uint8_t> bytes(data.begin(), data.end());
    accessor.bufferView = add_view(bytes.data(), bytes.size(), target);
  } else {
    accessor.bufferView = add_view(data.data(), data.size() * sizeof(uint16_t), target);
  }
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_described(const float* data, size_t count, int type) {
  tinygltf::Accessor accessor = float_accessor(count, type);
  set_bounds(accessor, data, count, components_of_type(type));
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_zeros(size_t count, int type, bool bounds) {
  tinygltf::Accessor accessor = float_accessor(count, type);
  if (bounds) {
    accessor.minValues.assign(size_t(components_of_type(type)), 0.0);
    accessor.maxValues.assign(size_t(components_of_type(type)), 0.0);
  }
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

int AccessorWriter::add_sparse_floats(size_t count, int type, const std::vector<uint32_t>& indices,
                                      const std::vector<float>& values) {
  tinygltf::Accessor accessor = float_accessor(count, type);
  accessor.sparse.isSparse = true;
  accessor.sparse.count = int(indices.size());
  if (count <= 65536) {
    std::vector<uint16_t> narrow(indices.begin(), indices.end());
    accessor.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    accessor.sparse.indices.bufferView = add_view(narrow.data(), narrow.size() * sizeof(uint16_t), 0);
  } else {
    accessor.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    accessor.sparse.indices.bufferView = add_view(indices.data(), indices.size() * sizeof(uint32_t), 0);
  }
  accessor.sparse.indices.byteOffset = 0;
  accessor.sparse.values.bufferView = add_view(values.data(), values.size() * sizeof(float), 0);
  accessor.sparse.values.byteOffset = 0;
  model_.accessors.push_back(accessor);
  return int(model_.accessors.size()) - 1;
}

}  // namespace segmorph
