// segmorph: the command-line tool.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bake.h"
#include "gltf_io.h"
#include "sample.h"
#include "topology.h"

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
    "\n"
    "Options:\n"
    "  -o, --output FILE  output file (.glb: binary; .gltf: JSON with FILE's name .bin beside it)\n"
    "  --fps N            sample every clip on a regular grid of N frames per second; by default the\n"
    "                     union of the clip's key times, or 30 fps where keys are denser than 60 per second\n"
    "  --json             info: print one JSON object instead of text\n"
    "  -q, --quiet        no progress messages on stderr\n"
    "  -h, --help         this help\n"
    "  --version          print the version\n"
    "\n"
    "Exit status: 0 on success, 1 when the input cannot be processed, 2 on a usage error.\n";

struct Options {
  std::string command;
  std::vector<std::string> inputs;
  std::string output;
  SampleSettings sampling;
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
    if (c == '"' || c == '\\') out += '\\', out += char(c);
    else if (c < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    } else out += char(c);
  }
  return out + "\"";
}

std::string node_name(const tinygltf::Model& model, int node) {
  const std::string& name = model.nodes[size_t(node)].name;
  return name.empty() ? "node " + std::to_string(node) : name;
}

// A file loaded, analyzed and sampled. Not copyable: sampled nodes point into scene.
struct SampledFile {
  tinygltf::Model model;
  Scene scene;
  std::vector<SampledNode> sampled;
};

Status load_and_sample(const std::string& path, const Options& options, SampledFile& file) {
  tinygltf::Model& model = file.model;
  Scene& scene = file.scene;
  std::vector<SampledNode>& sampled = file.sampled;
  progress(options, "reading " + path);
  std::vector<std::string> warnings;
  SEGMORPH_RETURN_IF_ERROR(load_gltf(path, model, &warnings));
  for (const std::string& warning : warnings) progress(options, "warning: " + path + ": " + warning);
  SEGMORPH_RETURN_IF_ERROR(analyze_scene(model, scene));
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
      json += "{\"node\":" + std::to_string(animated.node) + ",\"node_name\":" +
              json_string(model.nodes[size_t(animated.node)].name) + ",\"mesh\":" + std::to_string(animated.mesh) +
              ",\"primitive\":" + std::to_string(primitive.primitive) + ",\"kind\":" + json_string(animated.kind()) +
              ",\"vertices\":" + std::to_string(first.vertex_count) + ",\"triangles\":" +
              std::to_string(first.triangle_count()) + ",\"welded_vertices\":" +
              std::to_string(topology.welded_count()) + ",\"connected_components\":" +
              std::to_string(topology.component_count) + ",\"clips\":[";
      text += node_name(model, animated.node) + ", mesh " + std::to_string(animated.mesh) + " primitive " +
              std::to_string(primitive.primitive) + ": " + animated.kind() + ", " +
              std::to_string(first.vertex_count) + " vertices (" + std::to_string(topology.welded_count()) +
              " welded), " + std::to_string(first.triangle_count()) + " triangles, " +
              std::to_string(topology.component_count) + " connected component" +
              (topology.component_count == 1 ? "" : "s") + "\n";
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
        std::snprintf(line, sizeof(line), "%s{\"animation\":%d,\"name\":%s,\"frames\":%zu,\"duration\":%.6g,\"baked_bytes\":%zu}",
                      c ? "," : "", scene.clips[size_t(animated.clips[c])].animation, json_string(name).c_str(),
                      clip.frame_count, duration, bytes);
        json += line;
      }
      json += "]}";
    }
  }
  json += "]}";
  if (options.json) std::printf("%s\n", json.c_str());
  else std::printf("%s: %zu animated primitive%s, %zu animation%s\n%s", path.c_str(), primitive_count,
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
      std::printf("segmorph 0.1.0\n");
      return 0;
    } else if (arg == "-o" || arg == "--output") {
      if (!value(options.output)) return usage_error(arg + " needs a file name");
    } else if (arg == "--fps") {
      std::string text;
      if (!value(text)) return usage_error("--fps needs a number");
      char* end = nullptr;
      options.sampling.fps = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end || !(options.sampling.fps > 0) || options.sampling.fps > 1000)
        return usage_error("--fps takes a number of frames per second between 0 and 1000, not '" + text + "'");
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
  return usage_error("unknown command '" + options.command + "'");
}

}  // namespace
}  // namespace segmorph

int main(int argc, char** argv) { return segmorph::run(argc, argv); }
