// segmorph bake: what it writes, and bad inputs of every kind failing cleanly (every command reads its input as
// bake does).
#include <gtest/gtest.h>

#include "cli_run.h"

using namespace cli_testing;

TEST(Cli, BadInputsFailCleanly) {
  const std::string directory = output_directory("inputs");
  expect_clean_failure(directory + "/missing.glb", "cannot open");
  expect_clean_failure(directory, "no .obj files in the folder (a folder input is an OBJ sequence)");

  write_text(directory + "/text.gltf", "hello, I am not glTF\n");
  expect_clean_failure(directory + "/text.gltf", "not a glTF file");
  // GLB chunks longer than the file: tinygltf 2.7 reads past its buffer (found by fuzzing). A file cut short,
  // and one whose header says so but whose BIN chunk claims 4 bytes more.
  const std::string glb = read_text(sample("AnimatedMorphCube/AnimatedMorphCube.glb"));
  write_text(directory + "/short.glb", glb.substr(0, glb.size() - 4));
  expect_clean_failure(directory + "/short.glb", "chunk lengths");
  std::string longer = glb;
  const size_t bin = 20 + size_t(uint8_t(glb[12])) + (size_t(uint8_t(glb[13])) << 8) + (size_t(uint8_t(glb[14])) << 16);
  longer[bin] = char(uint8_t(longer[bin]) + 4);  // the BIN chunk's length, low byte (0xBC in this file: no carry)
  write_text(directory + "/long_chunk.glb", longer);
  expect_clean_failure(directory + "/long_chunk.glb", "chunk lengths");
  // 30 000 nested arrays crash tinygltf 2.7's recursive parser (stack overflow); segmorph refuses them first.
  write_text(directory + "/deep.gltf",
             "{\"asset\": {\"version\": \"2.0\"}, \"x\": " + std::string(30000, '[') + std::string(30000, ']') + "}");
  expect_clean_failure(directory + "/deep.gltf", "nested deeper");

  write_text(directory + "/broken.gltf", "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ {");
  expect_clean_failure(directory + "/broken.gltf", "cannot parse");

  const std::string fox = read_text(sample("Fox/Fox.glb"));
  write_text(directory + "/truncated.glb", fox.substr(0, fox.size() / 2));
  expect_clean_failure(directory + "/truncated.glb", "cannot parse");

  write_text(directory + "/still.gltf", R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{}]})");
  expect_clean_failure(directory + "/still.gltf", "nothing animated");

  write_text(directory + "/meshopt.gltf", R"({"asset":{"version":"2.0"},"extensionsUsed":["EXT_meshopt_compression"],)"
                                          R"("extensionsRequired":["EXT_meshopt_compression"],"nodes":[{}]})");
  expect_clean_failure(directory + "/meshopt.gltf", "EXT_meshopt_compression");

  // SimpleMorph with its first accessor claiming more vertices than its bufferView holds.
  std::string morph = simple_morph_in(directory);
  const size_t count = morph.find("\"count\"");
  ASSERT_NE(count, std::string::npos);
  morph.replace(count, morph.find_first_of(",}", count) - count, "\"count\" : 3000000");
  write_text(directory + "/out_of_range.gltf", morph);
  expect_clean_failure(directory + "/out_of_range.gltf", "accessor");
}

// SimpleMorph with its last key time (the fifth float of simpleMorphAnimation.bin) at 1e9 s: at --fps 30, 3e10
// frames. Refused in one line; before, sampling hung building them.
TEST(Cli, AGridOfTooManyFramesIsRefused) {
  const std::string directory = output_directory("forever");
  write_text(directory + "/forever.gltf", simple_morph_in(directory));
  {
    std::fstream times(directory + "/simpleMorphAnimation.bin", std::ios::in | std::ios::out | std::ios::binary);
    const float forever = 1e9f;
    times.seekp(16);
    times.write(reinterpret_cast<const char*>(&forever), sizeof(forever));
    ASSERT_TRUE(times.good());
  }
  expect_clean_failure(directory + "/forever.gltf", "frames at --fps 30, above the 1e+06 a clip may have", "bake",
                       "--fps 30");
  EXPECT_EQ(run("info -q " + directory + "/forever.gltf").exit_code, 0) << "without --fps, the frames are the keys";
}

// SimpleMorph with a TEXCOORD_0 accessor whose bufferView names a missing buffer, or lies outside its buffer: bake
// keeps the attribute without reading it, and repack copied the view unchecked (found by tests/fuzz).
TEST(Cli, UnreadBufferViewOutsideItsBufferFailsCleanly) {
  const std::string directory = output_directory("views");
  const std::string original = simple_morph_in(directory);
  for (const std::string view :
       {R"({"buffer":7,"byteLength":24})", R"({"buffer":1,"byteOffset":48,"byteLength":24})"}) {
    std::string morph = original;
    const std::string position = "\"POSITION\":1";
    morph.insert(morph.find(position) + position.size(), ",\"TEXCOORD_0\":6");
    // New last entries of "accessors" (followed by "asset") and "bufferViews" (followed by "accessors").
    morph.insert(morph.rfind(']', morph.find("\"asset\"")),
                 R"(,{"bufferView":4,"componentType":5126,"count":3,"type":"VEC2"})");
    morph.insert(morph.rfind(']', morph.find("\"accessors\"")), "," + view);
    write_text(directory + "/texcoord.gltf", morph);
    expect_clean_failure(directory + "/texcoord.gltf", "bufferView 4");
  }
}

// References bake_model follows without checking them itself (found by tests/fuzz): a skin index on a node without
// a mesh (analyze_scene checks skins only where there is a mesh), and a child index in an encoded file (decoding
// bakes without analyze_scene).
TEST(Cli, BadNodeReferencesFailCleanly) {
  const std::string directory = output_directory("references");
  std::string morph = simple_morph_in(directory);
  morph.insert(morph.find('}', morph.find("\"mesh\":0")) + 1, R"(,{"skin":99})");  // a second node
  write_text(directory + "/skin.gltf", morph);
  expect_clean_failure(directory + "/skin.gltf", "skin that does not exist");

  ASSERT_EQ(run("encode -q " + sample("AnimatedMorphCube/AnimatedMorphCube.glb") + " -o " + directory + "/cube.gltf")
                .exit_code,
            0);
  std::string cube = read_text(directory + "/cube.gltf");
  cube.insert(cube.find("\"mesh\": 0"), R"("children": [99], )");
  write_text(directory + "/cube.gltf", cube);
  expect_clean_failure(directory + "/cube.gltf", "child that does not exist", "decode");
}

// An encoded file whose Draco attribute map gives TANGENT the normals (three components) or NORMAL the tangents
// (four): decoding baked them unchecked and read past the end (found by tests/fuzz).
TEST(Cli, DecodedNormalsOrTangentsOfTheWrongShapeFailCleanly) {
  const std::string directory = output_directory("shapes");
  ASSERT_EQ(run("encode -q " + sample("AnimatedMorphCube/AnimatedMorphCube.glb") + " -o " + directory + "/cube.gltf")
                .exit_code,
            0);
  const std::string cube = read_text(directory + "/cube.gltf");
  ASSERT_NE(cube.find("\"NORMAL\": 1,"), std::string::npos);
  ASSERT_NE(cube.find("\"TANGENT\": 2"), std::string::npos);
  std::string tangent = cube, normal = cube;
  tangent.replace(tangent.find("\"TANGENT\": 2"), 12, "\"TANGENT\": 1");
  normal.replace(normal.find("\"NORMAL\": 1,"), 12, "\"NORMAL\": 2,");
  write_text(directory + "/tangent.gltf", tangent);
  write_text(directory + "/normal.gltf", normal);
  expect_clean_failure(directory + "/tangent.gltf", "TANGENT must be VEC4", "decode");
  expect_clean_failure(directory + "/normal.gltf", "NORMAL must be VEC3", "decode");
}

TEST(Cli, CorruptedInputsFailCleanlyOrBake) {
  // Random byte changes and truncations of small samples: every run either bakes or fails with exit 1 and one
  // line, and never leaves output behind on failure. (Crashes and memory errors show under the sanitizer build.)
  std::mt19937 random(2024);
  const std::string directory = output_directory("corrupt");
  for (const char* name : {"AnimatedMorphCube/AnimatedMorphCube.glb", "SimpleSkin/SimpleSkin.gltf"}) {
    const std::string original = read_text(sample(name));
    const std::string extension = fs::path(name).extension().string();
    for (int trial = 0; trial < 60; ++trial) {
      std::string bytes = original;
      const int changes = 1 + int(random() % 8);
      for (int c = 0; c < changes; ++c) bytes[random() % bytes.size()] = char(random() % 256);
      if (trial % 5 == 0) bytes.resize(random() % bytes.size());
      const std::string input = directory + "/input" + extension, output = directory + "/out.glb";
      write_text(input, bytes);
      fs::remove(output);
      const Result result = run("bake -q " + input + " -o " + output);
      SCOPED_TRACE(std::string(name) + " trial " + std::to_string(trial));
      ASSERT_TRUE(result.exit_code == 0 || result.exit_code == 1) << result.exit_code << " " << result.err;
      if (result.exit_code == 1) {
        EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
        EXPECT_FALSE(fs::exists(output));
      }
    }
  }
}

TEST(Cli, BakeWritesGlbAndGltfAndNothingElse) {
  const std::string directory = output_directory("bake");
  Result result = run("bake " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.glb");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("sampling"), std::string::npos) << "progress goes to stderr";
  result = run("bake -q " + sample("SimpleMorph/SimpleMorph.gltf") + " -o " + directory + "/morph.gltf");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.err.empty());
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"fox.glb", "morph.bin", "morph.gltf"}));
  EXPECT_NE(read_text(directory + "/morph.gltf").find("\"uri\": \"morph.bin\""), std::string::npos);
}

// KHR_draco_mesh_compression gives a compressed primitive an indices accessor without a bufferView, as
// segmorph writes and other tools do; tinygltf 2.7 refuses it, so segmorph rewrites the JSON before parsing
// (json_prepass.h). Both .gltf and .glb.
TEST(Cli, DracoIndicesWithoutBufferViewAreRead) {
  const std::string directory = output_directory("draco_indices");
  const std::string input = sample("AnimatedMorphCube/AnimatedMorphCube.glb");
  for (const char* extension : {"gltf", "glb"}) {
    const std::string encoded = directory + "/cube." + extension;
    ASSERT_EQ(run("encode -q " + input + " -o " + encoded).exit_code, 0);
    const std::string text = read_text(encoded);
    const size_t primitive = text.find("\"KHR_draco_mesh_compression\"", text.find("\"meshes\""));
    ASSERT_NE(primitive, std::string::npos);
    EXPECT_NE(text.find("\"indices\"", primitive), std::string::npos) << extension;
    const Result result = run("verify -q " + input + " " + encoded + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(json_number(result.out, "vertices"), 24);
    EXPECT_LE(json_number(result.out, "kg_percent"), 0.15);
    ASSERT_EQ(run("decode -q " + encoded + " -o " + directory + "/decoded.glb").exit_code, 0);
  }
}

// Two clips of a compressed primitive naming one animation would make decode write an invalid file.
TEST(Cli, ClipsNamingOneAnimationTwiceAreRefused) {
  const std::string directory = output_directory("clips_twice");
  ASSERT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.gltf --error 1 --skins bake").exit_code, 0);
  std::string json = read_text(directory + "/fox.gltf");
  const size_t second = json.find("\"animation\": 1,", json.find("SEGMORPH_animation_compression\": {"));
  ASSERT_NE(second, std::string::npos);
  json.replace(second, 15, "\"animation\": 0,");
  write_text(directory + "/fox.gltf", json);
  expect_clean_failure(directory + "/fox.gltf", "two clips name the same animation", "decode");
}
