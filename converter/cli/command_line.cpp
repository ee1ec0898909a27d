#include "cli/command_line.h"

#include <cstdlib>
#include <cstring>

namespace segmorph {
namespace {

enum Command : unsigned { kInfo = 1, kBake = 2, kEncode = 4, kDecode = 8, kVerify = 16, kEvery = 31 };
const char* const kCommandNames[] = {"info", "bake", "encode", "decode", "verify"};

const char* const kCommands =
    "usage: segmorph <command> [options]\n"
    "\n"
    "Commands:\n"
    "  info FILE [--cache C] [--json] [--fps N]\n"
    "      List the animated primitives of a glTF file: vertices, triangles, kind (morph, skinned or\n"
    "      morph+skinned), clips with their frame counts and durations, connected components, and the\n"
    "      size of the baked frames (V x F x 3 floats).\n"
    "  bake IN -o OUT [--cache C] [--fps N]\n"
    "      Write OUT (.glb or .gltf) with every animated primitive baked into POSITION and NORMAL morph\n"
    "      targets, one per frame, played by one weights animation per clip (sparse one-hot weights).\n"
    "      Skins and joint channels that no longer move anything are removed; everything else is kept.\n"
    "  encode IN -o OUT [--cache C] [--error E | --bpvf R | --lossless] [--fps N] [--clusters K]\n"
    "         [--position-bits B] [--normal-bits B] [--texcoord-bits B] [--skins keep|bake]\n"
    "         [--targets auto|keep|bake] [--fast-decode] [--max-stream-version N] [--gpu-playable] [--json]\n"
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
    "  verify ORIGINAL COMPRESSED [--cache C] [--cache2 C] [--max-error E] [--max-bpvf R] [--json] [--fps N]\n"
    "      Compare the animation of two files (either may be encoded, baked, original or written by another\n"
    "      tool: primitives and vertices are paired by trajectory, COMPRESSED is sampled at ORIGINAL's frame\n"
    "      times): bytes, bits per vertex per frame, KG error, RMSE and maximum error over the bounding-box\n"
    "      diagonal, for the worst primitive and for each. With --max-error or --max-bpvf, a gate: exit\n"
    "      status 1 when COMPRESSED is above a bound. Exit status 1 too when a primitive of ORIGINAL has no\n"
    "      counterpart in COMPRESSED (none follows its trajectories: the files play different animations).\n"
    "\n"
    "bake, encode and decode also run as a batch: IN... --output-dir DIR [--jobs N] (see --output-dir).\n"
    "An input named - is the standard input (a .glb, or a .gltf whose other files are found from the working\n"
    "directory).\n"
    "The input of info, bake, encode and verify may also be a vertex cache: an OBJ sequence (a folder, or a name\n"
    "with %04d), or a base mesh (.obj, .glb, .gltf) with its PC2 or MDD point cache (--cache); it reads as the\n"
    "glTF bake would write for it (docs/caches.md).\n"
    "\n"
    "Options (an option's value may also follow '=': --error=0.5):\n";

const char* const kExitStatus =
    "\nExit status: 0 on success, 1 when the input cannot be processed (or verify finds it above --max-error\n"
    "or --max-bpvf), 2 on a usage error.\n";

// The value an option takes.
enum class Kind {
  flag,    // none
  text,    // any text (a file name)
  number,  // a number in (low, high] (low_open) or [low, high]
  whole,   // a whole number in [low, high]
  choice,  // one of `choices`
};

struct Option {
  const char* name;   // --name
  const char* alias;  // -n, or nullptr
  const char* argument;  // the value's name in --help ("N", "FILE"); a choice shows its choices
  unsigned commands;  // those that take it
  Kind kind;
  double low, high;
  bool low_open;
  const char* choices;  // choice: "keep|bake"
  int group;            // options of one group > 0 exclude each other
  const char* help;     // "{range}" stands for the range
  void (*apply)(CommandLine& line, const std::string& text, double number);
};

// Positions: beyond 22 bits the grid is finer than a float resolves across the bounding box (and Draco's decoded
// points no longer match their originals; at 30 bits Draco crashed).
const Option kOptions[] = {
    {"--output", "-o", "FILE", kBake | kEncode | kDecode, Kind::text, 0, 0, false, nullptr, 0,
     "output file (.glb: binary; .gltf: JSON with FILE's name .bin beside it; -: a .glb on the standard output, "
     "the report then on stderr)",
     [](CommandLine& line, const std::string& text, double) { line.output = text; }},
    {"--force", nullptr, nullptr, kBake | kEncode | kDecode, Kind::flag, 0, 0, false, nullptr, 0,
     "replace the output even where it is the input or a file the input reads (its .bin, its images); the "
     "replacement is atomic",
     [](CommandLine& line, const std::string&, double) { line.force = true; }},
    {"--output-dir", nullptr, "DIR", kBake | kEncode | kDecode, Kind::text, 0, 0, false, nullptr, 0,
     "a batch: take any number of inputs (files, and the .glb and .gltf files under folders) and write each to "
     "DIR (created if missing) under its own name with the extension .glb, one report per file in input order, "
     "then a summary line; a file that fails stops no other (exit status 1 when any failed). Two inputs that would "
     "write the same output are refused before any work",
     [](CommandLine& line, const std::string& text, double) { line.output_directory = text; }},
    {"--jobs", "-j", "N", kBake | kEncode | kDecode, Kind::whole, 1, 256, false, nullptr, 0,
     "with --output-dir: files processed at once, each in a process of its own, {range} (default 1); the outputs "
     "are the bytes single runs write",
     [](CommandLine& line, const std::string&, double number) { line.jobs = int(number); }},
    {"--frames", nullptr, "FILE", kDecode, Kind::text, 0, 0, false, nullptr, 0,
     "also write the decoded frames as raw float32 (see decode)",
     [](CommandLine& line, const std::string& text, double) { line.frames = text; }},
    {"--cache", nullptr, "FILE", kInfo | kBake | kEncode | kVerify, Kind::text, 0, 0, false, nullptr, 0,
     "a PC2 or MDD point cache that moves the input, its base mesh: an .obj (the cache's points are its v lines, in "
     "order) or a .glb or .gltf of one unanimated mesh (its vertices, primitive after primitive); with verify, the "
     "cache of ORIGINAL. An input that is a folder, or a name with one %d or %04d (frames/walk_%04d.obj), is an OBJ "
     "sequence: one .obj per frame, ordered by the number in their names (docs/caches.md)",
     [](CommandLine& line, const std::string& text, double) { line.cache = text; }},
    {"--z-up", nullptr, nullptr, kInfo | kBake | kEncode | kVerify, Kind::flag, 0, 0, false, nullptr, 0,
     "the vertex caches and their OBJ meshes are Z up (Blender's own axes; its MDD exporter writes nothing else): "
     "turn them to glTF's Y up, (x, y, z) to (x, z, -y). A glTF base mesh is Y up already and is not turned",
     [](CommandLine& line, const std::string&, double) { line.z_up = true; }},
    {"--cache2", nullptr, "FILE", kVerify, Kind::text, 0, 0, false, nullptr, 0,
     "the point cache that moves COMPRESSED, its base mesh (see --cache)",
     [](CommandLine& line, const std::string& text, double) { line.cache2 = text; }},
    {"--fps", nullptr, "N", kInfo | kBake | kEncode | kVerify, Kind::number, 0, 1000, true, nullptr, 0,
     "sample every clip on a regular grid of N frames per second, {range}; by default the union of the clip's key "
     "times, or 30 fps where keys are denser than 60 per second. For an OBJ sequence or a PC2 cache, N is instead "
     "their frame rate (default 30), and every frame is kept; an MDD cache has its own times",
     [](CommandLine& line, const std::string&, double number) { line.sampling.fps = number; }},
    {"--error", nullptr, "E", kEncode, Kind::number, 0, 100, true, nullptr, 1,
     "KG error target in percent, {range} (default 0.15)",
     [](CommandLine& line, const std::string&, double number) {
       line.encode.mode = RateMode::error;
       line.encode.target = number;
     }},
    {"--bpvf", nullptr, "R", kEncode, Kind::number, 0, 1000, true, nullptr, 1,
     "target bits per vertex per frame of the whole output, images and JSON included, {range} (it encodes twice: "
     "the first encode measures what the rest of the file takes)",
     [](CommandLine& line, const std::string&, double number) {
       line.encode.mode = RateMode::bpvf;
       line.encode.target = number;
     }},
    {"--lossless", nullptr, nullptr, kEncode, Kind::flag, 0, 0, false, nullptr, 1,
     "restore the sampled frames bit for bit",
     [](CommandLine& line, const std::string&, double) { line.encode.mode = RateMode::lossless; }},
    {"--threads", "-t", "N", kEncode | kDecode, Kind::whole, 0, 1024, false, nullptr, 0,
     "threads for the work that splits: encode's stages (the eigenvectors of a mesh's connected parts, side by side, "
     "and of a part above 60,000 vertices, the cluster-count search, the motion fits, refinement and cluster weights, "
     "each frame's reference, rate control's measurements and motion step trials, the version-4 bases (the stream's "
     "beside the residual coding), the decodes and the comparison with the input at the end), decode's frames of "
     "version-4 streams; {range}; "
     "0 (default): every core, shared by the files of a batch that run at once (--jobs). The output is the same "
     "bytes for every N",
     [](CommandLine& line, const std::string&, double number) {
       line.encode.threads = line.decode.threads = size_t(number);
     }},
    {"--fast-decode", nullptr, nullptr, kEncode, Kind::flag, 0, 0, false, nullptr, 0,
     "code the residuals for decoding speed (stream version 2, its table code): about a third less decoding time, "
     "files 1 to 11 % larger on the three classic sequences (docs/codec.md). Not with --lossless",
     [](CommandLine& line, const std::string&, double) { line.encode.fast_decode = true; }},
    {"--max-stream-version", nullptr, "N", kEncode, Kind::whole, 1, 4, false, nullptr, 0,
     "write animation streams of at most version N, {range} (default 4), for players whose decoder reads no later "
     "one: version 3 adds frame references and the motion's and the weights' contexts, version 4 the residuals as "
     "temporal bases and coefficients (with --error targets, not with --fast-decode), which the encoder uses only "
     "where they make a stream smaller; --fast-decode needs 2",
     [](CommandLine& line, const std::string&, double number) { line.encode.max_stream_version = int(number); }},
    {"--gpu-playable", nullptr, nullptr, kEncode, Kind::flag, 0, 0, false, nullptr, 0,
     "write every stream of clips as version 4, whose model players evaluate on the GPU (the three.js plugin's "
     "default playback, docs/runtime.md), even where version 3 would be smaller (docs/codec.md: the cost); a "
     "primitive that cannot have one at the error target fails the encode; kept morph targets are coded as without "
     "it (they play as morph targets). With --error targets only: not with --bpvf, --lossless, --fast-decode or "
     "--max-stream-version below 4",
     [](CommandLine& line, const std::string&, double) { line.encode.gpu_playable = true; }},
    {"--clusters", nullptr, "K", kEncode, Kind::whole, 1, 65535, false, nullptr, 0,
     "number of motion clusters, {range}, at most what the segmentation gives a primitive (more is said and coded "
     "with that many; default: automatic)",
     [](CommandLine& line, const std::string&, double number) { line.encode.clusters = size_t(number); }},
    {"--position-bits", nullptr, "B", kEncode, Kind::whole, 8, 22, false, nullptr, 0,
     "Draco quantization bits of the base mesh positions, {range} (default: from the error target and the frame "
     "count, at least 10; 14 with --bpvf or --lossless)",
     [](CommandLine& line, const std::string&, double number) { line.encode.position_bits = int(number); }},
    {"--normal-bits", nullptr, "B", kEncode, Kind::whole, 4, 16, false, nullptr, 0,
     "Draco quantization bits of the base mesh normals, {range} (default 8)",
     [](CommandLine& line, const std::string&, double number) { line.encode.normal_bits = int(number); }},
    {"--texcoord-bits", nullptr, "B", kEncode, Kind::whole, 4, 30, false, nullptr, 0,
     "Draco quantization bits of the base mesh texture coordinates, {range} (default 12)",
     [](CommandLine& line, const std::string&, double number) { line.encode.texcoord_bits = int(number); }},
    {"--skins", nullptr, "MODE", kEncode, Kind::choice, 0, 0, false, "keep|bake", 0,
     "what a skinned mesh (without morph targets) stores. keep (default): its skin, the mesh compressed with Draco "
     "and the joints' tracks coded; bake: its sampled frames, for runtimes without skinning. --bpvf and --lossless "
     "bake, and so does keep where a kept skin cannot reach --error (its weights are bytes)",
     [](CommandLine& line, const std::string& text, double) {
       line.encode.skins = text == "keep" ? EncodeSettings::Skins::keep : EncodeSettings::Skins::bake;
     }},
    {"--targets", nullptr, "MODE", kEncode, Kind::choice, 0, 0, false, "auto|keep|bake", 0,
     "what a morph-target mesh (unskinned, one node) stores. keep: its targets, compressed, played by its own "
     "weights animation; bake: its sampled frames, like a skinned mesh. auto (default): where a mesh has at most "
     "half as many targets as frames, encode both ways and keep the file smaller as a server sends it (an "
     "estimate of its compressed size: the kept weights are floats that compress, the streams are not; with --bpvf, "
     "the one with the "
     "smaller error); never keep them with --lossless (kept targets are lossy)",
     [](CommandLine& line, const std::string& text, double) {
       line.encode.targets = text == "auto"   ? EncodeSettings::Targets::automatic
                             : text == "keep" ? EncodeSettings::Targets::keep
                                              : EncodeSettings::Targets::bake;
     }},
    {"--max-error", nullptr, "E", kVerify, Kind::number, 0, 10000, false, nullptr, 0,
     "fail (exit status 1) when the worst primitive's KG error in percent is above E, {range}",
     [](CommandLine& line, const std::string&, double number) { line.max_error = number; }},
    {"--max-bpvf", nullptr, "R", kVerify, Kind::number, 0, 1000, false, nullptr, 0,
     "fail (exit status 1) when COMPRESSED takes more than R bits per vertex per frame, {range}",
     [](CommandLine& line, const std::string&, double number) { line.max_bpvf = number; }},
    {"--json", nullptr, nullptr, kInfo | kEncode | kVerify, Kind::flag, 0, 0, false, nullptr, 0,
     "print one JSON object instead of text", [](CommandLine& line, const std::string&, double) { line.json = true; }},
    {"--quiet", "-q", nullptr, kEvery, Kind::flag, 0, 0, false, nullptr, 0, "no progress messages on stderr",
     [](CommandLine& line, const std::string&, double) { line.quiet = true; }},
    {"--help", "-h", nullptr, kEvery, Kind::flag, 0, 0, false, nullptr, 0, "this help",
     [](CommandLine& line, const std::string&, double) { line.help = true; }},
    {"--version", nullptr, nullptr, kEvery, Kind::flag, 0, 0, false, nullptr, 0, "print the version",
     [](CommandLine& line, const std::string&, double) { line.version = true; }},
};

std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%g", value);
  return buffer;
}

// "from 8 to 22", "more than 0 and at most 100", "auto, keep or bake".
std::string range(const Option& option) {
  if (option.kind == Kind::choice) {
    std::string text = option.choices;
    text.replace(text.rfind('|'), 1, " or ");
    for (size_t bar = text.find('|'); bar != std::string::npos; bar = text.find('|', bar)) text.replace(bar, 1, ", ");
    return text;
  }
  if (option.low_open) return "more than " + number_text(option.low) + " and at most " + number_text(option.high);
  return "from " + number_text(option.low) + " to " + number_text(option.high);
}

std::string command_list(unsigned commands) {
  std::string text;
  for (unsigned c = 0; c < 5; ++c)
    if (commands & (1u << c)) text += std::string(text.empty() ? "" : ", ") + kCommandNames[c];
  return text;
}

// `text` wrapped to `width` columns, lines after the first indented by `indent`.
std::string wrap(const std::string& text, size_t column, size_t indent, size_t width) {
  std::string out;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.size();
    if (column + (end - start) > width) {
      end = text.rfind(' ', start + (width - column));
      if (end == std::string::npos || end <= start) end = text.find(' ', start);
      if (end == std::string::npos) end = text.size();
    }
    out += text.substr(start, end - start);
    start = end < text.size() ? end + 1 : end;
    if (start < text.size()) out += "\n" + std::string(indent, ' '), column = indent;
  }
  return out;
}

std::string option_help(const Option& option) {
  std::string names = std::string("  ") + (option.alias ? std::string(option.alias) + ", " : "") + option.name;
  if (option.argument) names += std::string(" ") + (option.kind == Kind::choice ? option.choices : option.argument);
  names.resize(std::max<size_t>(names.size() + 1, 21), ' ');
  std::string help = option.help;
  const size_t placeholder = help.find("{range}");
  if (placeholder != std::string::npos) help.replace(placeholder, 7, range(option));
  if (option.commands != kEvery) help = command_list(option.commands) + ": " + help;
  return names + wrap(help, names.size(), 21, 110) + "\n";
}

const Option* find_option(const std::string& name) {
  for (const Option& option : kOptions)
    if (name == option.name || (option.alias && name == option.alias)) return &option;
  return nullptr;
}

// Checks `text` against the option's kind and range and applies it; false with `error` set when it does not fit.
bool apply(const Option& option, const std::string& text, CommandLine& line, std::string& error) {
  double number = 0;
  if (option.kind == Kind::number || option.kind == Kind::whole) {
    char* end = nullptr;
    number = option.kind == Kind::number ? std::strtod(text.c_str(), &end) : double(std::strtol(text.c_str(), &end, 10));
    const bool below = option.low_open ? !(number > option.low) : !(number >= option.low);
    if (end == text.c_str() || *end || below || !(number <= option.high)) {
      error = std::string(option.name) + " takes a " + (option.kind == Kind::whole ? "whole " : "") + "number " +
              range(option) + ", not '" + text + "'";
      return false;
    }
  } else if (option.kind == Kind::choice) {
    const std::string choices = std::string("|") + option.choices + "|";
    if (text.empty() || text.find('|') != std::string::npos || choices.find("|" + text + "|") == std::string::npos) {
      error = std::string(option.name) + " takes " + range(option) + ", not '" + text + "'";
      return false;
    }
  }
  option.apply(line, text, number);
  return true;
}

// An option as given: `name` is how (-o or --output).
struct Given {
  const Option* option;
  std::string name;
};

// The rules between options and the command's files, once all are read.
// Combinations of encode's options that contradict each other.
bool check_encode_options(const CommandLine& line, std::string& error) {
  if (line.encode.targets == EncodeSettings::Targets::keep && line.encode.mode == RateMode::lossless)
    return error = "--targets keep is lossy: it cannot be combined with --lossless", false;
  if (line.encode.fast_decode && line.encode.mode == RateMode::lossless)
    return error = "--fast-decode codes lossy residuals: it cannot be combined with --lossless", false;
  if (line.encode.fast_decode && line.encode.max_stream_version < 2)
    return error = "--fast-decode writes stream version 2: it cannot be combined with --max-stream-version 1", false;
  if (line.encode.gpu_playable) {
    if (line.encode.mode == RateMode::lossless)
      return error = "--gpu-playable writes lossy version-4 streams: it cannot be combined with --lossless", false;
    if (line.encode.mode == RateMode::bpvf)
      return error = "--gpu-playable needs an --error target: it cannot be combined with --bpvf", false;
    if (line.encode.fast_decode)
      return error = "--gpu-playable writes version 4, --fast-decode version 2: they cannot be combined", false;
    if (line.encode.max_stream_version < 4)
      return error = "--gpu-playable writes stream version 4: it cannot be combined with --max-stream-version " +
                     std::to_string(line.encode.max_stream_version), false;
  }
  return true;
}

bool check_command(CommandLine& line, const std::vector<Given>& given, std::string& error) {
  unsigned command = 0;
  for (unsigned c = 0; c < 5; ++c)
    if (line.command == kCommandNames[c]) command = 1u << c;
  if (!command) return error = "unknown command '" + line.command + "'", false;
  for (const Given& option : given)
    if (!(option.option->commands & command))
      return error = option.name + " is not an option of " + line.command + " (it is for " +
                     command_list(option.option->commands) + ")",
             false;
  bool jobs = false;
  for (const Given& option : given) jobs |= option.name == "--jobs" || option.name == "-j";
  if (!line.output_directory.empty()) {
    if (!line.output.empty()) return error = "give -o or --output-dir, not both", false;
    if (!line.frames.empty()) return error = "--frames writes one file: it cannot be combined with --output-dir", false;
    if (line.inputs.empty()) return error = line.command + " --output-dir takes one or more inputs", false;
    if (!line.cache.empty())
      return error = "--cache names one input's cache: it cannot be combined with --output-dir", false;
    for (const std::string& input : line.inputs)
      if (input == "-") return error = "a batch reads files: - (the standard input) is a single run's", false;
    line.encode.sampling = line.sampling;
    return check_encode_options(line, error);
  }
  if (jobs) return error = "--jobs is for batches: give --output-dir", false;
  const size_t inputs = command == kVerify ? 2 : 1;
  if (line.inputs.size() != inputs)
    return error = command == kVerify ? "verify takes two files: ORIGINAL COMPRESSED"
                   : command == kInfo ? "info takes one file"
                                      : line.command + " takes one input file",
           false;
  const bool frames_only = command == kDecode && !line.frames.empty() && line.output.empty();
  if ((command & (kBake | kEncode | kDecode)) && !frames_only) {
    if (line.output.empty()) return error = line.command + " needs -o OUT", false;
    if (!has_gltf_extension(line.output) && line.output != "-")
      return error = "the output must end in .glb or .gltf (or be - for a .glb on the standard output)", false;
  }
  if (line.output == "-" && line.frames == "-") return error = "only one output can be the standard output", false;
  if (command == kVerify && line.inputs[0] == "-" && line.inputs[1] == "-")
    return error = "only one input can be the standard input", false;
  line.encode.sampling = line.sampling;
  return check_encode_options(line, error);
}

}  // namespace

std::string usage() {
  std::string text = kCommands;
  for (const Option& option : kOptions) text += option_help(option);
  return text + kExitStatus;
}

ParseResult parse_command_line(int argc, const char* const* argv, CommandLine& line, std::string& error) {
  std::vector<Given> given;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.size() < 2 || arg[0] != '-') {  // a command or a file ("-" included)
      if (line.command.empty())
        line.command = arg;
      else
        line.inputs.push_back(arg);
      continue;
    }
    const size_t equals = arg.compare(0, 2, "--") == 0 ? arg.find('=') : std::string::npos;
    const std::string name = arg.substr(0, equals);
    const Option* option = find_option(name);
    if (!option) return error = "unknown option " + name, ParseResult::usage_error;
    std::string text;
    if (option->kind == Kind::flag && equals != std::string::npos)
      return error = name + " takes no value", ParseResult::usage_error;
    if (option->kind != Kind::flag) {
      if (equals != std::string::npos)
        text = arg.substr(equals + 1);
      else if (i + 1 < argc)
        text = argv[++i];
      else
        return error = name + " needs " +
                       (option->kind == Kind::text     ? std::string("a file name")
                        : option->kind == Kind::choice ? range(*option)
                                                       : std::string("a number")),
               ParseResult::usage_error;
    }
    for (const Given& other : given)
      if (option->group && other.option->group == option->group && other.option != option) {
        std::string members;
        for (const Option& o : kOptions)
          if (o.group == option->group) members += std::string(members.empty() ? "" : ", ") + o.name;
        return error = "give one of " + members.replace(members.rfind(", "), 2, " and "), ParseResult::usage_error;
      }
    if (!apply(*option, text, line, error)) return ParseResult::usage_error;
    if (line.help) return ParseResult::help;
    if (line.version) return ParseResult::version;
    given.push_back({option, name});
  }
  if (line.command.empty()) return error.clear(), ParseResult::usage_error;
  return check_command(line, given, error) ? ParseResult::run : ParseResult::usage_error;
}

}  // namespace segmorph
