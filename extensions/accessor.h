// Bounds-checked reading and writing of glTF accessors. tiny_gltf.h stays behind converter/ and extensions/.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "segmorph/status.h"

namespace segmorph {

// Components per element of a tinygltf accessor type (TINYGLTF_TYPE_*), 0 when unknown.
int components_of_type(int type);
// The accessor type (TINYGLTF_TYPE_SCALAR to VEC4) of 1 to 4 components; VEC4 for any other count.
int type_of_components(int components);
// Bytes of one component (TINYGLTF_COMPONENT_TYPE_*), 0 when unknown.
int bytes_of_component(int component_type);

// The bytes of bufferView `view`, checked against its buffer; `what` names it in errors.
Status buffer_view_bytes(const tinygltf::Model& model, int view, const std::string& what, const unsigned char** data,
                         size_t* size);

// Reads accessor `index` as count × components floats, applying byteStride, normalization and sparse
// substitution. Every offset is checked against its bufferView and buffer before it is read; an accessor
// without bufferView reads as zeros, as the specification says. `what` names the accessor in errors.
Status read_floats(const tinygltf::Model& model, int index, const std::string& what, std::vector<float>& out,
                   int* components = nullptr);

// Reads an integer accessor (indices, joints) as count × components unsigned values.
Status read_uints(const tinygltf::Model& model, int index, const std::string& what, std::vector<uint32_t>& out,
                  int* components = nullptr);

// Builds a bufferView and accessor from new data and appends them to `model`, whose last buffer
// receives the bytes (a fresh buffer is added when the model has none).
class AccessorWriter {
 public:
  explicit AccessorWriter(tinygltf::Model& model);

  // count × components floats of type TINYGLTF_TYPE_*; min/max are written when `bounds` is set
  // (glTF requires them on POSITION). target: TINYGLTF_TARGET_ARRAY_BUFFER etc., 0 for none.
  int add_floats(const float* data, size_t count, int type, bool bounds, int target);
  // An accessor with no bufferView whose min/max describe `data`, held elsewhere (by an extension).
  int add_described(const float* data, size_t count, int type);
  // An accessor of `count` zero elements with no bufferView: glTF's compact form for all-zero data.
  int add_zeros(size_t count, int type, bool bounds);
  // A float accessor that is zero except for `indices` (strictly increasing element indices) whose
  // elements are `values` (indices.size() × components floats): a sparse accessor with no bufferView.
  int add_sparse_floats(size_t count, int type, const std::vector<uint32_t>& indices, const std::vector<float>& values);
  // count × components values in [0, 1] (unsigned) or [−1, 1] (signed) as normalized 16-bit integers, rounded to
  // the nearest, as glTF allows for morph weights and rotations. Values outside the range are clamped.
  int add_normalized_shorts(const float* data, size_t count, int type, bool is_signed);
  // An index accessor of `count` indices into `vertex_count` vertices with no bufferView: the triangles of a
  // KHR_draco_mesh_compression primitive, which the extension holds (validators warn about a TRIANGLES primitive
  // whose vertex count is not a multiple of 3 without one). tinygltf 2.7 refuses such accessors; load_gltf drops
  // them before it parses (json_prepass.h).
  int add_described_indices(size_t count, size_t vertex_count);
  // An unsigned-int index accessor (TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER).
  int add_indices(const std::vector<uint32_t>& indices);
  // count × components unsigned integers of component type UNSIGNED_BYTE or UNSIGNED_SHORT (each value must fit),
  // normalized or not: JOINTS_n, and WEIGHTS_n stored as normalized integers.
  int add_unsigned_integers(const std::vector<uint16_t>& data, int type, int component_type, bool normalized,
                            int target);
  // A bufferView holding `bytes` (for data an extension refers to).
  int add_view(const void* data, size_t bytes, int target);
  // Room for `bytes` more in the buffer: a writer that knows about how much it will add grows the buffer once,
  // where growing by doubling copies it, holding both copies for a moment, at each step.
  void reserve(size_t bytes);

 private:

  tinygltf::Model& model_;
  int buffer_;
};

}  // namespace segmorph
