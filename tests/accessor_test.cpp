#include "accessor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace segmorph {
namespace {

// A model with one buffer holding `bytes`, one bufferView over all of it, and one accessor over that view.
tinygltf::Model model_with(const std::vector<unsigned char>& bytes, int component_type, int type, size_t count,
                           size_t byte_stride = 0) {
  tinygltf::Model model;
  model.buffers.emplace_back();
  model.buffers[0].data = bytes;
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteLength = bytes.size();
  view.byteStride = byte_stride;
  model.bufferViews.push_back(view);
  tinygltf::Accessor accessor;
  accessor.bufferView = 0;
  accessor.componentType = component_type;
  accessor.type = type;
  accessor.count = count;
  model.accessors.push_back(accessor);
  return model;
}

template <typename T>
std::vector<unsigned char> bytes_of(const std::vector<T>& values) {
  std::vector<unsigned char> bytes(values.size() * sizeof(T));
  std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

TEST(Accessor, ReadsFloatsWithStride) {
  // Two VEC2 elements interleaved with one float of padding each: stride 12 bytes.
  const auto model = model_with(bytes_of<float>({1, 2, 99, 3, 4, 99}), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                TINYGLTF_TYPE_VEC2, 2, 12);
  std::vector<float> out;
  int components = 0;
  ASSERT_TRUE(read_floats(model, 0, "test", out, &components).ok());
  EXPECT_EQ(components, 2);
  EXPECT_EQ(out, (std::vector<float>{1, 2, 3, 4}));
}

TEST(Accessor, NormalizedIntegersFollowTheSpecification) {
  std::vector<float> out;
  auto u8 = model_with({0, 255, 51, 0}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_SCALAR, 3);
  u8.accessors[0].normalized = true;
  ASSERT_TRUE(read_floats(u8, 0, "test", out).ok());
  EXPECT_EQ(out, (std::vector<float>{0.0f, 1.0f, 0.2f}));

  auto i16 = model_with(bytes_of<int16_t>({-32768, 32767}), TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_TYPE_SCALAR, 2);
  i16.accessors[0].normalized = true;
  ASSERT_TRUE(read_floats(i16, 0, "test", out).ok());
  EXPECT_EQ(out, (std::vector<float>{-1.0f, 1.0f}));  // -32768/32767 clamps to -1
}

TEST(Accessor, SparseValuesReplaceTheBase) {
  // Base: 4 zeros (no bufferView); sparse: elements 1 and 3 become 5 and 7.
  tinygltf::Model model = model_with(bytes_of<uint16_t>({1, 3}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, 4);
  model.buffers[0].data.resize(4);
  const auto values = bytes_of<float>({5, 7});
  model.buffers[0].data.insert(model.buffers[0].data.end(), values.begin(), values.end());
  model.bufferViews[0].byteLength = 4;
  tinygltf::BufferView value_view;
  value_view.buffer = 0;
  value_view.byteOffset = 4;
  value_view.byteLength = 8;
  model.bufferViews.push_back(value_view);
  tinygltf::Accessor& accessor = model.accessors[0];
  accessor.bufferView = -1;
  accessor.sparse.isSparse = true;
  accessor.sparse.count = 2;
  accessor.sparse.indices.bufferView = 0;
  accessor.sparse.indices.byteOffset = 0;  // tinygltf leaves these uninitialized
  accessor.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  accessor.sparse.values.bufferView = 1;
  accessor.sparse.values.byteOffset = 0;
  std::vector<float> out;
  ASSERT_TRUE(read_floats(model, 0, "test", out).ok());
  EXPECT_EQ(out, (std::vector<float>{0, 5, 0, 7}));

  accessor.sparse.count = 3;  // runs past both views
  EXPECT_EQ(read_floats(model, 0, "test", out).code(), StatusCode::bad_data);
  accessor.sparse.count = 2;
  model.buffers[0].data[0] = 9;  // index 9 >= count 4
  EXPECT_EQ(read_floats(model, 0, "test", out).code(), StatusCode::bad_data);
}

TEST(Accessor, OutOfRangeDataIsBadData) {
  std::vector<float> out;
  // 3 VEC3 floats need 36 bytes; the view has 24.
  auto short_view = model_with(bytes_of<float>({1, 2, 3, 4, 5, 6}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3);
  EXPECT_EQ(read_floats(short_view, 0, "test", out).code(), StatusCode::bad_data);
  // The view claims more bytes than its buffer has.
  auto long_view = model_with(bytes_of<float>({1, 2, 3}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 1);
  long_view.bufferViews[0].byteLength = 4000;
  EXPECT_EQ(read_floats(long_view, 0, "test", out).code(), StatusCode::bad_data);
  // An offset that overflows when added.
  auto offset = model_with(bytes_of<float>({1, 2, 3}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 1);
  offset.accessors[0].byteOffset = SIZE_MAX - 3;
  EXPECT_EQ(read_floats(offset, 0, "test", out).code(), StatusCode::bad_data);
  // A huge count.
  auto huge = model_with(bytes_of<float>({1, 2, 3}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, SIZE_MAX / 2);
  EXPECT_EQ(read_floats(huge, 0, "test", out).code(), StatusCode::bad_data);
  // No such accessor, no such bufferView.
  EXPECT_EQ(read_floats(huge, 7, "test", out).code(), StatusCode::bad_data);
  huge.accessors[0].bufferView = 3;
  EXPECT_EQ(read_floats(huge, 0, "test", out).code(), StatusCode::bad_data);
}

TEST(Accessor, AbsurdCountWithoutDataIsRefusedBeforeAllocating) {
  tinygltf::Model model = model_with({}, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, size_t(1) << 40);
  model.accessors[0].bufferView = -1;
  std::vector<float> out;
  EXPECT_EQ(read_floats(model, 0, "test", out).code(), StatusCode::bad_data);
  model.accessors[0].count = 5;
  ASSERT_TRUE(read_floats(model, 0, "test", out).ok());
  EXPECT_EQ(out, std::vector<float>(15, 0.0f));
}

TEST(Accessor, NonFiniteFloatsAreBadData) {
  std::vector<float> out;
  auto model = model_with(bytes_of<float>({1, NAN, 3}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 1);
  EXPECT_EQ(read_floats(model, 0, "test", out).code(), StatusCode::bad_data);
  model = model_with(bytes_of<float>({1, INFINITY, 3}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 1);
  EXPECT_EQ(read_floats(model, 0, "test", out).code(), StatusCode::bad_data);
}

TEST(Accessor, UintsRefuseFloatsAndReadAllWidths) {
  std::vector<uint32_t> out;
  auto u16 = model_with(bytes_of<uint16_t>({1, 65535}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, 2);
  ASSERT_TRUE(read_uints(u16, 0, "test", out).ok());
  EXPECT_EQ(out, (std::vector<uint32_t>{1, 65535}));
  auto floats = model_with(bytes_of<float>({1}), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, 1);
  EXPECT_EQ(read_uints(floats, 0, "test", out).code(), StatusCode::bad_data);
}

TEST(Accessor, WriterRoundTripsDenseZeroAndSparse) {
  tinygltf::Model model;
  AccessorWriter writer(model);
  const std::vector<float> data = {1, -2, 3, 4, 5, -6};
  const int dense = writer.add_floats(data.data(), 2, TINYGLTF_TYPE_VEC3, true, TINYGLTF_TARGET_ARRAY_BUFFER);
  const int zeros = writer.add_zeros(4, TINYGLTF_TYPE_SCALAR, false);
  const int sparse = writer.add_sparse_floats(6, TINYGLTF_TYPE_SCALAR, {0, 5}, {1, 2});
  std::vector<float> out;
  ASSERT_TRUE(read_floats(model, dense, "dense", out).ok());
  EXPECT_EQ(out, data);
  EXPECT_EQ(model.accessors[size_t(dense)].minValues, (std::vector<double>{1, -2, -6}));
  EXPECT_EQ(model.accessors[size_t(dense)].maxValues, (std::vector<double>{4, 5, 3}));
  ASSERT_TRUE(read_floats(model, zeros, "zeros", out).ok());
  EXPECT_EQ(out, std::vector<float>(4, 0.0f));
  EXPECT_EQ(model.accessors[size_t(zeros)].bufferView, -1);
  ASSERT_TRUE(read_floats(model, sparse, "sparse", out).ok());
  EXPECT_EQ(out, (std::vector<float>{1, 0, 0, 0, 0, 2}));
  EXPECT_EQ(model.accessors[size_t(sparse)].bufferView, -1);
}

}  // namespace
}  // namespace segmorph
