// libFuzzer target: vertex caches through Model::load_cache, as info, bake, encode and verify read them. The input's
// first byte chooses what the rest is; bytes 1-4 (little-endian) give the length of an OBJ, the rest follows it:
//   0: a base mesh (that OBJ) and a point cache (the rest, PC2 or MDD by its first bytes);
//   1: an OBJ sequence of two frames (that OBJ, then the rest as the second frame).
// Seeds: samples/WavingFlag's OBJ with its PC2, with its MDD, and two frames of its sequence
// (vertex_cache_seeds.sh). Each input's files go to a fresh temporary directory, removed after.
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline.h"

namespace {

void write(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream file(path, std::ios::binary);
  file.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  if (!file.flush()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 5) return 0;
  const uint8_t mode = data[0] % 2;
  const size_t length = size_t(data[1]) | size_t(data[2]) << 8 | size_t(data[3]) << 16 | size_t(data[4]) << 24;
  if (length > size - 5) return 0;
  const uint8_t* first = data + 5;
  const uint8_t* rest = first + length;
  const size_t rest_size = size - 5 - length;

  static const char* const tmp = std::getenv("TMPDIR");
  std::string directory = std::string(tmp && *tmp ? tmp : "/tmp") + "/segmorph-fuzz-XXXXXX";
  if (!mkdtemp(directory.data())) std::abort();
  segmorph::CacheSource source;
  if (mode == 0) {
    source.mesh = directory + "/base.obj";
    source.cache = directory + "/anim.cache";
    write(source.mesh, first, length);
    write(source.cache, rest, rest_size);
  } else {
    source.mesh = directory + "/frame_%d.obj";
    write(directory + "/frame_1.obj", first, length);
    write(directory + "/frame_2.obj", rest, rest_size);
  }
  segmorph::Model model;
  segmorph::CacheReport report;
  if (segmorph::Model::load_cache(source, model, &report).ok()) {
    segmorph::InfoReport info;
    (void)segmorph::info(model, report.sampling, info);
  }
  std::filesystem::remove_all(directory);
  return 0;
}
