// segmorph: the command-line tool, argument parsing and printing over the pipeline API (include/segmorph/segmorph.h).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "segmorph/segmorph.h"
#include "segmorph/version.h"

namespace segmorph {
namespace {

const char* const kUsage =
    "usage: segmorph <command> [options]\n"
    "\n"
    "Commands:\n"
    "  info FILE [--json] [--fps N]\n"
    "      List the animated primitives of a glTF file: vertices, triangles, kind (morph, skinned or\n"
    "      morph+skinned), clips with their frame counts and durations, connected components, and the\n"
    "      size of the baked frames (V x F x 3 floats).\n"
    "  bake IN -o OUT [--fps N]\n"
    "      Write OUT (.glb or .gltf) with every animated primitive baked into POSITION and NORMAL morph\n"
    "      targets, one per frame, played by one weights animation per clip (sparse one-hot weights).\n"
    "      Skins and joint channels that no longer move anything are removed; everything else is kept.\n"
    "  encode IN -o OUT [--error E | --bpvf R | --lossless] [--fps N] [--clusters K] [--position-bits B]\n"
    "         [--normal-bits B] [--texcoord-bits B] [--skins keep|bake] [--targets auto|keep|bake]\n"
    "         [--fast-decode] [--json]\n"
    "      Compress every animated primitive: its first frame with KHR_draco_mesh_compression, its animation\n"
    "      as a SEGMORPH_animation_compression stream: the sampled frames, or the morph targets themselves\n"
    "      (see --targets); a skinned mesh keeps its skin (see --skins). Meshes that animated nodes move\n"
    "      are compressed with Draco, and translation, rotation and scale tracks are coded (the extension\n"
    "      is then required). Default target: --error 0.15 (KG error in %).\n"
    "  decode IN -o OUT [--frames FRAMES]\n"
    "      Restore standard glTF from an encoded file: morph targets in the form bake writes, a mesh's kept\n"
    "      morph targets played by its own weights animation, kept skins, plain meshes and float tracks.\n"
    "      With --frames, also (or, without -o, only) write what every compressed primitive's stream\n"
    "      decodes to as raw little-endian float32, the layout examples/engine_decode writes: primitive by\n"
    "      primitive (meshes in order, then their primitives), clip by clip, frame by frame, vertex by\n"
    "      vertex, x y z; the frames are positions, except for kept morph targets: one clip of their\n"
    "      POSITION displacements (docs/runtime.md).\n"
    "  verify ORIGINAL COMPRESSED [--json]\n"
    "      Compare the animation of two files (either may be encoded, baked, original or written by another\n"
    "      tool: primitives and vertices are paired by trajectory, COMPRESSED is sampled at ORIGINAL's frame\n"
    "      times): bytes, bits per vertex per frame, KG error, RMSE and maximum error over the bounding-box\n"
    "      diagonal.\n"
    "\n"
    "Options:\n"
    "  -o, --output FILE  output file (.glb: binary; .gltf: JSON with FILE's name .bin beside it)\n"
    "  --frames FILE      decode: also write the decoded frames as raw float32 (see decode)\n"
    "  --fps N            sample every clip on a regular grid of N frames per second; by default the\n"
    "                     union of the clip's key times, or 30 fps where keys are denser than 60 per second\n"
    "  --error E          encode: KG error target in percent (default 0.15)\n"
    "  --bpvf R           encode: target bits per vertex per frame of the whole output, images and JSON\n"
    "                     included (it encodes twice: the first encode measures what the rest of the file takes)\n"
    "  --lossless         encode: restore the sampled frames bit for bit\n"
    "  --fast-decode      encode: code the residuals for decoding speed (stream version 2, its table\n"
    "                     code): about a third less decoding time, files 1 to 11 % larger on the three\n"
    "                     classic sequences (docs/codec.md). Not with --lossless\n"
    "  --clusters K       encode: number of motion clusters, 1 to 65535, at most what the segmentation\n"
    "                     gives a primitive (more is said and coded with that many; default: automatic)\n"
    "  --position-bits B  encode: Draco quantization bits of the base mesh positions, 8 to 22 (default: from\n"
    "                     the error target, at least 12; 14 with --bpvf or --lossless)\n"
    "  --normal-bits B    encode: Draco quantization bits of the base mesh normals, 4 to 16 (default 8)\n"
    "  --texcoord-bits B  encode: Draco quantization bits of the base mesh texture coordinates, 4 to 30\n"
    "                     (default 12)\n"
    "  --skins MODE       encode: what a skinned mesh (without morph targets) stores. keep (default): its\n"
    "                     skin, the mesh compressed with Draco and the joints' tracks coded; bake: its\n"
    "                     sampled frames, for runtimes without skinning. --bpvf and --lossless bake, and\n"
    "                     so does keep where a kept skin cannot reach --error (its weights are bytes)\n"
    "  --targets MODE     encode: what a morph-target mesh (unskinned, one node) stores. keep: its targets,\n"
    "                     compressed, played by its own weights animation; bake: its sampled frames, like a\n"
    "                     skinned mesh. auto (default): where a mesh has at most half as many targets as\n"
    "                     frames, encode both ways and keep the smaller file (with --bpvf, the one with the\n"
    "                     smaller error); never keep them with --lossless (kept targets are lossy)\n"
    "  --json             info, encode, verify: print one JSON object instead of text\n"
    "  -q, --quiet        no progress messages on stderr\n"
    "  -h, --help         this help\n"
    "  --version          print the version\n"
    "\n"
    "Exit status: 0 on success, 1 when the input cannot be processed, 2 on a usage error.\n";

struct Options {
  std::string command;
  std::vector<std::string> inputs;
  std::string output;
  std::string frames;  // decode --frames: the decoded frames as raw floats
  SampleSettings sampling;
  EncodeSettings encode;  // its sampling is `sampling`
  bool rate_given = false;
  bool json = false;
  bool quiet = false;
};

int usage_error(const std::string& message) {
  std::fprintf(stderr, "segmorph: %s (see segmorph --help)\n", message.c_str());
  return 2;
}

int fail(const std::string& file, const Status& status) {
  // Messages may quote bytes of a corrupt file: control characters would break the one-line promise.
  std::string message = status.message();
  for (char& c : message)
    if ((unsigned char)c < 0x20 || c == 0x7f) c = '?';
  std::fprintf(stderr, "segmorph: error: %s: %s\n", file.c_str(), message.c_str());
  return 1;
}

void progress(const Options& options, const std::string& message) {
  if (!options.quiet) std::fprintf(stderr, "segmorph: %s\n", message.c_str());
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\')
      out += '\\', out += char(c);
    else if (c < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    } else
      out += char(c);
  }
  return out + "\"";
}

// Reads `path` into `model`, its warnings as progress.
Status load(const std::string& path, const Options& options, Model& model) {
  progress(options, "reading " + path);
  std::vector<std::string> warnings;
  SEGMORPH_RETURN_IF_ERROR(Model::load(path, model, &warnings));
  for (const std::string& warning : warnings) progress(options, "warning: " + path + ": " + warning);
  return Status::Ok();
}

Progress progress_of(const Options& options) {
  return [&options](const std::string& message) { progress(options, message); };
}

int run_info(const Options& options) {
  const std::string& path = options.inputs[0];
  Model model;
  InfoReport report;
  Status status = load(path, options, model);
  if (status.ok()) status = info(model, options.sampling, report, progress_of(options));
  if (!status.ok()) return fail(path, status);

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
            ",\"connected_components\":" + std::to_string(primitive.connected_components) + ",\"clips\":[";
    text += name + ", mesh " + std::to_string(primitive.mesh) + " primitive " + std::to_string(primitive.primitive) +
            ": " + primitive.kind + ", " + std::to_string(primitive.vertices) + " vertices (" +
            std::to_string(primitive.welded_vertices) + " welded), " + std::to_string(primitive.triangles) +
            " triangles, " + std::to_string(primitive.connected_components) + " connected component" +
            (primitive.connected_components == 1 ? "" : "s") + "\n";
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

int run_bake(const Options& options) {
  const std::string& path = options.inputs[0];
  Model model;
  BakeReport report;
  Status status = load(path, options, model);
  if (status.ok()) status = bake(model, options.sampling, &report, progress_of(options));
  if (!status.ok()) return fail(path, status);
  progress(options, "writing " + options.output);
  status = model.save(options.output);
  if (!status.ok()) return fail(options.output, status);
  progress(options, "baked " + std::to_string(report.nodes) + " animated node" + (report.nodes == 1 ? "" : "s") + ", " +
                        std::to_string(report.frames) + " frames in all");
  return 0;
}

int run_encode(const Options& options) {
  const std::string& path = options.inputs[0];
  Model input, output;
  EncodeReport report;
  Status status = load(path, options, input);
  if (status.ok()) status = encode(input, options.encode, output, &report, progress_of(options));
  if (!status.ok()) return fail(path, status);
  progress(options, "writing " + options.output);
  status = output.save(options.output);
  if (!status.ok()) return fail(options.output, status);

  Model written;
  const size_t bytes = Model::load(options.output, written).ok() ? file_bytes(options.output, written) : 0;
  const double vertex_frames = report.vertex_frames;
  double clusters = 0, e_pi = 0, e_pi_morse = 0, ms[5] = {0, 0, 0, 0, 0};
  for (const StreamReport& r : report.streams) {
    clusters += double(r.clusters);
    e_pi = std::max(e_pi, r.e_pi);
    e_pi_morse = std::max(e_pi_morse, r.e_pi_morse);
    const double stage[5] = {r.ms_segmentation, r.ms_motion, r.ms_prediction, r.ms_rate_control, r.ms_entropy};
    for (int i = 0; i < 5; ++i) ms[i] += stage[i];
  }
  const double bpvf = vertex_frames > 0 ? 8.0 * double(bytes) / vertex_frames : 0;
  if (options.json) {
    std::printf(
        "{\"file\":%s,\"output\":%s,\"bytes\":%zu,\"primitives\":%zu,\"clusters\":%.0f,"
        "\"e_pi_morse\":%.6g,\"e_pi\":%.6g,\"bpvf\":%.4f,\"bpvf_animation\":%.4f,"
        "\"draco_bytes\":%zu,\"animation_bytes\":%zu,\"milliseconds\":{\"segmentation\":%.1f,\"motion\":%.1f,"
        "\"prediction\":%.1f,\"rate_control\":%.1f,\"entropy\":%.1f,\"draco\":%.1f}}\n",
        json_string(path).c_str(), json_string(options.output).c_str(), bytes, report.streams.size(), clusters,
        e_pi_morse, e_pi, bpvf, vertex_frames > 0 ? 8.0 * double(report.animation_bytes) / vertex_frames : 0,
        report.draco_bytes, report.animation_bytes, ms[0], ms[1], ms[2], ms[3], ms[4], report.ms_draco);
  } else {
    std::printf("%s: %zu bytes, %.3f bits per vertex per frame (animation streams %zu bytes, Draco meshes %zu bytes)",
                options.output.c_str(), bytes, bpvf, report.animation_bytes, report.draco_bytes);
    if (report.streams.empty())
      std::printf("\n");
    else
      std::printf(", %zu primitive%s coded as frames, %.0f clusters, E(Pi) %.6f (Morse segmentation %.6f)\n",
                  report.streams.size(), report.streams.size() == 1 ? "" : "s", clusters, e_pi, e_pi_morse);
  }
  return 0;
}

int run_decode(const Options& options) {
  const std::string& path = options.inputs[0];
  Model model;
  DecodeReport report;
  std::vector<DecodedFrames> decoded;
  Status status = load(path, options, model);
  if (status.ok()) status = decode(model, &report, options.frames.empty() ? nullptr : &decoded);
  if (!status.ok()) return fail(path, status);
  if (report.primitives == 0 && report.coded_animations == 0)
    return fail(path, Status(StatusCode::nothing_to_do,
                             "not encoded: it has no SEGMORPH_animation_compression primitive or animation"));
  if (!options.output.empty()) {
    progress(options, "writing " + options.output);
    status = model.save(options.output);
    if (!status.ok()) return fail(options.output, status);
  }
  if (!options.frames.empty()) {
    progress(options, "writing the decoded frames to " + options.frames);
    status = save_decoded_frames(decoded, options.frames);
    if (!status.ok()) return fail(options.frames, status);
  }
  progress(options, "decoded " + std::to_string(report.primitives) + " primitive" + (report.primitives == 1 ? "" : "s") +
                        " and the tracks of " + std::to_string(report.coded_animations) + " animation" +
                        (report.coded_animations == 1 ? "" : "s"));
  return 0;
}

int run_verify(const Options& options) {
  const std::string &original_path = options.inputs[0], &compressed_path = options.inputs[1];
  Model original, compressed;
  Status status = load(original_path, options, original);
  if (!status.ok()) return fail(original_path, status);
  status = load(compressed_path, options, compressed);
  if (!status.ok()) return fail(compressed_path, status);
  VerifyReport report;
  status = verify(original, compressed, options.sampling, report, progress_of(options));
  if (!status.ok()) {
    // Which file is at fault: the original when it cannot be sampled alone.
    InfoReport alone;
    const Status original_status = info(original, options.sampling, alone);
    return original_status.ok() ? fail(compressed_path, status) : fail(original_path, original_status);
  }
  const size_t bytes = file_bytes(compressed_path, compressed);
  const double vertex_frames = report.vertex_frames;
  const double bpvf = vertex_frames > 0 ? 8.0 * double(bytes) / vertex_frames : 0;
  const double bpvf_animation = vertex_frames > 0 ? 8.0 * double(report.animation_bytes) / vertex_frames : 0;
  if (options.json) {
    std::printf(
        "{\"original\":%s,\"compressed\":%s,\"vertices\":%zu,\"frames\":%zu,\"vertex_frames\":%.0f,"
        "\"bytes\":%zu,\"bpvf\":%.4f,\"bpvf_animation\":%.4f,\"kg_percent\":%.6g,\"rmse_over_diag\":%.6g,"
        "\"max_error_over_diag\":%.6g}\n",
        json_string(original_path).c_str(), json_string(compressed_path).c_str(), report.vertices, report.frames,
        vertex_frames, bytes, bpvf, bpvf_animation, report.kg_percent, report.rmse_over_diagonal,
        report.max_error_over_diagonal);
  } else {
    std::printf(
        "%s against %s: %zu vertices, %zu frames, %zu bytes, %.3f bpvf (animation %.3f), KG %.4f %%, "
        "RMSE %.3g and max error %.3g of the diagonal\n",
        compressed_path.c_str(), original_path.c_str(), report.vertices, report.frames, bytes, bpvf, bpvf_animation,
        report.kg_percent, report.rmse_over_diagonal, report.max_error_over_diagonal);
  }
  return 0;
}

int run(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](std::string& out) {
      if (i + 1 >= argc) return false;
      out = argv[++i];
      return true;
    };
    if (arg == "-h" || arg == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (arg == "--version") {
      std::printf("segmorph %d.%d.%d (animation streams %d to %d, track stream %d)\n", SEGMORPH_VERSION_MAJOR,
                  SEGMORPH_VERSION_MINOR, SEGMORPH_VERSION_PATCH, SEGMORPH_STREAM_VERSION_MIN,
                  SEGMORPH_STREAM_VERSION_MAX, SEGMORPH_TRACK_STREAM_VERSION);
      return 0;
    } else if (arg == "-o" || arg == "--output") {
      if (!value(options.output)) return usage_error(arg + " needs a file name");
    } else if (arg == "--frames") {
      if (!value(options.frames)) return usage_error(arg + " needs a file name");
    } else if (arg == "--fps") {
      std::string text;
      if (!value(text)) return usage_error("--fps needs a number");
      char* end = nullptr;
      options.sampling.fps = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end || !(options.sampling.fps > 0) || options.sampling.fps > 1000)
        return usage_error("--fps takes a number of frames per second between 0 and 1000, not '" + text + "'");
    } else if (arg == "--error" || arg == "--bpvf") {
      std::string text;
      if (!value(text)) return usage_error(arg + " needs a number");
      char* end = nullptr;
      const double number = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end || !(number > 0) || number > (arg == "--error" ? 100.0 : 1000.0))
        return usage_error(arg + " takes a positive number, not '" + text + "'");
      if (options.rate_given) return usage_error("give one of --error, --bpvf and --lossless");
      options.rate_given = true;
      options.encode.mode = arg == "--error" ? RateMode::error : RateMode::bpvf;
      options.encode.target = number;
    } else if (arg == "--lossless") {
      if (options.rate_given) return usage_error("give one of --error, --bpvf and --lossless");
      options.rate_given = true;
      options.encode.mode = RateMode::lossless;
    } else if (arg == "--fast-decode") {
      options.encode.fast_decode = true;
    } else if (arg == "--clusters" || arg == "--position-bits" || arg == "--normal-bits" || arg == "--texcoord-bits") {
      const bool clusters = arg == "--clusters";
      long low = 4, high = 30;  // --texcoord-bits
      if (clusters) low = 1, high = 65535;
      // Positions: beyond 22 bits the grid is finer than a float resolves across the bounding box (and Draco's
      // decoded points no longer match their originals; at 30 bits Draco crashed).
      if (arg == "--position-bits") low = 8, high = 22;
      if (arg == "--normal-bits") high = 16;
      std::string text;
      if (!value(text)) return usage_error(arg + " needs a number");
      char* end = nullptr;
      const long number = std::strtol(text.c_str(), &end, 10);
      if (end == text.c_str() || *end || number < low || number > high)
        return usage_error(arg + " takes a whole number from " + std::to_string(low) + " to " + std::to_string(high) +
                           ", not '" + text + "'");
      if (clusters)
        options.encode.clusters = size_t(number);
      else if (arg == "--position-bits")
        options.encode.position_bits = int(number);
      else if (arg == "--normal-bits")
        options.encode.normal_bits = int(number);
      else
        options.encode.texcoord_bits = int(number);
    } else if (arg == "--skins") {
      std::string text;
      if (!value(text)) return usage_error("--skins needs keep or bake");
      if (text == "keep")
        options.encode.skins = EncodeSettings::Skins::keep;
      else if (text == "bake")
        options.encode.skins = EncodeSettings::Skins::bake;
      else
        return usage_error("--skins takes keep or bake, not '" + text + "'");
    } else if (arg == "--targets") {
      std::string text;
      if (!value(text)) return usage_error("--targets needs auto, keep or bake");
      if (text == "auto")
        options.encode.targets = EncodeSettings::Targets::automatic;
      else if (text == "keep")
        options.encode.targets = EncodeSettings::Targets::keep;
      else if (text == "bake")
        options.encode.targets = EncodeSettings::Targets::bake;
      else
        return usage_error("--targets takes auto, keep or bake, not '" + text + "'");
    } else if (arg == "--json") {
      options.json = true;
    } else if (arg == "-q" || arg == "--quiet") {
      options.quiet = true;
    } else if (arg.size() > 1 && arg[0] == '-') {
      return usage_error("unknown option " + arg);
    } else if (options.command.empty()) {
      options.command = arg;
    } else {
      options.inputs.push_back(arg);
    }
  }
  if (options.command.empty()) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  if (options.command == "info") {
    if (options.inputs.size() != 1) return usage_error("info takes one file");
    if (!options.output.empty()) return usage_error("info writes no file; -o is not for it");
    return run_info(options);
  }
  if (options.command == "bake") {
    if (options.inputs.size() != 1) return usage_error("bake takes one input file");
    if (options.output.empty()) return usage_error("bake needs -o OUT");
    if (!has_gltf_extension(options.output)) return usage_error("the output must end in .glb or .gltf");
    return run_bake(options);
  }
  if (!options.frames.empty() && options.command != "decode") return usage_error("--frames is for decode");
  if (options.command == "encode" || options.command == "decode") {
    if (options.inputs.size() != 1) return usage_error(options.command + " takes one input file");
    const bool frames_only = options.command == "decode" && !options.frames.empty() && options.output.empty();
    if (options.output.empty() && !frames_only) return usage_error(options.command + " needs -o OUT");
    if (!frames_only && !has_gltf_extension(options.output)) return usage_error("the output must end in .glb or .gltf");
    options.encode.sampling = options.sampling;
    if (options.encode.targets == EncodeSettings::Targets::keep && options.encode.mode == RateMode::lossless)
      return usage_error("--targets keep is lossy: it cannot be combined with --lossless");
    if (options.encode.fast_decode && options.encode.mode == RateMode::lossless)
      return usage_error("--fast-decode codes lossy residuals: it cannot be combined with --lossless");
    return options.command == "encode" ? run_encode(options) : run_decode(options);
  }
  if (options.command == "verify") {
    if (options.inputs.size() != 2) return usage_error("verify takes two files: ORIGINAL COMPRESSED");
    return run_verify(options);
  }
  return usage_error("unknown command '" + options.command + "'");
}

}  // namespace
}  // namespace segmorph

int main(int argc, char** argv) {
  return segmorph::run(argc, argv);
}
