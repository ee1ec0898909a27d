// Batches: one command over many files (segmorph encode IN... --output-dir DIR --jobs N). Each file runs in a child
// process of its own exactly as a single run would (the same bytes), so that a file that fails, or crashes, stops no
// other, and its report is printed whole, in input order.
#pragma once

#include <string>
#include <vector>

#include "cli/command_line.h"

namespace segmorph {

struct BatchFile {
  std::string input, output;
};

// The files of `inputs` (files as given; folders: the .glb and .gltf files under them, in name order, except those
// under `directory`) with their outputs, `directory`/<name>.glb. False with `error` when there is no file, or when
// two would write the same output.
bool plan_batch(const std::vector<std::string>& inputs, const std::string& directory, std::vector<BatchFile>& files,
                std::string& error);

// Creates `options.output_directory`, then runs `single` on every file (with the file's input, output and label) in up
// to `options.jobs` child processes. Prints each file's report (the child's stdout) in input order, then one summary
// line ({"files":N,"failed":M} with --json). SIGINT and SIGTERM are passed on to the children, and the batch ends
// with the signal once they have ended. Returns 0 when every file succeeded, 1 otherwise.
int run_batch(const CommandLine& options, const std::vector<BatchFile>& files, int (*single)(const CommandLine&));

}  // namespace segmorph
