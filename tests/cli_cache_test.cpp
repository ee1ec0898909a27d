// Vertex caches on the command line (tests/vertex_cache_test.cpp reads them through the library).
#include <gtest/gtest.h>

#include <cstring>

#include "cli_run.h"

using namespace cli_testing;

TEST(Cli, VertexCachesEncodeAndVerify) {
  const std::string directory = output_directory("caches");
  for (const std::string& input : {flag("flag.obj") + " --cache " + flag("flag.pc2"), flag("obj_sequence"),
                                   "'" + flag("obj_sequence/flag_%04d.obj") + "'"}) {
    SCOPED_TRACE(input);
    const Result encoded = run("encode -q " + input + " --fps 24 --z-up -o " + directory + "/flag.glb --json");
    ASSERT_EQ(encoded.exit_code, 0) << encoded.err;
    EXPECT_LE(json_number(encoded.out, "kg_percent"), 0.15 * 1.05) << encoded.out;
    // Blender wrote the glTF, the PC2 and the sequence at the same times: verify compares them as they are.
    const Result verified = run("verify -q " + flag("flag.glb") + " " + directory + "/flag.glb --max-error 0.16");
    EXPECT_EQ(verified.exit_code, 0) << verified.out << verified.err;
    const Result against_cache = run("verify -q " + flag("flag.glb") + " " + input.substr(0, input.find(" --cache")) +
                                     (input.find("--cache") != std::string::npos ? " --cache2 " + flag("flag.pc2") : "") +
                                     " --fps 24 --z-up --max-error 0.0001");
    EXPECT_EQ(against_cache.exit_code, 0) << against_cache.out << against_cache.err;
  }
  // Without --z-up the caches lie on their back.
  const Result lying = run("verify -q " + flag("flag.glb") + " " + flag("flag.obj") + " --cache2 " + flag("flag.pc2") +
                           " --fps 24 --max-error 1");
  EXPECT_EQ(lying.exit_code, 1) << lying.out;
  // bake writes the cache as standard morph targets; info lists it.
  EXPECT_EQ(run("bake -q " + flag("flag.obj") + " --cache " + flag("flag.mdd") + " --z-up -o " + directory +
                "/baked.glb").exit_code,
            0);
  const Result info = run("info -q " + directory + "/baked.glb");
  EXPECT_NE(info.out.find("clip 0 \"flag\": 24 frames, 0.958 s"), std::string::npos) << info.out;
}

TEST(Cli, BadVertexCachesFailCleanly) {
  const std::string directory = output_directory("bad_caches");
  const std::string obj = flag("flag.obj");
  const std::string pc2 = read_text(flag("flag.pc2"));
  auto cache = [&](const std::string& name, const std::string& bytes) {
    write_text(directory + "/" + name, bytes);
    return " --cache " + directory + "/" + name;
  };
  std::string other_count = pc2;
  other_count[16] = char(116);  // 116 points: the file's size no longer fits either
  expect_clean_failure(obj, "other_count.pc2: PC2 cache of 24 frames of 116 points is", "encode",
                       cache("other_count.pc2", other_count));
  std::string fewer_points = pc2.substr(0, 32 + 24 * 116 * 12);
  fewer_points[16] = char(116);
  expect_clean_failure(obj, "fewer_points.pc2 moves 116 points, the base mesh", "encode",
                       cache("fewer_points.pc2", fewer_points));
  expect_clean_failure(obj, "truncated.pc2: PC2 cache of 24 frames of 117 points is 33728 bytes, the file 33727 "
                            "(truncated)", "encode", cache("truncated.pc2", pc2.substr(0, pc2.size() - 1)));
  std::string absurd = pc2;
  absurd[31] = char(0x7f);  // samples: 2 130 706 456
  expect_clean_failure(obj, "absurd.pc2: PC2 header claims 117 points and", "encode", cache("absurd.pc2", absurd));
  std::string infinite = pc2;
  const uint32_t infinity = 0x7f800000;
  std::memcpy(&infinite[32 + (3 * 117 + 5) * 12], &infinity, 4);
  expect_clean_failure(obj, "infinite.pc2: frame 3, point 5: not a finite position", "bake",
                       cache("infinite.pc2", infinite));
  expect_clean_failure(obj, "missing.pc2: cannot open", "encode", " --cache " + directory + "/missing.pc2");
  expect_clean_failure(flag("flag.pc2"), "a point cache moves a base mesh", "encode");
  expect_clean_failure(obj, "an .obj alone is one frame", "encode");

  // OBJ sequences: a frame with other faces or another vertex count, a missing frame, an index out of range, an
  // empty OBJ.
  const std::string sequence = output_directory("bad_sequence");
  for (int f = 1; f <= 24; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "/flag_%04d.obj", f);
    fs::copy_file(flag("obj_sequence") + name, sequence + name);
  }
  std::string frame = read_text(sequence + "/flag_0007.obj");
  write_text(sequence + "/flag_0007.obj", frame + "f 1/1/1 3/3/1 2/2/1\n");
  expect_clean_failure(sequence, ": more faces than the first frame's 96", "encode");
  std::string changed = frame;
  const size_t face = changed.find("\nf ") + 1;
  changed.replace(face, changed.find('\n', face) - face, "f 1 2 3 4");
  const std::string line = std::to_string(std::count(changed.begin(), changed.begin() + long(face), '\n') + 1);
  write_text(sequence + "/flag_0007.obj", changed);
  expect_clean_failure(sequence, "flag_0007.obj line " + line + ": face 1 differs from the first frame's", "encode");
  write_text(sequence + "/flag_0007.obj", frame + "v 0 0 0\n");
  expect_clean_failure(sequence, "flag_0007.obj: 118 vertices, the first frame 117", "encode");
  write_text(sequence + "/flag_0007.obj", frame);
  const std::string first = read_text(sequence + "/flag_0001.obj");
  write_text(sequence + "/flag_0001.obj", first + "f 1 2 118\n");
  expect_clean_failure(sequence, "flag_0001.obj: a face index is out of range (117 vertices", "encode");
  write_text(sequence + "/flag_0001.obj", "");
  expect_clean_failure(sequence, "flag_0001.obj: no faces", "encode");
  write_text(sequence + "/flag_0001.obj", first);
  fs::remove(sequence + "/flag_0012.obj");
  expect_clean_failure(sequence, "frame 12 is missing", "bake");
  expect_clean_failure(sequence + "/flag_%04d.obj", "frame 12 is missing", "encode");
}
