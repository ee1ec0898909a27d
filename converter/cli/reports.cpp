#include "cli/reports.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

namespace segmorph {
namespace {

// Objects keep their keys in the order written.
using Json = nlohmann::ordered_json;

// `value` as printf's `format` writes it ("%.6g", "%.4f"), read back: the JSON holds the figures the text shows, in
// the fewest digits that read back as them. Non-finite values are JSON's null.
Json figure(double value, const char* format) {
  if (!std::isfinite(value)) return nullptr;
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return std::strtod(text, nullptr);
}

// One line of JSON: invalid UTF-8 (a file name in another encoding) as U+FFFD rather than an exception.
std::string line_of(const Json& json) {
  return json.dump(-1, ' ', false, Json::error_handler_t::replace);
}

// A count held as a double (Σ V × F) as a JSON integer.
Json whole(double value) {
  if (!(value >= 0 && value < 9e15)) return figure(value, "%.0f");
  return uint64_t(std::llround(value));
}

std::string plural(size_t count, const char* noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

Json name_or_null(const std::string& name) { return name.empty() ? Json(nullptr) : Json(name); }

Json primitive_error_json(const PrimitiveError& primitive) {
  return Json{{"node", primitive.node},
              {"node_name", primitive.node_name},
              {"mesh", primitive.mesh},
              {"primitive", primitive.primitive},
              {"vertices", primitive.vertices},
              {"frames", primitive.frames},
              {"kg_percent", figure(primitive.kg_percent, "%.6g")},
              {"rmse_over_diag", figure(primitive.rmse_over_diagonal, "%.6g")},
              {"max_error_over_diag", figure(primitive.max_error_over_diagonal, "%.6g")}};
}

// The size and error figures encode and verify both report, in that order, added to `json`.
template <typename Report>
void add_size_and_error(Json& json, size_t bytes, const Report& report) {
  json["bytes"] = bytes;
  json["bpvf"] = figure(bits_per_vertex_frame(bytes, report.vertex_frames), "%.4f");
  json["bpvf_animation"] = figure(bits_per_vertex_frame(report.animation_bytes, report.vertex_frames), "%.4f");
  json["kg_percent"] = figure(report.kg_percent, "%.6g");
  json["rmse_over_diag"] = figure(report.rmse_over_diagonal, "%.6g");
  json["max_error_over_diag"] = figure(report.max_error_over_diagonal, "%.6g");
}

Json stream_version_json(int version) { return version ? Json(version) : Json(nullptr); }

// How info says an encoded primitive's stream plays.
std::string stream_text(const PrimitiveInfo& primitive) {
  if (primitive.stream_version == 0) return "";
  const std::string version = ", stream version " + std::to_string(primitive.stream_version);
  if (primitive.kept_targets) return version + " of kept morph targets (plays as morph targets)";
  return version + (primitive.gpu_playable ? " (plays on the GPU from its model)"
                                           : " (plays as decoded frames; --gpu-playable writes version 4)");
}

}  // namespace

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

std::string error_json(const std::string& code, const std::string& file, const std::string& message) {
  return line_of(Json{{"error", Json{{"code", code}, {"file", name_or_null(file)}, {"message", message}}}});
}

std::string primitive_label(const PrimitiveError& primitive) {
  return (primitive.node_name.empty() ? "node " + std::to_string(primitive.node) : primitive.node_name) + ", mesh " +
         std::to_string(primitive.mesh) + " primitive " + std::to_string(primitive.primitive);
}

std::string info_text(const std::string& path, const InfoReport& report) {
  std::string text = path + ": " + plural(report.primitives.size(), "animated primitive") + ", " +
                     plural(report.animations, "animation") + "\n";
  for (const PrimitiveInfo& primitive : report.primitives) {
    const std::string name =
        primitive.node_name.empty() ? "node " + std::to_string(primitive.node) : primitive.node_name;
    text += name + ", mesh " + std::to_string(primitive.mesh) + " primitive " + std::to_string(primitive.primitive) +
            ": " + primitive.kind + ", " + std::to_string(primitive.vertices) + " vertices (" +
            std::to_string(primitive.welded_vertices) + " welded), " + std::to_string(primitive.triangles) +
            " triangles, " + plural(primitive.connected_components, "connected component") + stream_text(primitive) +
            "\n";
    for (const ClipInfo& clip : primitive.clips) {
      char line[512];
      std::snprintf(line, sizeof(line), "  clip %d %s: %zu frames, %.3f s, baked frames %zu bytes\n", clip.animation,
                    line_of(Json(clip.name)).c_str(), clip.frames, clip.duration, clip.baked_bytes);
      text += line;
    }
  }
  return text;
}

std::string info_json(const std::string& path, const InfoReport& report) {
  Json primitives = Json::array();
  for (const PrimitiveInfo& primitive : report.primitives) {
    Json clips = Json::array();
    for (const ClipInfo& clip : primitive.clips)
      clips.push_back(Json{{"animation", clip.animation},
                           {"name", clip.name},
                           {"frames", clip.frames},
                           {"duration", figure(clip.duration, "%.6g")},
                           {"baked_bytes", clip.baked_bytes}});
    primitives.push_back(Json{{"node", primitive.node},
                              {"node_name", primitive.node_name},
                              {"mesh", primitive.mesh},
                              {"primitive", primitive.primitive},
                              {"kind", primitive.kind},
                              {"vertices", primitive.vertices},
                              {"triangles", primitive.triangles},
                              {"welded_vertices", primitive.welded_vertices},
                              {"connected_components", primitive.connected_components},
                              {"stream_version", stream_version_json(primitive.stream_version)},
                              {"gpu_playable", primitive.gpu_playable},
                              {"clips", std::move(clips)}});
  }
  return line_of(Json{{"file", path}, {"primitives", std::move(primitives)}});
}

std::string encode_text(const std::string& output, size_t bytes, const EncodeReport& report) {
  char line[1024];
  std::snprintf(line, sizeof(line),
                "%s: %zu bytes, %.3f bits per vertex per frame (animation streams %zu bytes, Draco meshes %zu bytes), "
                "KG %.4f %% measured on the decoded file",
                output.c_str(), bytes, bits_per_vertex_frame(bytes, report.vertex_frames), report.animation_bytes,
                report.draco_bytes, report.kg_percent);
  std::string text = line;
  if (!report.streams.empty()) {
    std::snprintf(line, sizeof(line), ", %zu stream%s, %zu clusters, E(Pi) %.6f (Morse segmentation %.6f)",
                  report.streams.size(), report.streams.size() == 1 ? "" : "s", report.clusters, report.e_pi,
                  report.e_pi_morse);
    text += line;
  }
  text += "\n";
  for (const EncodedPrimitive& primitive : report.primitives) {
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

std::string encode_json(const std::string& input, const std::string& output, size_t bytes, const EncodeReport& report) {
  Json primitives = Json::array();
  for (const EncodedPrimitive& primitive : report.primitives) {  // the animated primitives, then the rigid meshes
    Json entry = primitive_error_json(primitive.error);
    entry["mode"] = mode_name(primitive.mode);
    entry["output_mesh"] = primitive.output_mesh;
    entry["output_primitive"] = primitive.output_primitive;
    entry["clusters"] = primitive.clusters;
    entry["bytes"] = primitive.bytes;
    entry["stream_version"] = stream_version_json(primitive.stream_version);
    entry["gpu_playable"] = primitive.gpu_playable;
    primitives.push_back(std::move(entry));
  }
  const auto ms = [](double milliseconds) { return figure(milliseconds, "%.1f"); };
  Json json{{"file", input}, {"output", output}};
  add_size_and_error(json, bytes, report);
  json["draco_bytes"] = report.draco_bytes;
  json["animation_bytes"] = report.animation_bytes;
  json["streams"] = report.streams.size();
  json["clusters"] = report.clusters;
  json["e_pi_morse"] = figure(report.e_pi_morse, "%.6g");
  json["e_pi"] = figure(report.e_pi, "%.6g");
  json["milliseconds"] = Json{{"segmentation", ms(report.ms_segmentation)},
                              {"motion", ms(report.ms_motion)},
                              {"prediction", ms(report.ms_prediction)},
                              {"rate_control", ms(report.ms_rate_control)},
                              {"entropy", ms(report.ms_entropy)},
                              {"draco", ms(report.ms_draco)},
                              {"tracks", ms(report.ms_tracks)},
                              {"measure", ms(report.ms_measure)}};
  json["primitives"] = std::move(primitives);
  return line_of(json);
}

std::string bound_text(VerifyBound bound, const VerifyReport& report, size_t bytes, const VerifyBounds& bounds) {
  char line[512];
  switch (bound) {
    case VerifyBound::none: return "";
    case VerifyBound::max_error: {
      const PrimitiveError* worst = report.worst();
      std::snprintf(line, sizeof(line), "KG %.4f %% is above --max-error %g (%s)", report.kg_percent, bounds.max_error,
                    worst ? primitive_label(*worst).c_str() : "");
      return line;
    }
    case VerifyBound::max_bpvf:
      std::snprintf(line, sizeof(line), "%.3f bits per vertex per frame is above --max-bpvf %g",
                    bits_per_vertex_frame(bytes, report.vertex_frames), bounds.max_bpvf);
      return line;
  }
  return "";
}

std::string verify_text(const std::string& original, const std::string& compressed, size_t bytes,
                        const VerifyReport& report) {
  char line[1024];
  std::snprintf(line, sizeof(line),
                "%s against %s: %zu vertices, %zu frames, %zu bytes, %.3f bpvf (animation %.3f), KG %.4f %%, "
                "RMSE %.3g and max error %.3g of the diagonal\n",
                compressed.c_str(), original.c_str(), report.vertices, report.frames, bytes,
                bits_per_vertex_frame(bytes, report.vertex_frames),
                bits_per_vertex_frame(report.animation_bytes, report.vertex_frames), report.kg_percent,
                report.rmse_over_diagonal, report.max_error_over_diagonal);
  std::string text = line;
  if (report.primitives.size() > 1)
    for (const PrimitiveError& primitive : report.primitives) {
      std::snprintf(line, sizeof(line),
                    "  %s: %zu vertices, KG %.4f %%, RMSE %.3g and max error %.3g of the diagonal\n",
                    primitive_label(primitive).c_str(), primitive.vertices, primitive.kg_percent,
                    primitive.rmse_over_diagonal, primitive.max_error_over_diagonal);
      text += line;
    }
  return text;
}

std::string verify_json(const std::string& original, const std::string& compressed, size_t bytes,
                        const VerifyReport& report, const std::string& above) {
  Json primitives = Json::array();
  for (const PrimitiveError& primitive : report.primitives) primitives.push_back(primitive_error_json(primitive));
  Json json{{"original", original},
            {"compressed", compressed},
            {"vertices", report.vertices},
            {"frames", report.frames},
            {"vertex_frames", whole(report.vertex_frames)}};
  add_size_and_error(json, bytes, report);
  json["primitives"] = std::move(primitives);
  if (!above.empty())
    json["error"] = Json{{"code", "above_bound"}, {"file", compressed}, {"message", above}};
  return line_of(json);
}

}  // namespace segmorph
