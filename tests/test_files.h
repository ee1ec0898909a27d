// Where the tests find sample files, and small helpers for what they read and write.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>
#include <string>
#include <vector>

namespace segmorph::testing {

// Every .glb and .gltf file below `directory`, sorted; empty when the directory does not exist.
inline std::vector<std::string> gltf_files_under(const std::string& directory) {
  std::vector<std::string> files;
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error)) return files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(directory)) {
    const std::string extension = entry.path().extension().string();
    if (entry.is_regular_file() && (extension == ".glb" || extension == ".gltf")) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Bytes as lowercase hexadecimal, two digits each, as the specifications' worked examples print them.
inline std::string hex(const std::vector<uint8_t>& bytes) {
  std::string out;
  char digits[3];
  for (uint8_t byte : bytes) {
    std::snprintf(digits, sizeof(digits), "%02x", byte);
    out += digits;
  }
  return out;
}

// One number from a JSON object the tool printed ("key":value); NaN when the key is missing.
inline double json_number(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\":");
  return at == std::string::npos ? NAN : std::atof(json.c_str() + at + key.size() + 3);
}

inline std::vector<std::string> bundled_samples() { return gltf_files_under(SEGMORPH_SAMPLES_DIR); }

// ../shared/samples: present on developers' machines and in CI, absent on a bare clone.
inline bool have_shared_samples() { return std::filesystem::is_directory(SEGMORPH_SHARED_SAMPLES_DIR); }
inline std::vector<std::string> shared_samples() { return gltf_files_under(SEGMORPH_SHARED_SAMPLES_DIR); }

// A path in the tests' scratch directory, prefixed with the running test's name: ctest runs tests in
// parallel processes, which must not share files.
inline std::string temporary_path(const std::string& name) {
  const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string prefix = test ? std::string(test->test_suite_name()) + "." + test->name() + "." : "";
  return std::string(SEGMORPH_TEST_TMP) + "/" + prefix + name;
}

}  // namespace segmorph::testing
