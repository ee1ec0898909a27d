// segmorph: the command-line tool.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bake.h"
#include "comparison.h"
#include "compressed.h"
#include "gltf_io.h"
#include "metrics.h"
#include "moving_meshes.h"
#include "sample.h"
#include "segmorph/version.h"
#include "topology.h"
#include "tracks.h"

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
    "  --clusters K       encode: number of motion clusters (default: automatic)\n"
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
  CodecSettings codec;
  DracoSettings draco;  // position_bits 0: compress_model chooses them
  bool rate_given = false;
  enum class Targets { automatic, keep, bake } targets = Targets::automatic;
  enum class Skins { keep, bake } skins = Skins::keep;
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

// A file loaded, analyzed and sampled. Not copyable: sampled nodes point into scene.
struct SampledFile {
  tinygltf::Model model;
  Scene scene;
  std::vector<SampledNode> sampled;  // empty after load_and_analyze alone
  DecodedSizes decoded;              // what an encoded file held
};

// Reads `path`, decodes what is encoded and finds the animated nodes.
Status load_and_analyze(const std::string& path, const Options& options, SampledFile& file) {
  progress(options, "reading " + path);
  std::vector<std::string> warnings;
  SEGMORPH_RETURN_IF_ERROR(load_gltf(path, file.model, &warnings));
  for (const std::string& warning : warnings) progress(options, "warning: " + path + ": " + warning);
  SEGMORPH_RETURN_IF_ERROR(decode_compressed_model(file.model, &file.decoded));
  return analyze_scene(file.model, file.scene);
}

Status load_and_sample(const std::string& path, const Options& options, SampledFile& file) {
  SEGMORPH_RETURN_IF_ERROR(load_and_analyze(path, options, file));
  const tinygltf::Model& model = file.model;
  const Scene& scene = file.scene;
  std::vector<SampledNode>& sampled = file.sampled;
  sampled.resize(scene.animated.size());
  for (size_t i = 0; i < scene.animated.size(); ++i) {
    const AnimatedNode& node = scene.animated[i];
    progress(options, "sampling " + node_name(model, node.node) + " (" + std::to_string(i + 1) + "/" +
                          std::to_string(scene.animated.size()) + "), " + std::to_string(node.clips.size()) + " clip" +
                          (node.clips.size() == 1 ? "" : "s"));
    SEGMORPH_RETURN_IF_ERROR(sample_node(model, scene, node, options.sampling, sampled[i]));
  }
  return Status::Ok();
}

int run_info(const Options& options) {
  const std::string& path = options.inputs[0];
  SampledFile file;
  Status status = load_and_sample(path, options, file);
  if (!status.ok()) return fail(path, status);
  const tinygltf::Model& model = file.model;
  const Scene& scene = file.scene;
  const std::vector<SampledNode>& sampled = file.sampled;

  std::string json = "{\"file\":" + json_string(path) + ",\"primitives\":[";
  std::string text;
  size_t primitive_count = 0;
  for (const SampledNode& node : sampled) {
    const AnimatedNode& animated = *node.node;
    for (const SampledPrimitive& primitive : node.primitives) {
      const FrameSequence& first = primitive.clips[0];
      const WeldedTopology topology = weld_topology(primitive.clips);
      if (primitive_count++) json += ",";
      json += "{\"node\":" + std::to_string(animated.node) +
              ",\"node_name\":" + json_string(model.nodes[size_t(animated.node)].name) +
              ",\"mesh\":" + std::to_string(animated.mesh) + ",\"primitive\":" + std::to_string(primitive.primitive) +
              ",\"kind\":" + json_string(animated.kind()) + ",\"vertices\":" + std::to_string(first.vertex_count) +
              ",\"triangles\":" + std::to_string(first.triangle_count()) +
              ",\"welded_vertices\":" + std::to_string(topology.welded_count()) +
              ",\"connected_components\":" + std::to_string(topology.component_count) + ",\"clips\":[";
      text += node_name(model, animated.node) + ", mesh " + std::to_string(animated.mesh) + " primitive " +
              std::to_string(primitive.primitive) + ": " + animated.kind() + ", " + std::to_string(first.vertex_count) +
              " vertices (" + std::to_string(topology.welded_count()) + " welded), " +
              std::to_string(first.triangle_count()) + " triangles, " + std::to_string(topology.component_count) +
              " connected component" + (topology.component_count == 1 ? "" : "s") + "\n";
      for (size_t c = 0; c < primitive.clips.size(); ++c) {
        const FrameSequence& clip = primitive.clips[c];
        const std::string& name = scene.clips[size_t(animated.clips[c])].name;
        const double duration = clip.times.back() - clip.times.front();
        const size_t bytes = clip.frame_count * clip.vertex_count * 3 * sizeof(float);
        char line[512];
        std::snprintf(line, sizeof(line), "  clip %d %s: %zu frames, %.3f s, baked frames %zu bytes\n",
                      scene.clips[size_t(animated.clips[c])].animation, json_string(name).c_str(), clip.frame_count,
                      duration, bytes);
        text += line;
        std::snprintf(line, sizeof(line),
                      "%s{\"animation\":%d,\"name\":%s,\"frames\":%zu,\"duration\":%.6g,\"baked_bytes\":%zu}",
                      c ? "," : "", scene.clips[size_t(animated.clips[c])].animation, json_string(name).c_str(),
                      clip.frame_count, duration, bytes);
        json += line;
      }
      json += "]}";
    }
  }
  json += "]}";
  if (options.json)
    std::printf("%s\n", json.c_str());
  else
    std::printf("%s: %zu animated primitive%s, %zu animation%s\n%s", path.c_str(), primitive_count,
                primitive_count == 1 ? "" : "s", model.animations.size(), model.animations.size() == 1 ? "" : "s",
                text.c_str());
  return 0;
}

int run_bake(const Options& options) {
  const std::string& path = options.inputs[0];
  SampledFile file;
  Status status = load_and_sample(path, options, file);
  if (!status.ok()) return fail(path, status);
  const std::vector<SampledNode>& sampled = file.sampled;
  status = bake_model(file.model, file.scene, sampled);
  if (!status.ok()) return fail(path, status);
  progress(options, "writing " + options.output);
  status = save_gltf(file.model, options.output);
  if (!status.ok()) return fail(options.output, status);
  size_t frames = 0;
  for (const SampledNode& node : sampled)
    for (const FrameSequence& clip : node.primitives[0].clips) frames += clip.frame_count;
  progress(options, "baked " + std::to_string(sampled.size()) + " animated node" + (sampled.size() == 1 ? "" : "s") +
                        ", " + std::to_string(frames) + " frames in all");
  return 0;
}

// Bytes of a glTF file and of the files its buffers and images name (a .gltf's .bin).
size_t file_bytes(const std::string& path, const tinygltf::Model& model) {
  auto size_of = [](const std::string& file) -> size_t {
    std::FILE* handle = std::fopen(file.c_str(), "rb");
    if (!handle) return 0;
    std::fseek(handle, 0, SEEK_END);
    const long size = std::ftell(handle);
    std::fclose(handle);
    return size > 0 ? size_t(size) : 0;
  };
  size_t total = size_of(path);
  const size_t slash = path.find_last_of('/');
  const std::string directory = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  for (const tinygltf::Buffer& buffer : model.buffers)
    if (!buffer.uri.empty() && buffer.uri.rfind("data:", 0) != 0) total += size_of(directory + buffer.uri);
  for (const tinygltf::Image& image : model.images)
    if (!image.uri.empty() && image.uri.rfind("data:", 0) != 0) total += size_of(directory + image.uri);
  return total;
}

// Whether encode keeps the morph targets of `node` (see --targets): an unskinned morph mesh that only this node
// uses, in a lossy encode, with at most half as many targets as frames unless asked to keep them.
bool keeps_targets(const tinygltf::Model& model, const AnimatedNode& node, const SampledNode& sampled,
                   const Options& options) {
  if (options.targets == Options::Targets::bake || options.codec.mode == RateMode::lossless) return false;
  if (!node.morphed || node.skin >= 0) return false;
  size_t users = 0;
  for (const tinygltf::Node& other : model.nodes) users += other.mesh == node.mesh;
  if (users != 1) return false;
  if (options.targets == Options::Targets::keep) return true;
  size_t frames = 0;
  for (const FrameSequence& clip : sampled.primitives[0].clips) frames += clip.frame_count;
  return 2 * sampled.primitives[0].target_deltas.size() <= frames;
}

struct Encoded {
  tinygltf::Model model;
  CompressReport report;
  double kept_skins_floor = 0;  // when kept skins cannot reach the --error target: the KG % they stay at
};

// A --bpvf result within this factor of its target meets it (the codec aims a little below).
constexpr double kBpvfTolerance = 1.05;

// Bits per vertex per frame are counted over Σ V × F of the sampled primitives and clips.
double vertex_frames(const std::vector<SampledNode>& sampled) {
  double total = 0;
  for (const SampledNode& node : sampled)
    for (const SampledPrimitive& primitive : node.primitives)
      for (const FrameSequence& clip : primitive.clips) total += double(clip.vertex_count) * double(clip.frame_count);
  return total;
}

// Whether encode keeps the skin of `node` (see --skins): a skinned mesh without morph targets, with an error
// target (a kept skin's error is searched for; --bpvf rate control and --lossless are the codec's, on baked frames).
bool keeps_skin(const AnimatedNode& node, const Options& options) {
  return options.skins == Options::Skins::keep && options.codec.mode == RateMode::error && node.skin >= 0 &&
         !node.morphed;
}

// Draco's share of the KG error target in the meshes compress_moving_meshes takes.
constexpr double kMovingMeshErrorShare = 0.6;
// The tracks' quantization distance (TrackPrecision) where nothing measured depends on it: this fraction of the
// error target times the scene's diagonal, about what the search below settles on for kept skins.
constexpr double kTrackDistanceRatio = 0.25;
// The search for kept skins: KG within kSearchGoal of the target; a bracket in at most kSearchBracketRounds
// doublings or halvings, then kSearchHalvings bisections of it (in log distance).
constexpr double kSearchGoal = 0.99;
constexpr int kSearchBracketRounds = 8, kSearchHalvings = 4;

// The KG error target (%) the meshes and tracks outside the codec aim at: --error's, else the default one.
double error_target(const CodecSettings& codec) {
  return codec.mode == RateMode::error ? codec.target : CodecSettings().target;
}

// The worst KG error (%) of `encoded` against the file it was encoded from, as verify measures it.
Status measured_kg(const SampledFile& file, tinygltf::Model encoded, double& kg) {
  SEGMORPH_RETURN_IF_ERROR(decode_compressed_model(encoded));
  Scene scene;
  SEGMORPH_RETURN_IF_ERROR(analyze_scene(encoded, scene));
  AnimationComparison comparison;
  SEGMORPH_RETURN_IF_ERROR(compare_animation(file.model, file.scene, file.sampled, encoded, scene, comparison));
  kg = comparison.worst.kg_percent;
  return Status::Ok();
}

// Codes the tracks of `out.model` (whose kept skins depend on them): with --error, the coarsest quantization
// distance (a factor of 2 apart, then halved 4 times) whose measured KG is within the target; otherwise the rule
// of kTrackDistanceRatio.
Status encode_tracks_for(const SampledFile& file, const CodecSettings& codec, bool measured, Encoded& out) {
  const double first = kTrackDistanceRatio * error_target(codec) / 100 * scene_diagonal(out.model);
  auto encode = [&](double distance, Encoded& result, TrackReport& report) {
    result.model = out.model;
    report = TrackReport();
    return compress_tracks(result.model, TrackPrecision{distance}, report);
  };
  TrackReport report;
  if (!measured || codec.mode != RateMode::error) {
    SEGMORPH_RETURN_IF_ERROR(encode(first, out, report));
    out.report.animation_bytes += report.bytes;
    return Status::Ok();
  }
  const double goal = kSearchGoal * codec.target;
  Encoded candidate;
  double kg = 0, within = 0, beyond = 0;  // distances known within and beyond the goal (0: none yet)
  auto within_goal = [&](double distance, bool& ok) {
    SEGMORPH_RETURN_IF_ERROR(encode(distance, candidate, report));
    SEGMORPH_RETURN_IF_ERROR(measured_kg(file, candidate.model, kg));
    ok = kg <= goal;
    return Status::Ok();
  };
  bool ok = false;
  double distance = first;
  for (int round = 0; round < kSearchBracketRounds; ++round) {
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance, ok));
    (ok ? within : beyond) = distance;
    if (within > 0 && beyond > 0) break;
    distance = ok ? distance * 2 : distance / 2;
  }
  if (within == 0) {  // the error is not the tracks' (a kept skin's weights are bytes): the caller bakes instead
    out.kept_skins_floor = kg;
    return Status::Ok();
  }
  for (int round = 0; beyond > 0 && round < kSearchHalvings; ++round) {
    distance = std::sqrt(within * beyond);
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance, ok));
    (ok ? within : beyond) = distance;
  }
  SEGMORPH_RETURN_IF_ERROR(encode(within, out, report));
  out.report.animation_bytes += report.bytes;
  return Status::Ok();
}

// Encodes a copy of file's model with `codec`: the nodes `keep` marks keep their morph targets, skinned nodes whose
// skin is kept are compressed with the meshes that move rigidly, the others are baked; then the tracks are coded.
Status encode_model_once(const SampledFile& file, const std::vector<bool>& keep, const CodecSettings& codec,
                         const Options& options, Encoded& out) {
  out.model = file.model;
  out.report = CompressReport();
  out.kept_skins_floor = 0;
  std::vector<SampledNode> kept, baked;
  std::vector<int> kept_skins;
  for (size_t i = 0; i < file.sampled.size(); ++i) {
    if (keeps_skin(*file.sampled[i].node, options))
      kept_skins.push_back(file.sampled[i].node->node);
    else
      (keep[i] ? kept : baked).push_back(file.sampled[i]);
  }
  const auto report_progress = [&](const std::string& message) { progress(options, message); };
  SEGMORPH_RETURN_IF_ERROR(compress_targets(out.model, kept, codec, options.draco, out.report, report_progress));
  SEGMORPH_RETURN_IF_ERROR(bake_model(out.model, file.scene, baked));
  SEGMORPH_RETURN_IF_ERROR(compress_model(out.model, baked, codec, options.draco, out.report, report_progress));
  if (codec.mode == RateMode::lossless) return Status::Ok();
  // Draco's RMS error is half its step: a step of 2 × share × E / 100 of a mesh's spread is its share of KG E %.
  const double step_ratio = 2 * kMovingMeshErrorShare * error_target(codec) / 100;
  MovingMeshReport meshes;
  // A rigid part's error counts against the whole it belongs to: a figure's spread is about a quarter of its
  // diagonal.
  const double rigid_spread = scene_diagonal(out.model) / 4;
  SEGMORPH_RETURN_IF_ERROR(compress_moving_meshes(out.model, moving_meshes(out.model, kept_skins), options.draco,
                                                  step_ratio, rigid_spread, meshes));
  out.report.draco_bytes += meshes.bytes;
  progress(options, kept_skins.empty() ? "coding the animation tracks"
                                       : "coding the animation tracks, measuring the kept skins' error");
  return encode_tracks_for(file, codec, !kept_skins.empty(), out);
}

// encode_model_once, and with --bpvf a second time: the rate is of the whole file, and the codec budgets only its
// streams and base meshes, so the rest (JSON, images, other meshes and animations, kept weights), measured on the
// first encode, comes off the codec's target.
Status encode_model(const SampledFile& file, const std::vector<bool>& keep, const Options& options, Encoded& out) {
  SEGMORPH_RETURN_IF_ERROR(encode_model_once(file, keep, options.codec, options, out));
  if (out.kept_skins_floor > 0) {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "kept skins stay at KG %.4f %% even with the finest tracks, above --error %g (their weights are "
                  "bytes): baking them instead",
                  out.kept_skins_floor, options.codec.target);
    progress(options, line);
    Options baked = options;
    baked.skins = Options::Skins::bake;
    SEGMORPH_RETURN_IF_ERROR(encode_model_once(file, keep, options.codec, baked, out));
  }
  if (options.codec.mode != RateMode::bpvf) return Status::Ok();
  const double frames = vertex_frames(file.sampled);
  const size_t coded = out.report.draco_bytes + out.report.animation_bytes, whole = glb_size(out.model);
  const double rest = 8.0 * double(whole > coded ? whole - coded : 0) / frames;
  char figures[200];
  std::snprintf(figures, sizeof(figures), "%.3f bpvf, of which %.3f outside the animation streams and base meshes",
                8.0 * double(whole) / frames, rest);
  if (rest >= options.codec.target) {
    char target[32];
    std::snprintf(target, sizeof(target), "%g", options.codec.target);
    return Status(StatusCode::invalid_argument, std::string("--bpvf ") + target +
                                                    " is below what the rest of the file takes alone: the first "
                                                    "encode came to " +
                                                    figures);
  }
  progress(options, std::string("first encode: ") + figures + "; encoding again for the whole file's rate");
  CodecSettings codec = options.codec;
  codec.target -= rest;
  SEGMORPH_RETURN_IF_ERROR(encode_model_once(file, keep, codec, options, out));
  const double reached = 8.0 * double(glb_size(out.model)) / frames;
  if (reached > kBpvfTolerance * options.codec.target) {
    char line[200];
    std::snprintf(line, sizeof(line), "warning: --bpvf %g is out of reach for this file: it comes to %.3f bpvf",
                  options.codec.target, reached);
    progress(options, line);
  }
  return Status::Ok();
}

// The worst KG error (%) the encoder reports over the encoded primitives.
double worst_kg(const CompressReport& report) {
  double worst = 0;
  for (const EncodeReport& primitive : report.primitives) worst = std::max(worst, primitive.kg_percent);
  return worst;
}

int run_encode(const Options& options) {
  const std::string& path = options.inputs[0];
  SampledFile file;
  Status status = load_and_sample(path, options, file);
  if (!status.ok()) return fail(path, status);
  // Morph-target meshes that keep their targets are compressed where they are; the others are baked first. With
  // --targets auto, a file where some mesh could keep them is encoded both ways; the smaller file is kept (with
  // --bpvf, where both come to the target's size, the one with the smaller worst error).
  std::vector<bool> keep(file.sampled.size());
  bool any_kept = false;
  for (size_t i = 0; i < file.sampled.size(); ++i)
    any_kept |= keep[i] = keeps_targets(file.model, *file.sampled[i].node, file.sampled[i], options);
  Encoded encoded;
  status = encode_model(file, keep, options, encoded);
  if (any_kept && options.targets == Options::Targets::automatic) {
    // Either variant may be refused (a --bpvf target below what its rest takes); the other then stands alone.
    Encoded baked;
    progress(options, "encoding again with the morph targets baked, to compare");
    const Status baked_status = encode_model(file, std::vector<bool>(keep.size(), false), options, baked);
    if (!status.ok() && baked_status.ok()) {
      progress(options, "keeping the morph targets was refused (" + status.message() + "); the baked file stands");
      encoded = std::move(baked), status = baked_status;
    } else if (status.ok() && baked_status.ok()) {
      const size_t kept_size = glb_size(encoded.model), baked_size = glb_size(baked.model);
      const double kept_kg = worst_kg(encoded.report), baked_kg = worst_kg(baked.report);
      char line[160];
      std::snprintf(line, sizeof(line), "morph targets kept: %zu bytes, KG %.4f %%; baked: %zu bytes, KG %.4f %%",
                    kept_size, kept_kg, baked_size, baked_kg);
      progress(options, line);
      // With --bpvf: the smaller error among the files within the target, else the smaller file.
      const double budget = kBpvfTolerance * options.codec.target * vertex_frames(file.sampled) / 8;
      const bool kept_fits = double(kept_size) <= budget, baked_fits = double(baked_size) <= budget;
      const bool take_baked = options.codec.mode != RateMode::bpvf ? baked_size < kept_size
                              : kept_fits != baked_fits            ? baked_fits
                              : kept_fits                          ? baked_kg < kept_kg
                                                                   : baked_size < kept_size;
      if (take_baked) encoded = std::move(baked);
    }
  }
  if (!status.ok()) return fail(path, status);
  file.model = std::move(encoded.model);
  const CompressReport& report = encoded.report;
  progress(options, "writing " + options.output);
  status = save_gltf(file.model, options.output);
  if (!status.ok()) return fail(options.output, status);

  tinygltf::Model written;
  const size_t bytes = load_gltf(options.output, written).ok() ? file_bytes(options.output, written) : 0;
  const double vertex_frames = segmorph::vertex_frames(file.sampled);
  double clusters = 0, e_pi = 0, e_pi_before = 0, ms[5] = {0, 0, 0, 0, 0};
  for (const EncodeReport& r : report.primitives) {
    clusters += double(r.clusters);
    e_pi = std::max(e_pi, r.e_pi);
    e_pi_before = std::max(e_pi_before, r.e_pi_before_refinement);
    const double stage[5] = {r.ms_segmentation, r.ms_motion, r.ms_prediction, r.ms_rate_control, r.ms_entropy};
    for (int i = 0; i < 5; ++i) ms[i] += stage[i];
  }
  const double bpvf = vertex_frames > 0 ? 8.0 * double(bytes) / vertex_frames : 0;
  if (options.json) {
    std::printf(
        "{\"file\":%s,\"output\":%s,\"bytes\":%zu,\"primitives\":%zu,\"clusters\":%.0f,"
        "\"e_pi_before_refinement\":%.6g,\"e_pi\":%.6g,\"bpvf\":%.4f,\"bpvf_animation\":%.4f,"
        "\"draco_bytes\":%zu,\"animation_bytes\":%zu,\"milliseconds\":{\"segmentation\":%.1f,\"motion\":%.1f,"
        "\"prediction\":%.1f,\"rate_control\":%.1f,\"entropy\":%.1f,\"draco\":%.1f}}\n",
        json_string(path).c_str(), json_string(options.output).c_str(), bytes, report.primitives.size(), clusters,
        e_pi_before, e_pi, bpvf, vertex_frames > 0 ? 8.0 * double(report.animation_bytes) / vertex_frames : 0,
        report.draco_bytes, report.animation_bytes, ms[0], ms[1], ms[2], ms[3], ms[4], report.ms_draco);
  } else {
    std::printf("%s: %zu bytes, %.3f bits per vertex per frame (animation streams %zu bytes, Draco meshes %zu bytes)",
                options.output.c_str(), bytes, bpvf, report.animation_bytes, report.draco_bytes);
    if (report.primitives.empty())
      std::printf("\n");
    else
      std::printf(", %zu primitive%s coded as frames, %.0f clusters, E(Pi) %.6f (before refinement %.6f)\n",
                  report.primitives.size(), report.primitives.size() == 1 ? "" : "s", clusters, e_pi, e_pi_before);
  }
  return 0;
}

// The frames of every compressed primitive as decode --frames writes them: little-endian float32, primitive after
// primitive, clip after clip, frame after frame.
Status save_frames(const std::vector<DecodedFrames>& decoded, const std::string& path) {
  static_assert(sizeof(float) == 4, "binary32 floats");
  const uint16_t probe = 1;
  uint8_t first;
  std::memcpy(&first, &probe, 1);
  if (first != 1) return Status(StatusCode::unsupported, "--frames writes little-endian floats: this is a big-endian machine");
  size_t floats = 0;
  for (const DecodedFrames& primitive : decoded)
    for (const FrameSequence& clip : primitive.clips) floats += clip.positions.size();
  std::vector<float> all;
  all.reserve(floats);
  for (const DecodedFrames& primitive : decoded)
    for (const FrameSequence& clip : primitive.clips) all.insert(all.end(), clip.positions.begin(), clip.positions.end());
  return save_file(path, all.data(), all.size() * sizeof(float));
}

int run_decode(const Options& options) {
  const std::string& path = options.inputs[0];
  tinygltf::Model model;
  std::vector<std::string> warnings;
  progress(options, "reading " + path);
  Status status = load_gltf(path, model, &warnings);
  DecodedSizes sizes;
  std::vector<DecodedFrames> decoded;
  if (status.ok()) status = decode_compressed_model(model, &sizes, options.frames.empty() ? nullptr : &decoded);
  if (!status.ok()) return fail(path, status);
  if (sizes.primitives == 0 && sizes.coded_animations == 0)
    return fail(path, Status(StatusCode::nothing_to_do,
                             "not encoded: it has no SEGMORPH_animation_compression primitive or animation"));
  if (!options.output.empty()) {
    progress(options, "writing " + options.output);
    status = save_gltf(model, options.output);
    if (!status.ok()) return fail(options.output, status);
  }
  if (!options.frames.empty()) {
    progress(options, "writing the decoded frames to " + options.frames);
    status = save_frames(decoded, options.frames);
    if (!status.ok()) return fail(options.frames, status);
  }
  progress(options, "decoded " + std::to_string(sizes.primitives) + " primitive" + (sizes.primitives == 1 ? "" : "s") +
                        " and the tracks of " + std::to_string(sizes.coded_animations) + " animation" +
                        (sizes.coded_animations == 1 ? "" : "s"));
  return 0;
}

int run_verify(const Options& options) {
  SampledFile original, compressed;
  Status status = load_and_sample(options.inputs[0], options, original);
  if (!status.ok()) return fail(options.inputs[0], status);
  status = load_and_analyze(options.inputs[1], options, compressed);
  AnimationComparison comparison;
  if (status.ok()) {
    progress(options, "comparing at the frame times of " + options.inputs[0]);
    status = compare_animation(original.model, original.scene, original.sampled, compressed.model, compressed.scene,
                               comparison);
  }
  if (!status.ok()) return fail(options.inputs[1], status);

  const ErrorMetrics& worst = comparison.worst;
  const double vertex_frames = comparison.vertex_frames;
  const size_t bytes = file_bytes(options.inputs[1], compressed.model);
  const double bpvf = vertex_frames > 0 ? 8.0 * double(bytes) / vertex_frames : 0;
  const double bpvf_animation =
      vertex_frames > 0 ? 8.0 * double(compressed.decoded.animation_bytes) / vertex_frames : 0;
  if (options.json) {
    std::printf(
        "{\"original\":%s,\"compressed\":%s,\"vertices\":%zu,\"frames\":%zu,\"vertex_frames\":%.0f,"
        "\"bytes\":%zu,\"bpvf\":%.4f,\"bpvf_animation\":%.4f,\"kg_percent\":%.6g,\"rmse_over_diag\":%.6g,"
        "\"max_error_over_diag\":%.6g}\n",
        json_string(options.inputs[0]).c_str(), json_string(options.inputs[1]).c_str(), comparison.vertices,
        comparison.frames, vertex_frames, bytes, bpvf, bpvf_animation, worst.kg_percent, worst.rmse_over_diagonal,
        worst.max_error_over_diagonal);
  } else {
    std::printf(
        "%s against %s: %zu vertices, %zu frames, %zu bytes, %.3f bpvf (animation %.3f), KG %.4f %%, "
        "RMSE %.3g and max error %.3g of the diagonal\n",
        options.inputs[1].c_str(), options.inputs[0].c_str(), comparison.vertices, comparison.frames, bytes, bpvf,
        bpvf_animation, worst.kg_percent, worst.rmse_over_diagonal, worst.max_error_over_diagonal);
  }
  return 0;
}

int run(int argc, char** argv) {
  Options options;
  options.draco.position_bits = 0;
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
      options.codec.mode = arg == "--error" ? RateMode::error : RateMode::bpvf;
      options.codec.target = number;
    } else if (arg == "--lossless") {
      if (options.rate_given) return usage_error("give one of --error, --bpvf and --lossless");
      options.rate_given = true;
      options.codec.mode = RateMode::lossless;
    } else if (arg == "--fast-decode") {
      options.codec.table_residuals = true;
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
        options.codec.clusters = size_t(number);
      else if (arg == "--position-bits")
        options.draco.position_bits = int(number);
      else if (arg == "--normal-bits")
        options.draco.normal_bits = int(number);
      else
        options.draco.texcoord_bits = int(number);
    } else if (arg == "--skins") {
      std::string text;
      if (!value(text)) return usage_error("--skins needs keep or bake");
      if (text == "keep")
        options.skins = Options::Skins::keep;
      else if (text == "bake")
        options.skins = Options::Skins::bake;
      else
        return usage_error("--skins takes keep or bake, not '" + text + "'");
    } else if (arg == "--targets") {
      std::string text;
      if (!value(text)) return usage_error("--targets needs auto, keep or bake");
      if (text == "auto")
        options.targets = Options::Targets::automatic;
      else if (text == "keep")
        options.targets = Options::Targets::keep;
      else if (text == "bake")
        options.targets = Options::Targets::bake;
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
    if (options.targets == Options::Targets::keep && options.codec.mode == RateMode::lossless)
      return usage_error("--targets keep is lossy: it cannot be combined with --lossless");
    if (options.codec.table_residuals && options.codec.mode == RateMode::lossless)
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
