// The inputs of the pipeline's commands (include/segmorph/segmorph.h, "inputs"): which kind a name is, reading it as
// a glTF, and what it weighs as delivered.
#include <sys/stat.h>

#include <cstdio>
#include <string>
#include <vector>

#include "file_names.h"
#include "pipeline.h"
#include "segmorph/segmorph.h"

namespace segmorph {
namespace {

// True when `path` names an OBJ sequence: a folder, or a name with a % (a printf pattern) that is not a glTF's.
bool is_obj_sequence(const std::string& path) {
  struct stat info {};
  if (stat(path.c_str(), &info) == 0) return S_ISDIR(info.st_mode);
  return path.find('%') != std::string::npos && !has_gltf_extension(path);
}

}  // namespace

InputKind input_kind(const Input& input) {
  if (!input.cache.empty()) return InputKind::point_cache;
  return is_obj_sequence(input.path) ? InputKind::obj_sequence : InputKind::gltf;
}

Status load_input(const Input& input, const SampleSettings& requested, Model& model, SampleSettings& sampling,
                  const Progress& progress, CacheReport* cache) {
  return guarded([&]() -> Status {
    sampling = requested;
    if (!input.caches || input_kind(input) == InputKind::gltf) {
      if (input.caches && has_suffix(input.path, ".obj"))
        return Status(StatusCode::invalid_argument, "an .obj alone is one frame: give its point cache with --cache, "
                                                    "or an OBJ sequence as a folder or a pattern (walk_%04d.obj)");
      if (input.caches && (has_suffix(input.path, ".pc2") || has_suffix(input.path, ".mdd")))
        return Status(StatusCode::invalid_argument, "a point cache moves a base mesh: give the mesh (.obj, .glb or "
                                                    ".gltf) as the input and the cache with --cache");
      report_progress(progress, "reading " + (input.path == "-" ? std::string("the standard input") : input.path));
      std::vector<std::string> warnings;
      SEGMORPH_RETURN_IF_ERROR(Model::load(input.path, model, &warnings));
      for (const std::string& warning : warnings) report_progress(progress, "warning: " + input.path + ": " + warning);
      return Status::Ok();
    }
    CacheSource source;
    source.mesh = input.path;
    source.cache = input.cache;
    if (requested.fps > 0) source.fps = requested.fps;
    source.z_up = input.z_up;
    CacheReport local;
    CacheReport& read = cache ? *cache : local;
    SEGMORPH_RETURN_IF_ERROR(Model::load_cache(source, model, &read, progress));
    char line[256];
    std::snprintf(line, sizeof(line), "%s: %zu frames of %zu points (%zu glTF vertices), %.4g s to %.4g s",
                  read.format.c_str(), read.frames, read.points, read.vertices, read.first_time, read.last_time);
    report_progress(progress, line);
    if (!(read.own_times && requested.fps > 0)) sampling = read.sampling;
    return Status::Ok();
  });
}

size_t input_bytes(const Input& input, const Model& model) {
  if (input.path == "-") return model.glb_size();
  switch (input_kind(input)) {
    case InputKind::gltf: return file_bytes(input.path, model);
    case InputKind::obj_sequence: return model.glb_size();  // the glTF it reads as
    case InputKind::point_cache: break;
  }
  size_t bytes = 0;
  for (const std::string& file : {input.path, input.cache}) {
    struct stat info {};
    if (stat(file.c_str(), &info) == 0 && S_ISREG(info.st_mode)) bytes += size_t(info.st_size);
  }
  return bytes;
}

size_t saved_bytes(const std::string& path, const Model& saved) {
  if (path == "-") return saved.glb_size();
  Model written;
  return Model::load(path, written).ok() ? file_bytes(path, written) : 0;
}

}  // namespace segmorph
