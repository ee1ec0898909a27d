// The command line of the segmorph tool: its commands and options, parsed from one table (command_line.cpp) that
// holds each option's name, argument, range, the commands that take it and its help, so that --help, the checks
// and the error messages come from one place.
#pragma once

#include <string>
#include <vector>

#include "segmorph/segmorph.h"

namespace segmorph {

struct CommandLine {
  std::string command;  // info, bake, encode, decode or verify
  std::vector<std::string> inputs;
  std::string output;  // -o; empty only where the command writes no glTF file
  std::string frames;  // decode --frames: the decoded frames as raw floats
  bool z_up = false;          // --z-up: the caches and OBJ meshes are Z up
  std::string cache, cache2;  // --cache: the point cache of the first input (a base mesh); --cache2: of verify's second
  SampleSettings sampling;
  EncodeSettings encode;  // its sampling is `sampling`
  DecodeSettings decode;  // --threads too
  bool json = false;
  bool quiet = false;
  bool force = false;  // an output may replace the input
  double max_error = -1, max_bpvf = -1;  // verify's bounds; negative: none
  std::string output_directory;           // a batch: every input's output goes there
  int jobs = 1;                           // a batch's files at once
  std::string label;                      // a batch's file: what its progress lines start with
  bool help = false, version = false;
};

enum class ParseResult { run, help, version, usage_error };

// Reads argv into `line`. usage_error: `error` says in one line what is wrong, or is empty when no command was given
// (the caller prints the usage). Options take their value as the next argument or after '=' (--error=0.5); an option
// the command does not use is refused.
ParseResult parse_command_line(int argc, const char* const* argv, CommandLine& line, std::string& error);


// --help: the commands, then every option with its range, then the exit statuses.
std::string usage();

}  // namespace segmorph
