// Vertex caches in: the OBJ reader against hand-made files, OBJ sequences (order, patterns, bad frames), PC2 and MDD
// caches on OBJ and glTF base meshes (frame times, the points' vertices, axes), and the Blender-written WavingFlag
// sample: each of its caches reads to the frames of its glTF and encodes to files that agree within the target.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "cache_files.h"
#include "caches/obj_reader.h"
#include "encode/metrics.h"
#include "gltf/save.h"
#include "gltf_builder.h"
#include "pipeline.h"
#include "test_files.h"

namespace segmorph {
namespace {

namespace fs = std::filesystem;
using testing::coordinate;
using testing::temporary_path;
using testing::written;

// A fresh folder for a test's files.
std::string folder(const std::string& name) {
  const std::string path = temporary_path(name);
  fs::remove_all(path);
  fs::create_directories(path);
  return path;
}

void write(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The frames `model` samples to with `sampling`: its one animated primitive, its one clip.
FrameSequence frames_of(const Model& model, const SampleSettings& sampling, size_t primitive = 0) {
  SampledFile file;
  const Status status = analyze_model(model.data().gltf, sampling, true, {}, file);
  EXPECT_TRUE(status.ok()) << status.message();
  if (!status.ok() || file.sampled.empty()) return FrameSequence();
  return file.sampled[0].primitives[primitive].clips[0];
}

// --- the OBJ reader ---

TEST(ObjReader, QuadsBecomeFansAndCornersBecomeVertices) {
  // A quad and a triangle sharing the edge 2-3; point 2 has two texture coordinates (a seam), so it is two vertices.
  // The triangle uses relative indices. Comments, groups, smoothing and a vertex colour are skipped.
  const std::string path = written("mesh.obj",
                                   "# made by hand\n"
                                   "o Quad\n"
                                   "v 0 0 0\nv 1 0 0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\nv 2 1 0\n"
                                   "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.25\n"
                                   "vn 0 0 1\n"
                                   "g side\ns 1\nusemtl red\n"
                                   "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
                                   "f -4/-1/-1 -1/-3/-1 -3/-3/-1\n");
  ObjMesh mesh;
  const Status status = read_obj(path, mesh);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(mesh.points.size(), 15u);
  EXPECT_EQ(mesh.points[8], 0.0f);  // the colour after v 1 1 0 is not a coordinate
  // Corners in order: 1/1, 2/2, 3/3, 4/4, then 2/5 (new: point 2 with another vt), 5/3 (new), 3/3 (the third).
  EXPECT_EQ(mesh.vertex_point, (std::vector<uint32_t>{0, 1, 2, 3, 1, 4}));
  EXPECT_EQ(mesh.triangles, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 4, 5, 2}));
  ASSERT_EQ(mesh.texcoords.size(), 12u);
  EXPECT_EQ(mesh.texcoords[9], 1.0f - 0.25f);  // vertex 4's v, flipped for glTF
  ASSERT_EQ(mesh.normals.size(), 18u);
  EXPECT_EQ(mesh.normals[17], 1.0f);
  EXPECT_EQ(mesh.face_sizes, (std::vector<uint32_t>{4, 3}));
  EXPECT_EQ(mesh.face_points, (std::vector<uint32_t>{0, 1, 2, 3, 1, 4, 2}));
}

TEST(ObjReader, AttributesMissingOnSomeCornersAreLeftOut) {
  const std::string path = written("mixed.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3/1\n");
  ObjMesh mesh;
  ASSERT_TRUE(read_obj(path, mesh).ok());
  EXPECT_EQ(mesh.vertex_count(), 3u);
  EXPECT_TRUE(mesh.texcoords.empty());
  EXPECT_TRUE(mesh.normals.empty());
}

TEST(ObjReader, BadFilesAreRefusedNamingFileAndLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"v 1 2\n", "line 1: expected 3 finite numbers"},
      {"v 0 0 0\nv 1 nan 0\n", "line 2: expected 3 finite numbers"},
      {"v 0 0 0\nv 1 1e39 0\n", "line 2: expected 3 finite numbers"},
      {"v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: a face has fewer than 3 corners"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "a face index is out of range (3 vertices"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2 3\n", "a face index is out of range"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: a face has a bad vertex index"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", "line 4: a face's relative vertex index -4 is before the first"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1x 2 3\n", "line 4: a face corner is not v, v/vt, v//vn or v/vt/vn"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"},
      {"", "no faces"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string path = written("bad" + std::to_string(i) + ".obj", cases[i].first);
    ObjMesh mesh;
    const Status status = read_obj(path, mesh);
    EXPECT_EQ(status.code(), StatusCode::bad_data) << cases[i].first;
    EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
    EXPECT_NE(status.message().find(cases[i].second), std::string::npos) << status.message();
  }
  ObjMesh mesh;
  EXPECT_EQ(read_obj(temporary_path("missing.obj"), mesh).code(), StatusCode::io_error);
}

TEST(ObjReader, LaterFramesMustHaveTheFirstOnesFaces) {
  const std::string first_path = written("f1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n");
  ObjMesh first;
  ASSERT_TRUE(read_obj(first_path, first).ok());
  std::vector<float> points;
  // Relative indices naming the same points, and other texture coordinates, are the same faces.
  ASSERT_TRUE(
      read_obj_frame(written("f2.obj", "v 0 0 1\nv 1 0 1\nv 0 1 1\nvt 0 0\nf 1/1 2/1 3/1\nv 1 1 1\nf -3 -1 -2\n"),
                     first, points)
          .ok());
  EXPECT_EQ(points, (std::vector<float>{0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1}));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 3 4\n", "line 6: face 2 differs from the first frame's"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3 1\n", "face 2 differs from the first frame's"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n", "1 faces, the first frame 2"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 2\nf 1 2 3\nf 2 4 3\n", "5 vertices, the first frame 4"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string path = written("frame" + std::to_string(i) + ".obj", cases[i].first);
    const Status status = read_obj_frame(path, first, points);
    EXPECT_EQ(status.code(), StatusCode::bad_data);
    EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
    EXPECT_NE(status.message().find(cases[i].second), std::string::npos) << status.message();
  }
}

// --- OBJ sequences ---

// A triangle moved to x = offset.
std::string triangle_at(float offset) {
  const std::string x = std::to_string(offset), x1 = std::to_string(offset + 1);
  return "v " + x + " 0 0\nv " + x1 + " 0 0\nv " + x + " 1 0\nf 1 2 3\n";
}

TEST(VertexCache, ObjSequenceFramesFollowTheNumbersInTheirNames) {
  const std::string directory = folder("sequence");
  // frame_10 after frame_9 (not after frame_1), whatever the listing order; other files are ignored.
  for (int n = 1; n <= 11; ++n) write(directory + "/frame_" + std::to_string(n) + ".obj", triangle_at(float(n)));
  write(directory + "/notes.txt", "not a frame");
  for (const std::string& mesh : {directory, directory + "/frame_%d.obj"}) {
    SCOPED_TRACE(mesh);
    CacheSource source;
    source.mesh = mesh;
    source.fps = 10;
    Model model;
    CacheReport report;
    const Status status = Model::load_cache(source, model, &report);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(report.format, "OBJ sequence");
    EXPECT_EQ(report.frames, 11u);
    EXPECT_EQ(report.points, 3u);
    EXPECT_FLOAT_EQ(report.first_time, 0.1f);  // frame 1 at 1/10 s
    EXPECT_FLOAT_EQ(report.last_time, 1.1f);
    const FrameSequence frames = frames_of(model, report.sampling);
    ASSERT_EQ(frames.frame_count, 11u);
    for (size_t f = 0; f < 11; ++f) EXPECT_EQ(frames.frame(f)[0], float(f + 1)) << f;
  }
}

TEST(VertexCache, ZeroPaddedPatternsMatchOnlyTheirOwnNames) {
  const std::string directory = folder("padded");
  for (int n = 0; n < 3; ++n) write(directory + "/walk_000" + std::to_string(n) + ".obj", triangle_at(float(n)));
  write(directory + "/walk_5.obj", triangle_at(5));  // not what %04d writes
  write(directory + "/run_0003.obj", triangle_at(5));
  CacheSource source;
  source.mesh = directory + "/walk_%04d.obj";
  Model model;
  CacheReport report;
  ASSERT_TRUE(Model::load_cache(source, model, &report).ok());
  EXPECT_EQ(report.frames, 3u);
  EXPECT_EQ(report.first_time, 0.0f);
  EXPECT_EQ(model.data().gltf.animations[0].name, "walk");
}

TEST(VertexCache, BadSequencesAreRefusedNamingTheFrame) {
  struct Case {
    std::vector<std::pair<std::string, std::string>> files;
    std::string mesh, message;
  };
  const std::vector<Case> cases = {
      {{{"a_1.obj", triangle_at(1)}, {"a_2.obj", triangle_at(2)}, {"a_4.obj", triangle_at(4)}},
       "",
       "frame 3 is missing: the sequence goes from"},
      {{{"a_1.obj", triangle_at(1)}, {"b_1.obj", triangle_at(2)}}, "", "are both frame 1"},
      {{{"a.obj", triangle_at(1)}}, "", "has no frame number in its name"},
      {{{"a_1.obj", triangle_at(1)}}, "b_%d.obj", "no file matches the pattern"},
      {{{"a_1.obj", triangle_at(1)}}, "a_%d_%d.obj", "one %d"},
      {{}, "", "no .obj files in the folder"},
      {{{"a_1.obj", triangle_at(1)}, {"a_2.obj", triangle_at(2) + "v 0 0 0\n"}}, "", "a_2.obj: 4 vertices"},
      {{{"a_1.obj", triangle_at(1)}, {"a_2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 2\n"}},
       "",
       "a_2.obj line 4: face 1 differs"},
      {{{"a_1.obj", triangle_at(1)}, {"a_2.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n"}},
       "",
       "a_2.obj line 2: expected 3 finite numbers"},
      {{{"a_1.obj", "v 0 0 0\n"}, {"a_2.obj", triangle_at(2)}}, "", "a_1.obj: no faces"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string directory = folder("bad" + std::to_string(i));
    for (const auto& file : cases[i].files) write(directory + "/" + file.first, file.second);
    CacheSource source;
    source.mesh = cases[i].mesh.empty() ? directory : directory + "/" + cases[i].mesh;
    Model model;
    const Status status = Model::load_cache(source, model);
    EXPECT_FALSE(status.ok()) << i;
    EXPECT_NE(status.message().find(cases[i].message), std::string::npos) << i << ": " << status.message();
  }
}

// --- point caches on a base mesh ---

// A base mesh of `points` points, a fan of triangles, with a texture seam at point 2 (two vertices) when `seam`.
std::string fan_obj(size_t points, bool seam) {
  std::string text;
  for (size_t p = 0; p < points; ++p) text += "v " + std::to_string(p) + " " + std::to_string(p % 2) + " 0\n";
  text += "vt 0 0\nvt 1 1\n";
  for (size_t p = 1; p + 1 < points; ++p)
    text +=
        "f 1/1 " + std::to_string(p + 1) + "/" + (seam && p == 2 ? "1" : "2") + " " + std::to_string(p + 2) + "/2\n";
  return text;
}

// The OBJ `obj` and the cache `cache` (bytes) written to files and read by Model::load_cache.
Status load_written(const std::string& obj, const std::string& cache_name, const std::string& cache, double fps,
                    bool z_up, Model& model, CacheReport& report) {
  CacheSource source;
  source.mesh = written("base.obj", obj);
  source.cache = written(cache_name, cache);
  source.fps = fps;
  source.z_up = z_up;
  return Model::load_cache(source, model, &report);
}

TEST(VertexCache, Pc2OnAnObjMovesEachVertexWithItsPoint) {
  Model model;
  CacheReport report;
  const Status status = load_written(fan_obj(5, true), "anim.pc2", testing::pc2(5, 4, 10, 2), 20, false, model, report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(report.format, "PC2");
  EXPECT_EQ(report.points, 5u);
  EXPECT_EQ(report.vertices, 6u);  // point 2 is two vertices
  EXPECT_EQ(report.frames, 4u);
  EXPECT_FLOAT_EQ(report.first_time, 0.5f);  // frame 10 at 20 fps
  EXPECT_FLOAT_EQ(report.last_time, 0.8f);   // frame 16
  EXPECT_EQ(report.sampling.fps, 0);         // 10 frames per second: at the keys
  const FrameSequence frames = frames_of(model, report.sampling);
  ASSERT_EQ(frames.frame_count, 4u);
  ASSERT_EQ(frames.vertex_count, 6u);
  const std::vector<size_t> point_of = {0, 1, 2, 2, 3, 4};  // corners in order of first use
  for (size_t f = 0; f < 4; ++f) {
    EXPECT_FLOAT_EQ(frames.times[f], float((10 + 2 * f) / 20.0));
    for (size_t v = 0; v < 6; ++v)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(frames.frame(f)[v * 3 + size_t(c)], coordinate(f, point_of[v], c));
  }
  // The glTF keeps the OBJ's texture coordinates and triangles.
  const tinygltf::Primitive& primitive = model.data().gltf.meshes[0].primitives[0];
  EXPECT_EQ(primitive.attributes.count("TEXCOORD_0"), 1u);
  EXPECT_EQ(model.data().gltf.accessors[size_t(primitive.indices)].count, 9u);
}

TEST(VertexCache, MddKeepsItsTimesAndZUpTurnsToYUp) {
  Model model;
  CacheReport report;
  // The frame rate is not used: MDD has times.
  ASSERT_TRUE(
      load_written(fan_obj(4, false), "anim.mdd", testing::mdd(3, 4, {0, 0.25f, 1}), 1000, true, model, report).ok());
  EXPECT_EQ(report.format, "MDD");
  const FrameSequence frames = frames_of(model, report.sampling);
  ASSERT_EQ(frames.times, (std::vector<float>{0, 0.25f, 1}));
  for (size_t f = 0; f < 3; ++f)
    for (size_t v = 0; v < 4; ++v) {
      EXPECT_EQ(frames.frame(f)[v * 3 + 0], coordinate(f, v, 0));
      EXPECT_EQ(frames.frame(f)[v * 3 + 1], coordinate(f, v, 2));   // y = z
      EXPECT_EQ(frames.frame(f)[v * 3 + 2], -coordinate(f, v, 1));  // z = -y
    }
}

TEST(VertexCache, CachesFasterThanSixtyFramesPerSecondKeepEveryFrame) {
  Model model;
  CacheReport report;
  ASSERT_TRUE(load_written(fan_obj(4, false), "fast.pc2", testing::pc2(4, 30, 1, 1), 120, false, model, report).ok());
  EXPECT_EQ(report.sampling.fps, 120);
  const FrameSequence frames = frames_of(model, report.sampling);
  ASSERT_EQ(frames.frame_count, 30u);
  for (size_t f = 0; f < 30; ++f) EXPECT_EQ(frames.frame(f)[0], coordinate(f, 0, 0)) << f;
}

TEST(VertexCache, GltfBaseMeshTakesPointsPrimitiveAfterPrimitive) {
  test::GltfBuilder gltf;
  const int first = gltf.add_mesh(gltf.add_vec3({0, 0, 0, 1, 0, 0, 0, 1, 0}));
  const int second_position = gltf.add_vec3({0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1});
  tinygltf::Primitive second = gltf.primitive(first);
  second.attributes["POSITION"] = second_position;
  second.indices = gltf.add_uints({0, 1, 2, 1, 3, 2}, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  gltf.model.meshes[0].primitives.push_back(second);
  gltf.add_root(gltf.add_node());
  gltf.add_root(gltf.add_mesh_node(first));  // node 1: the mesh is not on the first node
  gltf.model.asset.version = "2.0";
  const std::string base = temporary_path("base.glb");
  ASSERT_TRUE(save_gltf(gltf.model, base).ok());
  CacheSource source;
  source.mesh = base;
  source.cache = written("anim.pc2", testing::pc2(7, 3, 0, 1));
  Model model;
  CacheReport report;
  const Status status = Model::load_cache(source, model, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(report.vertices, 7u);
  SampledFile file;
  ASSERT_TRUE(analyze_model(model.data().gltf, report.sampling, true, {}, file).ok());
  ASSERT_EQ(file.sampled.size(), 1u);
  EXPECT_EQ(file.sampled[0].node->node, 1);
  ASSERT_EQ(file.sampled[0].primitives.size(), 2u);
  for (size_t p = 0; p < 2; ++p)
    for (size_t f = 0; f < 3; ++f) {
      const FrameSequence& frames = file.sampled[0].primitives[p].clips[0];
      for (size_t v = 0; v < frames.vertex_count; ++v)
        EXPECT_EQ(frames.frame(f)[v * 3], coordinate(f, (p == 0 ? 0 : 3) + v, 0)) << p << " " << f << " " << v;
    }
}

TEST(VertexCache, BadCachesAreRefusedNamingTheFile) {
  const std::string obj = written("base.obj", fan_obj(5, false));
  std::string not_finite = testing::pc2(5, 3, 0, 1);
  const float nan = std::nanf("");
  std::memcpy(&not_finite[32 + ((5 + 2) * 3 + 1) * 4], &nan, 4);  // frame 1, point 2, y
  std::string truncated = testing::pc2(5, 3, 0, 1);
  truncated.resize(truncated.size() - 1);
  std::string absurd = testing::pc2(5, 3, 0, 1);
  absurd[28] = char(0xff), absurd[29] = char(0xff), absurd[30] = char(0xff);  // samples: 16 777 215
  const std::vector<std::pair<std::string, std::string>> cases = {
      {written("four.pc2", testing::pc2(4, 3, 0, 1)), "moves 4 points, the base mesh"},
      {written("nan.pc2", not_finite), "nan.pc2: frame 1, point 2: not a finite position"},
      {written("short.pc2", truncated), "short.pc2: PC2 cache of 3 frames of 5 points is 212 bytes, the file 211"},
      {written("absurd.pc2", absurd), "absurd.pc2: PC2 cache of 16777215 frames"},
      {written("empty.mdd", ""), "empty.mdd: neither a PC2 nor an MDD cache"},
      {temporary_path("missing.pc2"), "missing.pc2: cannot open"},
  };
  for (const auto& [cache, message] : cases) {
    CacheSource source;
    source.mesh = obj;
    source.cache = cache;
    Model model;
    const Status status = Model::load_cache(source, model);
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find(message), std::string::npos) << status.message();
  }
  // A base mesh with targets, or several meshes, is not a base mesh.
  CacheSource source;
  source.mesh = std::string(SEGMORPH_SAMPLES_DIR) + "/AnimatedMorphCube/AnimatedMorphCube.glb";
  source.cache = written("cube.pc2", testing::pc2(24, 3, 0, 1));
  Model model;
  const Status status = Model::load_cache(source, model);
  EXPECT_NE(status.message().find("has morph targets; a base mesh for a cache has none"), std::string::npos)
      << status.message();
}

// --- caches written by Blender (samples/WavingFlag: one animation as glTF, OBJ sequence, PC2 and MDD) ---

std::string flag(const std::string& file) {
  return std::string(SEGMORPH_SAMPLES_DIR) + "/WavingFlag/" + file;
}

Model load_flag(const std::string& mesh, const std::string& cache, CacheReport& report) {
  CacheSource source;
  source.mesh = flag(mesh);
  source.cache = cache.empty() ? "" : flag(cache);
  source.fps = 24;
  source.z_up = true;  // Blender's axes, as the MDD exporter writes
  Model model;
  const Status status = Model::load_cache(source, model, &report);
  EXPECT_TRUE(status.ok()) << status.message();
  return model;
}

// The largest distance between frame f of `a` and of `b`, vertex by vertex (same vertex order).
double largest_distance(const FrameSequence& a, const FrameSequence& b) {
  EXPECT_EQ(a.frame_count, b.frame_count);
  EXPECT_EQ(a.vertex_count, b.vertex_count);
  double largest = 0;
  for (size_t i = 0; i < std::min(a.positions.size(), b.positions.size()); i += 3)
    largest = std::max(
        largest, std::hypot(double(a.positions[i]) - b.positions[i], double(a.positions[i + 1]) - b.positions[i + 1],
                            double(a.positions[i + 2]) - b.positions[i + 2]));
  return largest;
}

TEST(VertexCache, BlenderCachesReadToTheFramesOfTheirGltf) {
  Model gltf;
  ASSERT_TRUE(Model::load(flag("flag.glb"), gltf).ok());
  const FrameSequence reference = frames_of(gltf, SampleSettings());
  ASSERT_EQ(reference.frame_count, 24u);
  ASSERT_EQ(reference.vertex_count, 117u);
  // Blender's glTF keeps its vertex order here (no seams, smooth shading), as the caches do: a vertex by vertex
  // comparison. The OBJ files hold 6 decimals (the flag is 2.4 wide).
  const struct {
    const char *mesh, *cache;
    double tolerance;
  } caches[] = {{"flag.obj", "flag.pc2", 1e-6}, {"flag.obj", "flag.mdd", 1e-6}, {"obj_sequence", "", 1e-6}};
  for (const auto& cache : caches) {
    SCOPED_TRACE(std::string(cache.mesh) + " " + cache.cache);
    CacheReport report;
    const Model model = load_flag(cache.mesh, cache.cache, report);
    EXPECT_EQ(report.frames, 24u);
    EXPECT_EQ(report.points, 117u);
    FrameSequence frames = frames_of(model, report.sampling);
    ASSERT_EQ(frames.vertex_count, 117u);
    // The OBJ's corners come in face order: put the vertices back in point order to compare.
    ObjMesh obj;
    ASSERT_TRUE(read_obj(flag("flag.obj"), obj).ok());
    FrameSequence ordered = frames;
    for (size_t f = 0; f < frames.frame_count; ++f)
      for (size_t v = 0; v < 117; ++v)
        for (size_t c = 0; c < 3; ++c) ordered.frame(f)[obj.vertex_point[v] * 3 + c] = frames.frame(f)[v * 3 + c];
    EXPECT_LT(largest_distance(ordered, reference), cache.tolerance);
    // Blender writes the glTF's, the PC2's and the sequence's frame k at k / 24 s, and the MDD's at (k - 1) / 24 s.
    const float offset = std::string(cache.cache) == "flag.mdd" ? 1.0f / 24 : 0.0f;
    for (size_t f = 0; f < 24; ++f) EXPECT_NEAR(frames.times[f] + offset, reference.times[f], 1e-6) << f;
  }
}

TEST(VertexCache, BlenderCachesEncodeToFilesThatAgree) {
  Model gltf;
  ASSERT_TRUE(Model::load(flag("flag.glb"), gltf).ok());
  EncodeSettings settings;  // --error 0.15
  std::vector<Model> encoded;
  for (const auto& [mesh, cache] : std::vector<std::pair<std::string, std::string>>{
           {"flag.obj", "flag.pc2"}, {"obj_sequence", ""}, {"flag.obj", "flag.mdd"}}) {
    SCOPED_TRACE(mesh + " " + cache);
    CacheReport report;
    const Model model = load_flag(mesh, cache, report);
    settings.sampling = report.sampling;
    Model output;
    EncodeReport encode_report;
    const Status status = encode(model, settings, output, &encode_report);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_LE(encode_report.kg_percent, 0.15 * 1.05);
    // Against the glTF of the animation: the MDD's frames play 1/24 s earlier, so it is compared with its own cache.
    VerifyReport verified;
    ASSERT_TRUE(verify(cache == "flag.mdd" ? model : gltf, output, SampleSettings(), verified).ok());
    EXPECT_LE(verified.kg_percent, 0.15 * 1.05);
    EXPECT_EQ(verified.frames, 24u);
    encoded.push_back(std::move(output));
  }
  // Decoded, the three files play the same frames within the target (frame by frame for the MDD's).
  std::vector<FrameSequence> decoded;
  for (Model& model : encoded) {
    ASSERT_TRUE(decode(model).ok());
    decoded.push_back(frames_of(model, SampleSettings()));
  }
  // Each is within 0.15 % of the same frames, so within twice that of each other.
  VerifyReport pc2_sequence;
  ASSERT_TRUE(verify(encoded[0], encoded[1], SampleSettings(), pc2_sequence).ok());
  EXPECT_LE(pc2_sequence.kg_percent, 2 * 0.15);
  ErrorAccumulator pc2_mdd;
  pc2_mdd.add(decoded[0], decoded[2]);
  EXPECT_LE(pc2_mdd.result().kg_percent, 2 * 0.15);
}

}  // namespace
}  // namespace segmorph
