// Files written whole or not at all (converter/gltf/output_file.h): nothing at the path until the commit, the
// temporary gone on every failure, two files committed together, a failed write reported.
#include <sys/resource.h>

#include <algorithm>
#include <csignal>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "gltf/output_file.h"
#include "test_files.h"

namespace segmorph {
namespace {

namespace fs = std::filesystem;
using testing::temporary_path;

// The files in `directory` (names), sorted.
std::vector<std::string> files_in(const std::string& directory) {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string read_all(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

std::string fresh_directory(const std::string& name) {
  const std::string directory = temporary_path(name);
  fs::remove_all(directory);
  fs::create_directories(directory);
  return directory;
}

TEST(OutputFile, NothingAtThePathUntilTheCommit) {
  const std::string directory = fresh_directory("commit"), path = directory + "/out.bin";
  {
    OutputFile file;
    ASSERT_TRUE(file.open(path).ok());
    file.stream() << "whole";
    EXPECT_FALSE(fs::exists(path));
    ASSERT_TRUE(file.finish().ok());
    EXPECT_FALSE(fs::exists(path));
    ASSERT_TRUE(file.commit().ok());
  }
  EXPECT_EQ(read_all(path), "whole");
  EXPECT_EQ(files_in(directory), std::vector<std::string>{"out.bin"});  // no temporary left
}

TEST(OutputFile, AnUncommittedFileLeavesNothingAndKeepsWhatWasThere) {
  const std::string directory = fresh_directory("abandon"), path = directory + "/out.bin";
  std::ofstream(path) << "before";
  {
    OutputFile file;
    ASSERT_TRUE(file.open(path).ok());
    file.stream() << "half";
    ASSERT_TRUE(file.finish().ok());
  }  // destroyed without a commit, as after a failure elsewhere
  EXPECT_EQ(read_all(path), "before");
  EXPECT_EQ(files_in(directory), std::vector<std::string>{"out.bin"});
}

TEST(OutputFile, TwoFilesAreCommittedTogether) {
  const std::string directory = fresh_directory("pair");
  OutputFile gltf, bin;
  ASSERT_TRUE(gltf.open(directory + "/a.gltf").ok());
  ASSERT_TRUE(bin.open(directory + "/a.bin").ok());
  gltf.stream() << "{}";
  bin.stream() << "data";
  ASSERT_TRUE(gltf.finish().ok());
  ASSERT_TRUE(bin.finish().ok());
  ASSERT_TRUE(OutputFile::commit(bin, gltf).ok());
  EXPECT_EQ(files_in(directory), (std::vector<std::string>{"a.bin", "a.gltf"}));
  EXPECT_EQ(read_all(directory + "/a.bin"), "data");
}

// A write that fails (here: beyond the file size limit, as on a full disk) is reported by finish(), and the
// temporary file goes; an output whose folder does not exist fails at open().
TEST(OutputFile, FailedWritesAreReportedAndLeaveNothing) {
  const std::string directory = fresh_directory("failed");
  EXPECT_EQ(save_file(directory + "/missing/out.bin", "x", 1).code(), StatusCode::io_error);
  rlimit previous{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &previous), 0);
  const auto previous_handler = std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead
  rlimit small = previous;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string big(1 << 20, 'x');
  const Status status = save_file(directory + "/out.bin", big.data(), big.size());
  setrlimit(RLIMIT_FSIZE, &previous);
  std::signal(SIGXFSZ, previous_handler);
  EXPECT_EQ(status.code(), StatusCode::io_error) << status.message();
  EXPECT_TRUE(files_in(directory).empty());
}

TEST(OutputFile, SameFileSeesThroughLinks) {
  const std::string directory = fresh_directory("links"), path = directory + "/a.glb";
  std::ofstream(path) << "x";
  fs::create_symlink(path, directory + "/link.glb");
  EXPECT_TRUE(same_file(path, directory + "/link.glb"));
  EXPECT_TRUE(same_file(path, directory + "/./a.glb"));
  EXPECT_FALSE(same_file(path, directory + "/missing.glb"));
}

}  // namespace
}  // namespace segmorph
