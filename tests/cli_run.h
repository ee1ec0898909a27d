// What the tests of the command-line tool (tests/cli_*_test.cpp, one file per command) share: running the tool,
// sample paths, scratch folders, and the checks several commands make.
#pragma once

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include "test_files.h"

namespace cli_testing {

using segmorph::testing::json_number;
using segmorph::testing::temporary_path;
namespace fs = std::filesystem;
struct Result {
  int exit_code = -1;
  std::string out, err;
};

inline std::string read_text(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

inline Result run(const std::string& arguments) {
  const std::string out = temporary_path("cli.out"), err = temporary_path("cli.err");
  const std::string command = std::string(SEGMORPH_BINARY) + " " + arguments + " >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(command.c_str());
  Result result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = read_text(out);
  result.err = read_text(err);
  return result;
}

inline std::string sample(const std::string& relative) {
  return std::string(SEGMORPH_SAMPLES_DIR) + "/" + relative;
}

// A fresh directory for outputs, so leftovers are easy to see.
inline std::string output_directory(const std::string& name) {
  const std::string directory = temporary_path(name);
  fs::remove_all(directory);
  fs::create_directories(directory);
  return directory;
}

// Runs bake (or `command`) with a bad input and checks the promise: exit 1, one line naming the file, no output,
// no leftovers.
// SimpleMorph's two .bin files copied into `directory`, and its JSON to edit and write beside them.
inline std::string simple_morph_in(const std::string& directory) {
  fs::copy_file(sample("SimpleMorph/simpleMorphGeometry.bin"), directory + "/simpleMorphGeometry.bin");
  fs::copy_file(sample("SimpleMorph/simpleMorphAnimation.bin"), directory + "/simpleMorphAnimation.bin");
  return read_text(sample("SimpleMorph/SimpleMorph.gltf"));
}

inline void expect_clean_failure(const std::string& input, const std::string& expected_message,
                          const std::string& command = "bake", const std::string& options = "") {
  SCOPED_TRACE(input + options);
  const std::string directory = output_directory("failure");
  const Result result = run(command + " -q '" + input + "' " + options + " -o " + directory + "/out.glb");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find(input), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(expected_message), std::string::npos) << result.err;
  EXPECT_TRUE(fs::is_empty(directory)) << command << " left files behind";
}

// `command` run by bash, its output and exit status.
inline Result run_shell(const std::string& command) {
  const std::string out = temporary_path("shell.out"), err = temporary_path("shell.err");
  const std::string line = "bash -c '" + command + "' >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(line.c_str());
  Result result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = read_text(out);
  result.err = read_text(err);
  return result;
}

// How many processes have `argument` among their command-line arguments (zombies have none).
inline int processes_with_argument(const std::string& argument) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream file(entry.path() / "cmdline", std::ios::binary);
    for (std::string word; std::getline(file, word, '\0');)
      if (word == argument) {
        ++count;
        break;
      }
  }
  return count;
}

// Runs segmorph with `arguments` and sends it `signal_number` once a line of its stderr (its progress) contains
// `line` ("" at once, before it starts), then returns its wait status (-1 when it could not be started or waited for).
// No clock: the signal follows a stage's announcement, whatever the machine's speed.
inline int signal_on_line(const std::vector<std::string>& arguments, const std::string& line, int signal_number) {
  std::vector<const char*> argv = {SEGMORPH_BINARY};
  for (const std::string& argument : arguments) argv.push_back(argument.c_str());
  argv.push_back(nullptr);
  int pipe_ends[2];
  if (pipe(pipe_ends) != 0) return -1;
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    dup2(pipe_ends[1], 2);
    close(pipe_ends[0]);
    close(pipe_ends[1]);
    execv(argv[0], const_cast<char* const*>(argv.data()));
    _exit(127);
  }
  close(pipe_ends[1]);
  std::string seen;
  char buffer[256];
  ssize_t got = 0;
  while (!line.empty() && seen.find(line) == std::string::npos && (got = read(pipe_ends[0], buffer, sizeof buffer)) > 0)
    seen.append(buffer, size_t(got));
  kill(pid, signal_number);
  while (read(pipe_ends[0], buffer, sizeof buffer) > 0) {
  }
  close(pipe_ends[0]);
  int status = 0;
  return waitpid(pid, &status, 0) == pid ? status : -1;
}

// A named pipe with a glTF name: a process that opens it to read waits until a writer opens it (none does), so a
// signal surely finds it before its end.
inline std::string waiting_input(const std::string& directory) {
  const std::string path = directory + "/waiting.glb";
  EXPECT_EQ(mkfifo(path.c_str(), 0600), 0) << path;
  return path;
}

// The value of `key` in the object of encode --json's "primitives" array at `index` (NaN when absent).
inline std::string json_primitive(const std::string& json, size_t index) {
  size_t at = json.find("\"primitives\":[");
  for (size_t i = 0; at != std::string::npos && i <= index; ++i) at = json.find("{\"node\":", at + 1);
  if (at == std::string::npos) return "";
  return json.substr(at, json.find('}', at) - at + 1);
}

// The lines of `text`.
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

// Encodes every file of `inputs` as one batch (2 jobs) and one by one, and expects the same bytes.
inline void expect_batch_bytes_of_single_runs(const std::vector<std::string>& inputs, const std::string& folder,
                                       const std::string& directory) {
  const Result batch = run("encode -q " + folder + " --output-dir " + directory + "/batch --jobs 2 --json");
  const std::vector<std::string> lines = lines_of(batch.out);
  ASSERT_EQ(lines.size(), inputs.size() + 1) << batch.out << batch.err;
  size_t failed = 0;
  for (size_t i = 0; i < inputs.size(); ++i) {
    SCOPED_TRACE(inputs[i]);
    EXPECT_NE(lines[i].find(inputs[i]), std::string::npos) << "input order: " << lines[i];
    const std::string name = fs::path(inputs[i]).stem().string() + ".glb";
    const Result single = run("encode -q " + inputs[i] + " -o " + directory + "/" + name);
    if (single.exit_code != 0) {  // a file with nothing to encode fails the same way in the batch
      ++failed;
      EXPECT_EQ(lines[i].rfind("{\"error\":", 0), 0u) << lines[i];
      EXPECT_FALSE(fs::exists(directory + "/batch/" + name));
      continue;
    }
    EXPECT_EQ(read_text(directory + "/batch/" + name), read_text(directory + "/" + name)) << "not the same bytes";
  }
  EXPECT_EQ(lines.back(), "{\"files\":" + std::to_string(inputs.size()) + ",\"failed\":" + std::to_string(failed) + "}");
  EXPECT_EQ(batch.exit_code, failed ? 1 : 0);
}

inline std::string flag(const std::string& file) { return sample("WavingFlag/" + file); }

}  // namespace cli_testing
