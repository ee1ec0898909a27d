// segmorph: the command-line tool. It parses the command line (command_line.h), calls the pipeline API
// (include/segmorph/segmorph.h) and prints what it returns (reports.h); batches run it once per file (batch.h).
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "cli/batch.h"
#include "cli/command_line.h"
#include "cli/huge_pages.h"
#include "cli/reports.h"
#include "gltf/output_file.h"
#include "segmorph/segmorph.h"
#include "segmorph/version.h"

namespace segmorph {
namespace {

// An error: one line on stderr and, with --json, one object on stdout.
void print_error(bool json, const char* code, const std::string& file, const std::string& message) {
  if (file.empty())
    std::fprintf(stderr, "segmorph: %s (see segmorph --help)\n", message.c_str());
  else
    std::fprintf(stderr, "segmorph: error: %s: %s\n", file.c_str(), message.c_str());
  if (json) std::printf("%s\n", error_json(code, file, message).c_str());
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

// Input `index` of the command line (decode reads glTF files only).
Input input(size_t index, const CommandLine& options) {
  return Input{options.inputs[index], index == 0 ? options.cache : options.cache2, options.z_up,
               options.command != "decode"};
}

// Reads input `index` (a glTF file or a vertex cache) and gives how to sample it.
Status load(size_t index, const CommandLine& options, Model& model, SampleSettings& sampling) {
  return load_input(input(index, options), options.sampling, model, sampling, progress_of(options));
}

// A binary file is not written to a terminal: a usage error (exit 2); otherwise 0.
int refuse_terminal_output(const CommandLine& options) {
  if ((options.output == "-" || options.frames == "-") && isatty(STDOUT_FILENO))
    return usage_error(options.json, "the standard output is a terminal: redirect it, or give -o FILE");
  return 0;
}

// bake, encode and decode do not write over their own input (or a file it reads) unless --force: a usage error.
int refuse_replacing_input(const CommandLine& options, const Model& input) {
  if (options.force || options.inputs[0] == "-") return 0;
  for (const std::string* output : {&options.output, &options.frames})
    if (!output->empty() && *output != "-" && writes_over(*output, options.inputs[0], input))
      return usage_error(options.json, *output + " would replace the input " + options.inputs[0] +
                                           " or a file it reads; give --force to replace it");
  return 0;
}

// Writes `model` to -o (progress first), or fails naming it.
int save(const CommandLine& options, Model& model) {
  progress(options, "writing " + (options.output == "-" ? std::string("to the standard output") : options.output));
  const Status status = model.save(options.output);
  return status.ok() ? 0 : fail(options, options.output, status);
}

int run_info(const CommandLine& options) {
  Model model;
  InfoReport report;
  SampleSettings sampling;
  Status status = load(0, options, model, sampling);
  if (status.ok()) status = info(model, sampling, report, progress_of(options));
  if (!status.ok()) return fail(options, options.inputs[0], status);
  const std::string& path = options.inputs[0];
  std::fputs((options.json ? info_json(path, report) + "\n" : info_text(path, report)).c_str(), stdout);
  return 0;
}

int run_bake(const CommandLine& options) {
  Model model;
  BakeReport report;
  SampleSettings sampling;
  if (const int refused = refuse_terminal_output(options)) return refused;
  Status status = load(0, options, model, sampling);
  if (status.ok())
    if (const int refused = refuse_replacing_input(options, model)) return refused;
  if (status.ok()) status = bake(model, sampling, &report, progress_of(options));
  if (!status.ok()) return fail(options, options.inputs[0], status);
  if (const int failed = save(options, model)) return failed;
  progress(options, "baked " + std::to_string(report.nodes) + " animated node" + (report.nodes == 1 ? "" : "s") +
                        ", " + std::to_string(report.frames) + " frames in all");
  return 0;
}

int run_encode(const CommandLine& options) {
  Model input, output;
  EncodeReport report;
  EncodeSettings settings = options.encode;
  if (const int refused = refuse_terminal_output(options)) return refused;
  Status status = load(0, options, input, settings.sampling);
  if (status.ok())
    if (const int refused = refuse_replacing_input(options, input)) return refused;
  if (status.ok()) status = encode(std::move(input), settings, output, &report, progress_of(options));
  if (!status.ok()) return fail(options, options.inputs[0], status);
  if (const int failed = save(options, output)) return failed;
  const size_t bytes = saved_bytes(options.output, output);
  const std::string text = options.json ? encode_json(options.inputs[0], options.output, bytes, report) + "\n"
                                        : encode_text(options.output, bytes, report);
  std::fputs(text.c_str(), options.output == "-" ? stderr : stdout);  // stdout may hold the file
  return 0;
}

int run_decode(const CommandLine& options) {
  const std::string& path = options.inputs[0];
  Model model;
  DecodeReport report;
  std::vector<DecodedFrames> decoded;
  SampleSettings sampling;
  if (const int refused = refuse_terminal_output(options)) return refused;
  Status status = load(0, options, model, sampling);
  if (status.ok())
    if (const int refused = refuse_replacing_input(options, model)) return refused;
  if (status.ok()) status = decode(model, options.decode, &report, options.frames.empty() ? nullptr : &decoded);
  if (!status.ok()) return fail(options, path, status);
  if (report.primitives == 0 && report.coded_animations == 0)
    return fail(options, path, Status(StatusCode::nothing_to_do,
                                      "not encoded: it has no SEGMORPH_animation_compression primitive or animation"));
  if (!options.output.empty())
    if (const int failed = save(options, model)) return failed;
  if (!options.frames.empty()) {
    progress(options, "writing the decoded frames to " + options.frames);
    status = save_decoded_frames(decoded, options.frames);
    if (!status.ok()) return fail(options, options.frames, status);
  }
  progress(options, "decoded " + std::to_string(report.primitives) + " primitive" +
                        (report.primitives == 1 ? "" : "s") + " and the tracks of " +
                        std::to_string(report.coded_animations) + " animation" +
                        (report.coded_animations == 1 ? "" : "s"));
  return 0;
}

int run_verify(const CommandLine& options) {
  const std::string &original_path = options.inputs[0], &compressed_path = options.inputs[1];
  Model original, compressed;
  SampleSettings sampling, compressed_sampling;
  Status status = load(0, options, original, sampling);
  if (!status.ok()) return fail(options, original_path, status);
  status = load(1, options, compressed, compressed_sampling);
  if (!status.ok()) return fail(options, compressed_path, status);
  VerifyReport report;
  status = verify(original, compressed, sampling, report, progress_of(options));
  if (!status.ok()) return fail(options, report.failed_model == 0 ? original_path : compressed_path, status);
  const size_t bytes = input_bytes(input(1, options), compressed);
  const VerifyBounds bounds{options.max_error, options.max_bpvf};
  const std::string above = bound_text(exceeded_bound(report, bytes, bounds), report, bytes, bounds);
  const std::string text = options.json ? verify_json(original_path, compressed_path, bytes, report, above) + "\n"
                                        : verify_text(original_path, compressed_path, bytes, report);
  std::fputs(text.c_str(), stdout);
  if (above.empty()) return 0;
  std::fprintf(stderr, "segmorph: error: %s: %s\n", compressed_path.c_str(), above.c_str());
  return 1;
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
  int (*const command)(const CommandLine&) = options.command == "info"     ? run_info
                                             : options.command == "bake"   ? run_bake
                                             : options.command == "encode" ? run_encode
                                             : options.command == "decode" ? run_decode
                                                                           : run_verify;
  if (options.output_directory.empty()) return command(options);
  std::vector<BatchFile> files;
  if (!plan_batch(options.inputs, options.output_directory, files, error)) return usage_error(options.json, error);
  return run_batch(options, files, command);
}

}  // namespace
}  // namespace segmorph

int main(int argc, char** argv) {
  segmorph::use_transparent_huge_pages(argv);
  segmorph::remove_temporary_files_on_signals();
  return segmorph::run(argc, argv);
}
