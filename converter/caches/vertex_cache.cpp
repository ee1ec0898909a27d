// Vertex caches in (Model::load_cache, include/segmorph/segmorph.h; docs/caches.md): an OBJ sequence, or a PC2 or
// MDD point cache on an OBJ or glTF base mesh, read frame by frame into the glTF bake writes for an animated mesh.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "accessor.h"
#include "bake/bake.h"
#include "caches/obj_reader.h"
#include "caches/point_cache.h"
#include "file_names.h"
#include "gltf/load.h"
#include "gltf/packing.h"
#include "pipeline.h"

namespace segmorph {
namespace {

namespace fs = std::filesystem;

Status bad(const std::string& message) {
  return Status(StatusCode::bad_data, message);
}

std::string stem_of(const std::string& path) {
  std::string stem = fs::path(path).filename().string();
  if (stem.empty()) stem = fs::path(path).parent_path().filename().string();  // "frames/"
  const size_t dot = stem.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? stem : stem.substr(0, dot);
}

// --- OBJ sequences: which files, in which order ---

// A sequence's name: its folder's, or its pattern's file name without the number and extension (walk_%04d.obj: walk).
std::string sequence_name(const std::string& source) {
  std::string name = stem_of(source);
  const size_t percent = name.find('%');
  if (percent == std::string::npos) return name;
  size_t end = percent + 1;
  while (end < name.size() && std::isdigit((unsigned char)name[end])) ++end;
  name.erase(percent, end + 1 - percent);
  while (!name.empty() && (name.back() == '_' || name.back() == '.' || name.back() == '-')) name.pop_back();
  return name.empty() ? "sequence" : name;
}

struct SequenceFile {
  long number = 0;
  std::string path;
};

// The frame number in a file name: its last run of digits (walk_0012.obj: 12), or -1 when it has none.
long frame_number(const std::string& name) {
  size_t end = name.size();
  while (end > 0 && !std::isdigit((unsigned char)name[end - 1])) --end;
  size_t begin = end;
  while (begin > 0 && std::isdigit((unsigned char)name[begin - 1])) --begin;
  if (begin == end || end - begin > 9) return -1;
  return std::stol(name.substr(begin, end - begin));
}

// A printf pattern's one conversion: %d, %Nd or %0Nd ("%%" is a percent sign). False when it has none or several.
bool pattern_conversion(const std::string& pattern, size_t& begin, size_t& end) {
  int conversions = 0;
  for (size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') continue;
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      ++i;
      continue;
    }
    size_t j = i + 1;
    while (j < pattern.size() && std::isdigit((unsigned char)pattern[j])) ++j;
    if (j == pattern.size() || pattern[j] != 'd' || j - i > 3) return false;
    begin = i, end = j + 1, ++conversions;
    i = j;
  }
  return conversions == 1;
}

std::string format_number(const std::string& pattern, long number) {
  char name[4096];
  std::snprintf(name, sizeof(name), pattern.c_str(), int(number));
  return name;
}

// The frames of an OBJ sequence given as a folder or a printf pattern, in frame order, numbers consecutive.
Status list_sequence(const std::string& source, std::vector<SequenceFile>& files) {
  std::error_code error;
  const bool folder = fs::is_directory(source, error);
  const fs::path directory = folder ? fs::path(source) : fs::path(source).parent_path();
  const std::string name_pattern = folder ? "" : fs::path(source).filename().string();
  size_t begin = 0, end = 0;
  if (!folder && !pattern_conversion(name_pattern, begin, end))
    return Status(StatusCode::invalid_argument,
                  "an OBJ sequence is a folder or a file name pattern with one %d, %4d or %04d in its name");
  fs::directory_iterator it(directory.empty() ? fs::path(".") : directory, error);
  if (error) return Status(StatusCode::io_error, "cannot list " + directory.string() + ": " + error.message());
  for (; it != fs::directory_iterator(); it.increment(error)) {
    if (error) return Status(StatusCode::io_error, "cannot list " + directory.string() + ": " + error.message());
    const std::string name = it->path().filename().string();
    if (folder) {
      if (!has_suffix(name, ".obj") || !it->is_regular_file(error)) continue;
      const long number = frame_number(name.substr(0, name.size() - 4));
      if (number < 0) return bad(it->path().string() + " has no frame number in its name");
      files.push_back({number, it->path().string()});
      continue;
    }
    // A name the pattern writes for the number in its place.
    const std::string prefix = name_pattern.substr(0, begin), suffix = name_pattern.substr(end);
    if (name.size() <= prefix.size() + suffix.size()) continue;
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit((unsigned char)c); }))
      continue;
    const long number = std::stol(digits);
    if (format_number(name_pattern, number) == name) files.push_back({number, it->path().string()});
  }
  if (files.empty())
    return bad(folder ? "no .obj files in the folder (a folder input is an OBJ sequence)"
                      : "no file matches the pattern");
  std::sort(files.begin(), files.end(), [](const SequenceFile& a, const SequenceFile& b) {
    return a.number != b.number ? a.number < b.number : a.path < b.path;
  });
  for (size_t f = 1; f < files.size(); ++f) {
    if (files[f].number == files[f - 1].number)
      return bad(files[f - 1].path + " and " + files[f].path + " are both frame " + std::to_string(files[f].number));
    if (files[f].number != files[f - 1].number + 1)
      return bad("frame " + std::to_string(files[f - 1].number + 1) + " is missing: the sequence goes from " +
                 files[f - 1].path + " to " + files[f].path);
  }
  return Status::Ok();
}

// --- the base mesh ---

// What a cache's frames fill: per primitive of the base mesh, its first point in the cache and its vertices' points.
struct CacheMesh {
  int node = 0;  // the node whose mesh it is
  size_t points = 0;
  std::vector<SampledPrimitive> primitives;
  std::vector<std::vector<uint32_t>> vertex_point;  // per primitive: the cache point of each vertex
};

// Z up to glTF's Y up: (x, y, z) -> (x, z, -y), for each vector of `xyz`.
void z_up_to_y_up(std::vector<float>& xyz) {
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) {
    const float y = xyz[i + 1];
    xyz[i + 1] = xyz[i + 2];
    xyz[i + 2] = -y;
  }
}

// An OBJ's mesh as the glTF of one node: positions, normals and texture coordinates per vertex, triangles.
void add_obj_mesh(const ObjMesh& obj, const std::string& name, bool z_up, tinygltf::Model& model, CacheMesh& base) {
  AccessorWriter writer(model);
  const size_t vertex_count = obj.vertex_count();
  SampledPrimitive sampled;
  sampled.primitive = 0;
  sampled.rest_positions.resize(vertex_count * 3);
  for (size_t v = 0; v < vertex_count; ++v)
    for (size_t c = 0; c < 3; ++c) sampled.rest_positions[v * 3 + c] = obj.points[size_t(obj.vertex_point[v]) * 3 + c];
  if (z_up) z_up_to_y_up(sampled.rest_positions);
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.attributes["POSITION"] = writer.add_floats(sampled.rest_positions.data(), vertex_count, TINYGLTF_TYPE_VEC3,
                                                       true, TINYGLTF_TARGET_ARRAY_BUFFER);
  // glTF's normals are unit vectors; a file with a zero normal gets none (viewers then derive them).
  bool unit = !obj.normals.empty();
  std::vector<float> normals = obj.normals;
  if (z_up) z_up_to_y_up(normals);
  for (size_t v = 0; unit && v < vertex_count; ++v) {
    float* n = &normals[v * 3];
    const double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    unit = length > 0;
    for (int c = 0; c < 3 && unit; ++c) n[c] = float(n[c] / length);
  }
  if (unit) {
    primitive.attributes["NORMAL"] =
        writer.add_floats(normals.data(), vertex_count, TINYGLTF_TYPE_VEC3, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    sampled.rest_normals = std::move(normals);
  }
  if (!obj.texcoords.empty())
    primitive.attributes["TEXCOORD_0"] =
        writer.add_floats(obj.texcoords.data(), vertex_count, TINYGLTF_TYPE_VEC2, false, TINYGLTF_TARGET_ARRAY_BUFFER);
  primitive.indices = writer.add_indices(obj.triangles);
  sampled.clips.resize(1);
  sampled.clips[0].triangles = obj.triangles;

  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(std::move(primitive));
  model.meshes.push_back(std::move(mesh));
  tinygltf::Node node;
  node.name = name;
  node.mesh = 0;
  model.nodes.push_back(std::move(node));
  base.points = obj.points.size() / 3;
  base.vertex_point.push_back(obj.vertex_point);
  base.primitives.push_back(std::move(sampled));
}

// A glTF base mesh: the one mesh of its nodes, without morph targets or skin; its animations are dropped (the cache
// is the animation). The cache's points are its primitives' vertices, primitive after primitive.
Status read_gltf_base(const std::string& path, tinygltf::Model& model, CacheMesh& base,
                      std::vector<std::string>& warnings) {
  SEGMORPH_RETURN_IF_ERROR(load_gltf(path, model, &warnings));
  int node = -1;
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    if (model.nodes[n].mesh < 0) continue;
    if (node >= 0) return bad(path + ": a base mesh for a cache is one node's mesh; this file has several");
    node = int(n);
  }
  if (node < 0 || size_t(model.nodes[size_t(node)].mesh) >= model.meshes.size()) return bad(path + ": no mesh");
  if (model.nodes[size_t(node)].skin >= 0)
    return bad(path +
               ": the base mesh is skinned; export it without its armature (the cache holds the skinned points)");
  if (!model.animations.empty()) {
    warnings.push_back(std::to_string(model.animations.size()) + " animation(s) dropped: the cache is the animation");
    model.animations.clear();
  }
  const tinygltf::Mesh& mesh = model.meshes[size_t(model.nodes[size_t(node)].mesh)];
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    const tinygltf::Primitive& primitive = mesh.primitives[p];
    const std::string what =
        path + ": mesh " + std::to_string(model.nodes[size_t(node)].mesh) + " primitive " + std::to_string(p);
    if (!primitive.targets.empty()) return bad(what + " has morph targets; a base mesh for a cache has none");
    if (!primitive.extensions.empty()) return bad(what + " is compressed; decode it first");
    SampledPrimitive sampled;
    sampled.primitive = int(p);
    SEGMORPH_RETURN_IF_ERROR(read_rest_attributes(model, primitive, what, sampled));
    const size_t vertex_count = sampled.rest_positions.size() / 3;
    std::vector<uint32_t> triangles;
    SEGMORPH_RETURN_IF_ERROR(read_triangles(model, primitive, vertex_count, what, triangles));
    sampled.clips.resize(1);
    sampled.clips[0].triangles = std::move(triangles);
    std::vector<uint32_t> points(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) points[v] = uint32_t(base.points + v);
    base.points += vertex_count;
    base.vertex_point.push_back(std::move(points));
    base.primitives.push_back(std::move(sampled));
  }
  if (base.primitives.empty()) return bad(path + ": the mesh has no primitives");
  base.node = node;
  return Status::Ok();
}

// --- the frames ---

// Reads the frames one at a time into the base's clips: frame f of the cache at times[f].
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual size_t frames() const = 0;
  virtual Status read(size_t f, std::vector<float>& points) = 0;
};

class PointCacheFrames : public FrameSource {
 public:
  explicit PointCacheFrames(PointCacheReader& reader) : reader_(reader) {}
  size_t frames() const override { return reader_.frame_count(); }
  Status read(size_t f, std::vector<float>& points) override {
    const Status status = reader_.read_frame(f, points);
    return status.ok() ? status : Status(status.code(), reader_.path() + ": " + status.message());
  }

 private:
  PointCacheReader& reader_;
};

class ObjFrames : public FrameSource {
 public:
  ObjFrames(const std::vector<SequenceFile>& files, const ObjMesh& first) : files_(files), first_(first) {}
  size_t frames() const override { return files_.size(); }
  Status read(size_t f, std::vector<float>& points) override {
    if (f == 0) {
      points = first_.points;
      return Status::Ok();
    }
    return read_obj_frame(files_[f].path, first_, points);
  }

 private:
  const std::vector<SequenceFile>& files_;
  const ObjMesh& first_;
};

Status read_frames(FrameSource& source, const std::vector<float>& times, bool z_up, const std::string& what,
                   const Progress& progress, CacheMesh& base) {
  const size_t frames = source.frames();
  for (SampledPrimitive& primitive : base.primitives) {
    FrameSequence& clip = primitive.clips[0];
    clip.vertex_count = primitive.rest_positions.size() / 3;
    clip.frame_count = frames;
    clip.times = times;
    clip.positions.resize(frames * clip.vertex_count * 3);
  }
  std::vector<float> points;
  auto reported = std::chrono::steady_clock::now();
  for (size_t f = 0; f < frames; ++f) {
    SEGMORPH_RETURN_IF_ERROR(source.read(f, points));
    if (z_up) z_up_to_y_up(points);
    if (points.size() != base.points * 3)
      return bad(what + " frame " + std::to_string(f) + ": " + std::to_string(points.size() / 3) +
                 " points, the base " + "mesh " + std::to_string(base.points));
    for (size_t p = 0; p < base.primitives.size(); ++p) {
      float* out = base.primitives[p].clips[0].frame(f);
      const std::vector<uint32_t>& vertex_point = base.vertex_point[p];
      for (size_t v = 0; v < vertex_point.size(); ++v)
        for (size_t c = 0; c < 3; ++c) out[v * 3 + c] = points[size_t(vertex_point[v]) * 3 + c];
    }
    if (std::chrono::steady_clock::now() - reported > std::chrono::seconds(2)) {
      reported = std::chrono::steady_clock::now();
      report_progress(progress,
                      "reading " + what + ": frame " + std::to_string(f + 1) + " of " + std::to_string(frames));
    }
  }
  return Status::Ok();
}

// Frames at a constant rate from `first` (seconds), computed as sample.cpp's regular grid computes its times, so that
// sampling at that rate lands on them.
std::vector<float> grid_times(double first, size_t frames, double frames_per_second) {
  std::vector<float> times(frames);
  const double start = double(float(first));
  for (size_t f = 0; f < frames; ++f) times[f] = float(start + double(f) / frames_per_second);
  return times;
}

Status check_times(const std::vector<float>& times, const std::string& what) {
  for (size_t f = 1; f < times.size(); ++f)
    if (!(times[f] > times[f - 1]))
      return bad(what + ": frames " + std::to_string(f - 1) + " and " + std::to_string(f) +
                 " fall on the same time as floats (rate too high or start too large)");
  return Status::Ok();
}

// The baked form of `base` over its one clip, as the model's only animation.
Status bake_base(const std::string& clip_name, tinygltf::Model& model, CacheMesh& base) {
  tinygltf::Animation animation;
  animation.name = clip_name;
  model.animations.push_back(animation);
  Scene scene;
  scene.clips.resize(1);
  scene.clips[0].animation = 0;
  scene.clips[0].name = clip_name;
  AnimatedNode node;
  node.node = base.node;
  node.mesh = model.nodes[size_t(base.node)].mesh;
  node.morphed = true;
  node.weights_animated = true;
  node.clips = {0};
  std::vector<SampledNode> sampled(1);
  sampled[0].node = &node;
  sampled[0].clip_is_step = {false};
  sampled[0].primitives = std::move(base.primitives);
  SEGMORPH_RETURN_IF_ERROR(bake_model(model, scene, sampled));
  repack(model);
  return Status::Ok();
}

}  // namespace

Status Model::load_cache(const CacheSource& source, Model& model, CacheReport* report, const Progress& progress) {
  return guarded([&]() -> Status {
    model = Model();
    tinygltf::Model& gltf = model.data().gltf;
    CacheReport local;
    CacheReport& out = report ? *report : local;
    out = CacheReport();
    if (!(source.fps > 0) || !std::isfinite(source.fps))
      return Status(StatusCode::invalid_argument, "a cache's frame rate must be positive");
    CacheMesh base;
    std::vector<float> times;
    std::string clip_name;
    ObjMesh obj;
    double frames_per_second = 0;  // 0: the cache's own times (MDD)
    if (source.cache.empty()) {
      std::vector<SequenceFile> files;
      SEGMORPH_RETURN_IF_ERROR(list_sequence(source.mesh, files));
      report_progress(progress, "reading an OBJ sequence of " + std::to_string(files.size()) + " frames, " +
                                    files.front().path + " to " + files.back().path);
      SEGMORPH_RETURN_IF_ERROR(read_obj(files[0].path, obj));
      clip_name = sequence_name(source.mesh);
      add_obj_mesh(obj, clip_name, source.z_up, gltf, base);
      frames_per_second = source.fps;
      times = grid_times(double(files[0].number) / source.fps, files.size(), frames_per_second);
      SEGMORPH_RETURN_IF_ERROR(check_times(times, source.mesh));
      out.format = "OBJ sequence";
      ObjFrames frames(files, obj);
      SEGMORPH_RETURN_IF_ERROR(read_frames(frames, times, source.z_up, source.mesh, progress, base));
    } else {
      std::vector<std::string> warnings;
      if (has_suffix(source.mesh, ".obj")) {
        SEGMORPH_RETURN_IF_ERROR(read_obj(source.mesh, obj));
        add_obj_mesh(obj, stem_of(source.mesh), source.z_up, gltf, base);
        obj = ObjMesh();
      } else {
        SEGMORPH_RETURN_IF_ERROR(read_gltf_base(source.mesh, gltf, base, warnings));
      }
      for (const std::string& warning : warnings) report_progress(progress, "warning: " + source.mesh + ": " + warning);
      PointCacheReader reader;
      const Status opened = reader.open(source.cache);
      if (!opened.ok()) return Status(opened.code(), source.cache + ": " + opened.message());
      if (reader.point_count() != base.points)
        return bad(source.cache + " moves " + std::to_string(reader.point_count()) + " points, the base mesh " +
                   source.mesh + " has " + std::to_string(base.points) +
                   (has_suffix(source.mesh, ".obj") ? " (v lines)" : " (vertices)"));
      const bool pc2 = reader.format() == PointCacheReader::Format::pc2;
      out.format = pc2 ? "PC2" : "MDD";
      out.own_times = !pc2;
      if (pc2) {
        frames_per_second = source.fps / double(reader.pc2_rate());
        times = grid_times(double(reader.pc2_start()) / source.fps, reader.frame_count(), frames_per_second);
      } else {
        times = reader.times(source.fps);
      }
      SEGMORPH_RETURN_IF_ERROR(check_times(times, source.cache));
      clip_name = stem_of(source.cache);
      report_progress(progress, "reading " + source.cache + ": " + out.format + ", " +
                                    std::to_string(reader.frame_count()) + " frames of " +
                                    std::to_string(reader.point_count()) + " points");
      PointCacheFrames frames(reader);
      SEGMORPH_RETURN_IF_ERROR(read_frames(frames, times, source.z_up, source.cache, progress, base));
    }
    out.points = base.points;
    for (const SampledPrimitive& primitive : base.primitives) out.vertices += primitive.rest_positions.size() / 3;
    out.frames = times.size();
    out.first_time = times.front();
    out.last_time = times.back();
    // Above kMaxKeyRate keys per second, sampling at the keys needs a grid: the cache's rate (MDD's mean rate).
    const double rate = frames_per_second > 0 ? frames_per_second
                        : times.size() > 1    ? double(times.size() - 1) / (double(times.back()) - times.front())
                                              : 0;
    out.sampling.fps =
        double(times.size() - 1) <= SampleSettings::kMaxKeyRate * (double(times.back()) - times.front()) + 1e-9 ? 0
                                                                                                                : rate;
    if (gltf.asset.version.empty()) gltf.asset.version = "2.0";
    if (gltf.scenes.empty()) {
      gltf.scenes.emplace_back();
      gltf.scenes[0].nodes = {0};
      gltf.defaultScene = 0;
    }
    return bake_base(clip_name, gltf, base);
  });
}

}  // namespace segmorph
