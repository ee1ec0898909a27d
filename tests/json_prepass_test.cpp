// The JSON pass that lets tinygltf 2.7 load KHR_draco_mesh_compression primitives with an indices accessor
// that has no bufferView (valid glTF; see extensions/json_prepass.h).
#include "json_prepass.h"

#include <gtest/gtest.h>

#include <string>

namespace segmorph {
namespace {

const char* const kDraco =
    R"({"accessors":[{"count":3,"type":"VEC3","componentType":5126},{"count":3,"type":"SCALAR","componentType":5123},)"
    R"({"bufferView":0,"count":3,"type":"SCALAR","componentType":5123}],)"
    R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,)"
    R"("extensions":{"KHR_draco_mesh_compression":{"bufferView":1,"attributes":{"POSITION":0}}}},)"
    R"({"attributes":{"POSITION":0},"indices":2,"extensions":{"KHR_draco_mesh_compression":{"bufferView":1,"attributes":{"POSITION":0}}}},)"
    R"({"attributes":{"POSITION":0},"indices":1}]}],"extensionsUsed":["KHR_draco_mesh_compression"]})";

TEST(JsonPrepass, DropsOnlyDracoIndicesWithoutABufferView) {
  std::string json = kDraco;
  bool changed = false;
  ASSERT_TRUE(drop_draco_indices(json, changed).ok());
  EXPECT_TRUE(changed);
  // The first primitive loses its indices; the second's accessor has a bufferView and the third is not Draco's.
  EXPECT_EQ(json.find(R"({"attributes":{"POSITION":0},"extensions")"), json.find(R"("primitives":[)") + 14);
  EXPECT_NE(json.find(R"("indices":2)"), std::string::npos);
  EXPECT_NE(json.find(R"({"attributes":{"POSITION":0},"indices":1}]})"), std::string::npos);
  // Everything else as written.
  std::string expected = kDraco;
  expected.erase(expected.find(R"("indices":1,)"), 12);
  EXPECT_EQ(json, expected);
}

TEST(JsonPrepass, LeavesOtherFilesAlone) {
  const std::string plain = "{ \"asset\": {\"version\": \"2.0\"}, \"meshes\": [] }";
  std::string json = plain;
  bool changed = true;
  ASSERT_TRUE(drop_draco_indices(json, changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_EQ(json, plain);
  // Draco primitives whose indices are fine: parsed, unchanged, white space kept.
  std::string with_view =
      "{\"accessors\": [{\"bufferView\": 0}],\n \"meshes\": [{\"primitives\": [{\"indices\": 0, "
      "\"extensions\": {\"KHR_draco_mesh_compression\": {}}}]}]}";
  const std::string before = with_view;
  ASSERT_TRUE(drop_draco_indices(with_view, changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_EQ(with_view, before);
}

TEST(JsonPrepass, MalformedOrHostileJsonIsRefusedCleanly) {
  bool changed = false;
  for (std::string json :
       {std::string("{\"KHR_draco_mesh_compression\": [1, 2"), std::string("{\"KHR_draco_mesh_compression\" 1}"),
        std::string("{\"KHR_draco_mesh_compression\": \"unterminated}"),
        std::string("{\"KHR_draco_mesh_compression\": 1} trailing"),
        "{\"KHR_draco_mesh_compression\":" + std::string(100000, '[') + std::string(100000, ']') + "}"}) {
    const std::string before = json;
    EXPECT_FALSE(drop_draco_indices(json, changed).ok()) << before.substr(0, 60);
    EXPECT_EQ(json, before);
  }
  // Odd but parseable: escaped quotes in strings, nested empty containers, indices that are not plain numbers.
  std::string odd =
      R"({"accessors":[{}],"x":"a\"KHR_draco_mesh_compression\"b","meshes":[{"primitives":[)"
      R"({"indices":-1,"extensions":{"KHR_draco_mesh_compression":{}}},{"indices":"0","extensions":)"
      R"({"KHR_draco_mesh_compression":{}}},{"indices":99,"extensions":{"KHR_draco_mesh_compression":{}}}]}]})";
  const std::string before = odd;
  ASSERT_TRUE(drop_draco_indices(odd, changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_EQ(odd, before);
}

TEST(JsonPrepass, DeepNestingIsRefusedBeforeTinygltfSeesIt) {
  EXPECT_TRUE(check_json_nesting("{\"a\": [[[{\"b\": \"[[[[[[[[[[\"}]]]}").ok());  // brackets in strings do not count
  EXPECT_TRUE(check_json_nesting(std::string(512, '[') + std::string(512, ']')).ok());
  const Status status = check_json_nesting(std::string(513, '[') + std::string(513, ']'));
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("nested deeper"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace segmorph
