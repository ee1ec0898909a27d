// segmorph: the command-line tool, argument parsing and printing over the pipeline API (include/segmorph/segmorph.h).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__linux__)
#include <sys/auxv.h>
#endif
#include <string>
#include <vector>

#include "cli/batch.h"
#include "cli/command_line.h"
#include "encode/metrics.h"
#include "file_names.h"
#include "gltf/output_file.h"
#include "segmorph/segmorph.h"
#include "segmorph/version.h"

namespace segmorph {
namespace {

// The stable names of the error codes --json prints ("usage" for a usage error).
const char* code_name(StatusCode code) {
  switch (code) {
    case StatusCode::ok: return "ok";
    case StatusCode::invalid_argument: return "invalid_argument";
    case StatusCode::io_error: return "io_error";
    case StatusCode::bad_data: return "bad_data";
    case StatusCode::unsupported: return "unsupported";
    case StatusCode::nothing_to_do: return "nothing_to_do";
    case StatusCode::numerical: return "numerical";
    case StatusCode::internal: return "internal";
    case StatusCode::out_of_memory: return "out_of_memory";
  }
  return "internal";
}

// An error: one line on stderr and, with --json, one object on stdout.
void print_error(bool json, const char* code, const std::string& file, const std::string& message) {
  if (file.empty())
    std::fprintf(stderr, "segmorph: %s (see segmorph --help)\n", message.c_str());
  else
    std::fprintf(stderr, "segmorph: error: %s: %s\n", file.c_str(), message.c_str());
  if (json)
    std::printf("{\"error\":{\"code\":\"%s\",\"file\":%s,\"message\":%s}}\n", code,
                file.empty() ? "null" : json_string(file).c_str(), json_string(message).c_str());
}

int usage_error(bool json, const std::string& message) {
  print_error(json, "usage", "", message);
  return 2;
}

int fail(const CommandLine& options, const std::string& file, const Status& status) {
  // Messages may quote bytes of a corrupt file: control characters would break the one-line promise. A message that
  // starts with the file's name (a vertex cache's, which reads several files) does not repeat it.
  std::string message = status.message();
  if (message.compare(0, file.size() + 2, file + ": ") == 0) message.erase(0, file.size() + 2);
  for (char& c : message)
    if ((unsigned char)c < 0x20 || c == 0x7f) c = '?';
  print_error(options.json, code_name(status.code()), file, message);
  return 1;
}

void progress(const CommandLine& options, const std::string& message) {
  if (options.quiet) return;
  if (options.label.empty())
    std::fprintf(stderr, "segmorph: %s\n", message.c_str());
  else
    std::fprintf(stderr, "segmorph: %s: %s\n", options.label.c_str(), message.c_str());
}


Progress progress_of(const CommandLine& options) {
  return [&options](const std::string& message) { progress(options, message); };
}

// Reads the glTF file `path` into `model`, its warnings as progress.
Status load(const std::string& path, const CommandLine& options, Model& model) {
  progress(options, "reading " + (path == "-" ? std::string("the standard input") : path));
  std::vector<std::string> warnings;
  SEGMORPH_RETURN_IF_ERROR(Model::load(path, model, &warnings));
  for (const std::string& warning : warnings) progress(options, "warning: " + path + ": " + warning);
  return Status::Ok();
}

// True when `path` names an OBJ sequence: a folder, or a name with a % (a printf pattern) that is not a glTF's.
bool is_obj_sequence(const std::string& path) {
  struct stat info {};
  if (stat(path.c_str(), &info) == 0) return S_ISDIR(info.st_mode);
  return path.find('%') != std::string::npos && !has_gltf_extension(path);
}

// Reads input `index` into `model`: a glTF file, or a vertex cache (an OBJ sequence, or a base mesh with its point
// cache, --cache or --cache2). `sampling`: how to sample it (a cache's every frame, unless --fps resamples an MDD).
Status load_input(size_t index, const CommandLine& options, Model& model, SampleSettings& sampling) {
  const std::string& path = options.inputs[index];
  const std::string& cache = index == 0 ? options.cache : options.cache2;
  sampling = options.sampling;
  if (cache.empty() && !is_obj_sequence(path)) {
    if (has_suffix(path, ".obj"))
      return Status(StatusCode::invalid_argument, "an .obj alone is one frame: give its point cache with --cache, "
                                                  "or an OBJ sequence as a folder or a pattern (walk_%04d.obj)");
    if (has_suffix(path, ".pc2") || has_suffix(path, ".mdd"))
      return Status(StatusCode::invalid_argument, "a point cache moves a base mesh: give the mesh (.obj, .glb or "
                                                  ".gltf) as the input and the cache with --cache");
    return load(path, options, model);
  }
  CacheSource source;
  source.mesh = path;
  source.cache = cache;
  if (options.sampling.fps > 0) source.fps = options.sampling.fps;
  source.z_up = options.z_up;
  CacheReport report;
  SEGMORPH_RETURN_IF_ERROR(Model::load_cache(source, model, &report, progress_of(options)));
  char line[256];
  std::snprintf(line, sizeof(line), "%s: %zu frames of %zu points (%zu glTF vertices), %.4g s to %.4g s",
                report.format.c_str(), report.frames, report.points, report.vertices, report.first_time,
                report.last_time);
  progress(options, line);
  if (!(report.format == "MDD" && options.sampling.fps > 0)) sampling = report.sampling;
  return Status::Ok();
}

// The bytes of input `index`: its files (a glTF's with its .bin and images; a point cache and its mesh); an OBJ
// sequence's or the standard input's, those of the glTF it reads as (a .glb).
size_t input_bytes(size_t index, const CommandLine& options, const Model& model) {
  const std::string& path = options.inputs[index];
  const std::string& cache = index == 0 ? options.cache : options.cache2;
  if (path == "-") return model.glb_size();
  if (cache.empty() && !is_obj_sequence(path)) return file_bytes(path, model);
  if (cache.empty()) return model.glb_size();  // an OBJ sequence: the glTF it reads as
  size_t bytes = 0;
  for (const std::string& file : {path, cache}) {
    struct stat info {};
    if (!file.empty() && stat(file.c_str(), &info) == 0 && S_ISREG(info.st_mode)) bytes += size_t(info.st_size);
  }
  return bytes;
}

// bake, encode and decode do not write over their own input (or a file it reads) unless --force: a usage error.
int refuse_replacing_input(const CommandLine& options, const Model& input) {
  for (const std::string* output : {&options.output, &options.frames})
    if (!output->empty() && *output != "-" && options.inputs[0] != "-" && writes_over(*output, options.inputs[0], input))
      return usage_error(options.json, *output + " would replace the input " + options.inputs[0] +
                         " or a file it reads; give --force to replace it");
  return 0;
}

// A binary file is not written to a terminal; otherwise 0.
int refuse_terminal_output(const CommandLine& options) {
  if ((options.output == "-" || options.frames == "-") && isatty(STDOUT_FILENO))
    return usage_error(options.json, "the standard output is a terminal: redirect it, or give -o FILE");
  return 0;
}

// Where a command's report goes: stdout, unless the output file does.
FILE* report_stream(const CommandLine& options) {
  return options.output == "-" || options.frames == "-" ? stderr : stdout;
}


std::string primitive_label(const PrimitiveError& primitive) {
  return (primitive.node_name.empty() ? "node " + std::to_string(primitive.node) : primitive.node_name) + ", mesh " +
         std::to_string(primitive.mesh) + " primitive " + std::to_string(primitive.primitive);
}

std::string primitive_error_json(const PrimitiveError& primitive) {
  char figures[256];
  std::snprintf(figures, sizeof(figures),
                ",\"mesh\":%d,\"primitive\":%d,\"vertices\":%zu,\"frames\":%zu,\"kg_percent\":%.6g,"
                "\"rmse_over_diag\":%.6g,\"max_error_over_diag\":%.6g",
                primitive.mesh, primitive.primitive, primitive.vertices, primitive.frames, primitive.kg_percent,
                primitive.rmse_over_diagonal, primitive.max_error_over_diagonal);
  return "{\"node\":" + std::to_string(primitive.node) + ",\"node_name\":" + json_string(primitive.node_name) + figures;
}

// encode's primitives as a JSON array: the input's animated primitives, then the rigid meshes.
std::string encoded_primitives_json(const EncodeReport& report) {
  std::string json = "[";
  for (const EncodedPrimitive& primitive : report.primitives) {
    if (json.size() > 1) json += ",";
    json += primitive_error_json(primitive.error);
    json += std::string(",\"mode\":\"") + mode_name(primitive.mode) + "\",\"output_mesh\":" +
            std::to_string(primitive.output_mesh) + ",\"output_primitive\":" +
            std::to_string(primitive.output_primitive) + ",\"clusters\":" + std::to_string(primitive.clusters) +
            ",\"bytes\":" + std::to_string(primitive.bytes) + ",\"stream_version\":" +
            (primitive.stream_version ? std::to_string(primitive.stream_version) : "null") +
            ",\"gpu_playable\":" + (primitive.gpu_playable ? "true" : "false") + "}";
  }
  return json + "]";
}

// encode's primitives, one indented line each.
std::string encoded_primitives_text(const EncodeReport& report) {
  std::string text;
  for (const EncodedPrimitive& primitive : report.primitives) {
    char line[512];
    const PrimitiveError& e = primitive.error;
    const std::string version = primitive.stream_version == 0 ? std::string()
                                : ", stream version " + std::to_string(primitive.stream_version) +
                                      (primitive.gpu_playable ? " (GPU-playable)" : "");
    std::snprintf(line, sizeof(line), "  %s: %s, %zu vertices, %zu frames, %zu clusters, %zu bytes, KG %.4f %%%s%s\n",
                  primitive_label(e).c_str(), mode_name(primitive.mode), e.vertices, e.frames, primitive.clusters,
                  primitive.bytes, e.kg_percent, version.c_str(),
                  primitive.mode == PrimitiveMode::rigid ? " of the part alone (not in the file's KG)" : "");
    text += line;
  }
  return text;
}

// How info says an encoded primitive's stream plays.
std::string stream_text(const PrimitiveInfo& primitive) {
  if (primitive.stream_version == 0) return "";
  const std::string version = ", stream version " + std::to_string(primitive.stream_version);
  if (primitive.kept_targets) return version + " of kept morph targets (plays as morph targets)";
  return version + (primitive.gpu_playable ? " (plays on the GPU from its model)"
                                           : " (plays as decoded frames; --gpu-playable writes version 4)");
}

int run_info(const CommandLine& options) {
  const std::string& path = options.inputs[0];
  Model model;
  InfoReport report;
  SampleSettings sampling;
  Status status = load_input(0, options, model, sampling);
  if (status.ok()) status = info(model, sampling, report, progress_of(options));
  if (!status.ok()) return fail(options, path, status);

  std::string json = "{\"file\":" + json_string(path) + ",\"primitives\":[";
  std::string text;
  for (size_t p = 0; p < report.primitives.size(); ++p) {
    const PrimitiveInfo& primitive = report.primitives[p];
    const std::string name = primitive.node_name.empty() ? "node " + std::to_string(primitive.node) : primitive.node_name;
    if (p) json += ",";
    json += "{\"node\":" + std::to_string(primitive.node) + ",\"node_name\":" + json_string(primitive.node_name) +
            ",\"mesh\":" + std::to_string(primitive.mesh) + ",\"primitive\":" + std::to_string(primitive.primitive) +
            ",\"kind\":" + json_string(primitive.kind) + ",\"vertices\":" + std::to_string(primitive.vertices) +
            ",\"triangles\":" + std::to_string(primitive.triangles) +
            ",\"welded_vertices\":" + std::to_string(primitive.welded_vertices) +
            ",\"connected_components\":" + std::to_string(primitive.connected_components) +
            ",\"stream_version\":" + (primitive.stream_version ? std::to_string(primitive.stream_version) : "null") +
            ",\"gpu_playable\":" + (primitive.gpu_playable ? "true" : "false") + ",\"clips\":[";
    text += name + ", mesh " + std::to_string(primitive.mesh) + " primitive " + std::to_string(primitive.primitive) +
            ": " + primitive.kind + ", " + std::to_string(primitive.vertices) + " vertices (" +
            std::to_string(primitive.welded_vertices) + " welded), " + std::to_string(primitive.triangles) +
            " triangles, " + std::to_string(primitive.connected_components) + " connected component" +
            (primitive.connected_components == 1 ? "" : "s") + stream_text(primitive) + "\n";
    for (size_t c = 0; c < primitive.clips.size(); ++c) {
      const ClipInfo& clip = primitive.clips[c];
      char line[512];
      std::snprintf(line, sizeof(line), "  clip %d %s: %zu frames, %.3f s, baked frames %zu bytes\n", clip.animation,
                    json_string(clip.name).c_str(), clip.frames, clip.duration, clip.baked_bytes);
      text += line;
      std::snprintf(line, sizeof(line),
                    "%s{\"animation\":%d,\"name\":%s,\"frames\":%zu,\"duration\":%.6g,\"baked_bytes\":%zu}",
                    c ? "," : "", clip.animation, json_string(clip.name).c_str(), clip.frames, clip.duration,
                    clip.baked_bytes);
      json += line;
    }
    json += "]}";
  }
  json += "]}";
  const size_t count = report.primitives.size();
  if (options.json)
    std::printf("%s\n", json.c_str());
  else
    std::printf("%s: %zu animated primitive%s, %zu animation%s\n%s", path.c_str(), count, count == 1 ? "" : "s",
                report.animations, report.animations == 1 ? "" : "s", text.c_str());
  return 0;
}

int run_bake(const CommandLine& options) {
  if (const int refused = refuse_terminal_output(options)) return refused;
  const std::string& path = options.inputs[0];
  Model model;
  BakeReport report;
  SampleSettings sampling;
  Status status = load_input(0, options, model, sampling);
  if (status.ok() && !options.force)
    if (const int refused = refuse_replacing_input(options, model)) return refused;
  if (status.ok()) status = bake(model, sampling, &report, progress_of(options));
  if (!status.ok()) return fail(options, path, status);
  progress(options, "writing " + (options.output == "-" ? std::string("to the standard output") : options.output));
  status = model.save(options.output);
  if (!status.ok()) return fail(options, options.output, status);
  progress(options, "baked " + std::to_string(report.nodes) + " animated node" + (report.nodes == 1 ? "" : "s") + ", " +
                        std::to_string(report.frames) + " frames in all");
  return 0;
}

int run_encode(const CommandLine& options) {
  if (const int refused = refuse_terminal_output(options)) return refused;
  const std::string& path = options.inputs[0];
  Model input, output;
  EncodeReport report;
  EncodeSettings settings = options.encode;
  Status status = load_input(0, options, input, settings.sampling);
  if (status.ok() && !options.force)
    if (const int refused = refuse_replacing_input(options, input)) return refused;
  if (status.ok()) status = encode(std::move(input), settings, output, &report, progress_of(options));
  if (!status.ok()) return fail(options, path, status);
  progress(options, "writing " + (options.output == "-" ? std::string("to the standard output") : options.output));
  status = output.save(options.output);
  if (!status.ok()) return fail(options, options.output, status);

  Model written;
  const size_t bytes = options.output == "-"                          ? output.glb_size()
                       : Model::load(options.output, written).ok() ? file_bytes(options.output, written)
                                                                    : 0;
  FILE* out = report_stream(options);
  const double vertex_frames = report.vertex_frames;
  double clusters = 0, e_pi = 0, e_pi_morse = 0, ms[5] = {0, 0, 0, 0, 0};
  for (const StreamReport& r : report.streams) {
    clusters += double(r.clusters);
    e_pi = std::max(e_pi, r.e_pi);
    e_pi_morse = std::max(e_pi_morse, r.e_pi_morse);
    const double stage[5] = {r.ms_segmentation, r.ms_motion, r.ms_prediction, r.ms_rate_control, r.ms_entropy};
    for (int i = 0; i < 5; ++i) ms[i] += stage[i];
  }
  const double bpvf = bits_per_vertex_frame(bytes, vertex_frames);
  if (options.json) {
    std::fprintf(out, 
        "{\"file\":%s,\"output\":%s,\"bytes\":%zu,\"bpvf\":%.4f,\"bpvf_animation\":%.4f,\"kg_percent\":%.6g,"
        "\"rmse_over_diag\":%.6g,\"max_error_over_diag\":%.6g,\"draco_bytes\":%zu,\"animation_bytes\":%zu,"
        "\"streams\":%zu,\"clusters\":%.0f,\"e_pi_morse\":%.6g,\"e_pi\":%.6g,\"milliseconds\":{\"segmentation\":%.1f,"
        "\"motion\":%.1f,\"prediction\":%.1f,\"rate_control\":%.1f,\"entropy\":%.1f,\"draco\":%.1f,\"tracks\":%.1f,"
        "\"measure\":%.1f},\"primitives\":%s}\n",
        json_string(path).c_str(), json_string(options.output).c_str(), bytes, bpvf,
        bits_per_vertex_frame(report.animation_bytes, vertex_frames), report.kg_percent,
        report.rmse_over_diagonal, report.max_error_over_diagonal, report.draco_bytes, report.animation_bytes,
        report.streams.size(), clusters, e_pi_morse, e_pi, ms[0], ms[1], ms[2], ms[3], ms[4], report.ms_draco,
        report.ms_tracks, report.ms_measure, encoded_primitives_json(report).c_str());
  } else {
    std::fprintf(out, "%s: %zu bytes, %.3f bits per vertex per frame (animation streams %zu bytes, Draco meshes %zu bytes), "
                "KG %.4f %% measured on the decoded file",
                options.output.c_str(), bytes, bpvf, report.animation_bytes, report.draco_bytes, report.kg_percent);
    if (!report.streams.empty())
      std::fprintf(out, ", %zu stream%s, %.0f clusters, E(Pi) %.6f (Morse segmentation %.6f)", report.streams.size(),
                  report.streams.size() == 1 ? "" : "s", clusters, e_pi, e_pi_morse);
    std::fprintf(out, "\n%s", encoded_primitives_text(report).c_str());
  }
  return 0;
}

int run_decode(const CommandLine& options) {
  if (const int refused = refuse_terminal_output(options)) return refused;
  const std::string& path = options.inputs[0];
  Model model;
  DecodeReport report;
  std::vector<DecodedFrames> decoded;
  Status status = load(path, options, model);
  if (status.ok() && !options.force)
    if (const int refused = refuse_replacing_input(options, model)) return refused;
  if (status.ok()) status = decode(model, &report, options.frames.empty() ? nullptr : &decoded);
  if (!status.ok()) return fail(options, path, status);
  if (report.primitives == 0 && report.coded_animations == 0)
    return fail(options, path, Status(StatusCode::nothing_to_do,
                             "not encoded: it has no SEGMORPH_animation_compression primitive or animation"));
  if (!options.output.empty()) {
    progress(options, "writing " + (options.output == "-" ? std::string("to the standard output") : options.output));
    status = model.save(options.output);
    if (!status.ok()) return fail(options, options.output, status);
  }
  if (!options.frames.empty()) {
    progress(options, "writing the decoded frames to " + options.frames);
    status = save_decoded_frames(decoded, options.frames);
    if (!status.ok()) return fail(options, options.frames, status);
  }
  progress(options, "decoded " + std::to_string(report.primitives) + " primitive" + (report.primitives == 1 ? "" : "s") +
                        " and the tracks of " + std::to_string(report.coded_animations) + " animation" +
                        (report.coded_animations == 1 ? "" : "s"));
  return 0;
}

int run_verify(const CommandLine& options) {
  const std::string &original_path = options.inputs[0], &compressed_path = options.inputs[1];
  Model original, compressed;
  SampleSettings sampling, compressed_sampling;
  Status status = load_input(0, options, original, sampling);
  if (!status.ok()) return fail(options, original_path, status);
  status = load_input(1, options, compressed, compressed_sampling);
  if (!status.ok()) return fail(options, compressed_path, status);
  VerifyReport report;
  status = verify(original, compressed, sampling, report, progress_of(options));
  if (!status.ok()) {
    // Which file is at fault: the original when it cannot be sampled alone.
    InfoReport alone;
    const Status original_status = info(original, sampling, alone);
    return original_status.ok() ? fail(options, compressed_path, status) : fail(options, original_path, original_status);
  }
  // The standard input's size is that of the file as a .glb.
  const size_t bytes = input_bytes(1, options, compressed);
  const double vertex_frames = report.vertex_frames;
  const double bpvf = bits_per_vertex_frame(bytes, vertex_frames);
  const double bpvf_animation = bits_per_vertex_frame(report.animation_bytes, vertex_frames);
  // The gate: the first bound exceeded, in one line.
  std::string above;
  char line[512];
  const PrimitiveError* worst = nullptr;
  for (const PrimitiveError& primitive : report.primitives)
    if (!worst || primitive.kg_percent > worst->kg_percent) worst = &primitive;
  if (options.max_error >= 0 && report.kg_percent > options.max_error) {
    std::snprintf(line, sizeof(line), "KG %.4f %% is above --max-error %g (%s)", report.kg_percent, options.max_error,
                  worst ? primitive_label(*worst).c_str() : "");
    above = line;
  } else if (options.max_bpvf >= 0 && bpvf > options.max_bpvf) {
    std::snprintf(line, sizeof(line), "%.3f bits per vertex per frame is above --max-bpvf %g", bpvf, options.max_bpvf);
    above = line;
  }
  std::string primitives;
  for (const PrimitiveError& primitive : report.primitives)
    primitives += (primitives.empty() ? "" : ",") + primitive_error_json(primitive) + "}";
  if (options.json) {
    std::printf(
        "{\"original\":%s,\"compressed\":%s,\"vertices\":%zu,\"frames\":%zu,\"vertex_frames\":%.0f,"
        "\"bytes\":%zu,\"bpvf\":%.4f,\"bpvf_animation\":%.4f,\"kg_percent\":%.6g,\"rmse_over_diag\":%.6g,"
        "\"max_error_over_diag\":%.6g,\"primitives\":[%s]%s}\n",
        json_string(original_path).c_str(), json_string(compressed_path).c_str(), report.vertices, report.frames,
        vertex_frames, bytes, bpvf, bpvf_animation, report.kg_percent, report.rmse_over_diagonal,
        report.max_error_over_diagonal, primitives.c_str(),
        above.empty() ? ""
                      : (",\"error\":{\"code\":\"above_bound\",\"file\":" + json_string(compressed_path) +
                         ",\"message\":" + json_string(above) + "}")
                            .c_str());
  } else {
    std::printf(
        "%s against %s: %zu vertices, %zu frames, %zu bytes, %.3f bpvf (animation %.3f), KG %.4f %%, "
        "RMSE %.3g and max error %.3g of the diagonal\n",
        compressed_path.c_str(), original_path.c_str(), report.vertices, report.frames, bytes, bpvf, bpvf_animation,
        report.kg_percent, report.rmse_over_diagonal, report.max_error_over_diagonal);
    if (report.primitives.size() > 1)
      for (const PrimitiveError& primitive : report.primitives)
        std::printf("  %s: %zu vertices, KG %.4f %%, RMSE %.3g and max error %.3g of the diagonal\n",
                    primitive_label(primitive).c_str(), primitive.vertices, primitive.kg_percent,
                    primitive.rmse_over_diagonal, primitive.max_error_over_diagonal);
  }
  if (!above.empty()) {
    std::fprintf(stderr, "segmorph: error: %s: %s\n", compressed_path.c_str(), above.c_str());
    return 1;
  }
  return 0;
}

// Whether the command line asks for --json (for a usage error found before it was read).
bool wants_json(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--json") == 0) return true;
  return false;
}

int run(int argc, char** argv) {
  CommandLine options;
  std::string error;
  switch (parse_command_line(argc, argv, options, error)) {
    case ParseResult::help:
      std::fputs(usage().c_str(), stdout);
      return 0;
    case ParseResult::version:
      std::printf("segmorph %d.%d.%d (animation streams %d to %d, track stream %d)\n", SEGMORPH_VERSION_MAJOR,
                  SEGMORPH_VERSION_MINOR, SEGMORPH_VERSION_PATCH, SEGMORPH_STREAM_VERSION_MIN,
                  SEGMORPH_STREAM_VERSION_MAX, SEGMORPH_TRACK_STREAM_VERSION);
      return 0;
    case ParseResult::usage_error:
      if (!error.empty()) return usage_error(options.json || wants_json(argc, argv), error);
      std::fputs(usage().c_str(), stderr);
      return 2;
    case ParseResult::run:
      break;
  }
  if (!options.output_directory.empty()) {
    std::vector<BatchFile> files;
    if (!plan_batch(options.inputs, options.output_directory, files, error)) return usage_error(options.json, error);
    return run_batch(options, files, options.command == "bake" ? run_bake : options.command == "encode" ? run_encode
                                                                                                    : run_decode);
  }
  if (options.command == "info") return run_info(options);
  if (options.command == "bake") return run_bake(options);
  if (options.command == "encode") return run_encode(options);
  if (options.command == "decode") return run_decode(options);
  return run_verify(options);
}

}  // namespace
}  // namespace segmorph

namespace {

// Large buffers (a production cache's frames are gigabytes) are first touched page by page, and with 4 KiB pages each
// touch is a page fault: on the machine the benchmarks run on, a third of a 200k-vertex encode's time. glibc backs its
// large allocations with transparent huge pages when its tunable glibc.malloc.hugetlb is 1 (where the kernel leaves
// them to madvise, as Debian's does), but reads its tunables only at start: so the tool starts itself again, once,
// from its own file, with the tunable added to GLIBC_TUNABLES and SEGMORPH_HUGE_PAGES=1 (which also stops a second
// restart where glibc ignores the tunables). The arguments, descriptors and output bytes are the same. It does not
// restart when SEGMORPH_HUGE_PAGES is set (0 turns this off: for a tool that does not follow a restart, valgrind
// without --trace-children), when GLIBC_TUNABLES already names the tunable, for a secure-mode (setuid) start, under
// a sanitizer or valgrind (which replace malloc), when started through the dynamic loader, or when the restart
// fails (it then goes on as started).
void use_transparent_huge_pages(char** argv) {
#if defined(__linux__) && defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
  constexpr const char* kTunable = "glibc.malloc.hugetlb";
  if (std::getenv("SEGMORPH_HUGE_PAGES") != nullptr || getauxval(AT_SECURE) != 0) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, kTunable) != nullptr) return;
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload != nullptr && std::strstr(preload, "vgpreload") != nullptr) return;  // valgrind
  // The file this process runs (not the dynamic loader's, when it was started through it).
  char self[4096];
  const ssize_t length = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length <= 0) return;
  self[length] = '\0';
  const char* name = std::strrchr(self, '/');
  if (std::strncmp(name != nullptr ? name + 1 : self, "ld-", 3) == 0) return;
  const std::string previous = tunables != nullptr ? tunables : "";
  const std::string wanted = (previous.empty() ? "" : previous + ":") + kTunable + "=1";
  if (setenv("GLIBC_TUNABLES", wanted.c_str(), 1) != 0 || setenv("SEGMORPH_HUGE_PAGES", "1", 1) != 0) return;
  execv(self, argv);
  // Still here: the restart failed; go on as started.
  unsetenv("SEGMORPH_HUGE_PAGES");
  if (tunables != nullptr)
    setenv("GLIBC_TUNABLES", previous.c_str(), 1);
  else
    unsetenv("GLIBC_TUNABLES");
#else
  (void)argv;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  use_transparent_huge_pages(argv);
  segmorph::remove_temporary_files_on_signals();
  return segmorph::run(argc, argv);
}
