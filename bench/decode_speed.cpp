// decode_speed DIR [--runs N] [--threads T]: the runtime decoder's C API (include/segmorph/decoder_c.h) timed on one stream, as an
// engine that keeps every frame calls it: segmorph_decoder_open, then every clip into memory allocated beforehand.
// DIR holds stream.bin (the SEGMORPH_animation_compression bufferView), base.f32 (the Draco base mesh's positions,
// V x 3 little-endian floats) and indices.u32 (its triangles), as bench/wasm_speed.mjs writes them. T threads
// (segmorph_decoder_set_threads: version-4 frames; default 1, 0 every hardware thread); N runs
// (default 9) after one that is not counted; prints one JSON line: vertex-frames, the median and the fastest run
// in milliseconds, and millions of vertex-frames per second at the median.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "segmorph/decoder_c.h"

namespace {

template <typename T>
bool read_file(const std::string& path, std::vector<T>& out) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return false;
  const std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.size() % sizeof(T) != 0) return false;
  out.resize(bytes.size() / sizeof(T));
  if (!bytes.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
  return true;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "decode_speed: %s\n", message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return fail("usage: decode_speed DIR [--runs N] [--threads T]");
  const std::string directory = argv[1];
  int runs = 9, threads = 1;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
      runs = std::atoi(argv[++i]);
      if (runs < 1 || runs > 1000) return fail("--runs takes 1 to 1000");
    } else if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
      if (threads < 0 || threads > 1024) return fail("--threads takes 0 to 1024");
    } else {
      return fail(std::string("unknown argument ") + argv[i]);
    }
  }
  std::vector<uint8_t> stream;
  std::vector<float> base;
  std::vector<uint32_t> indices;
  if (!read_file(directory + "/stream.bin", stream) || !read_file(directory + "/base.f32", base) ||
      !read_file(directory + "/indices.u32", indices) || base.size() % 3 != 0 || indices.size() % 3 != 0)
    return fail("cannot read stream.bin, base.f32 and indices.u32 in " + directory);

  segmorph_decoder* decoder = segmorph_decoder_create();
  if (!decoder) return fail("out of memory");
  segmorph_decoder_set_threads(decoder, size_t(threads));
  auto open = [&] {
    return segmorph_decoder_open(decoder, stream.data(), stream.size(), base.data(), base.size() / 3, indices.data(),
                                 indices.size());
  };
  if (open() != SEGMORPH_STATUS_OK) return fail(segmorph_decoder_message(decoder));
  std::vector<std::vector<float>> clips(segmorph_decoder_clip_count(decoder));
  size_t vertex_frames = 0;
  for (size_t c = 0; c < clips.size(); ++c) {
    clips[c].resize(segmorph_decode_clip_bound(decoder, c));
    vertex_frames += clips[c].size() / 3;
  }
  std::vector<double> milliseconds;
  for (int run = 0; run <= runs; ++run) {
    const auto start = std::chrono::steady_clock::now();
    segmorph_status status = open();
    for (size_t c = 0; status == SEGMORPH_STATUS_OK && c < clips.size(); ++c)
      status = segmorph_decode_clip(decoder, c, clips[c].data(), clips[c].size());
    const auto end = std::chrono::steady_clock::now();
    if (status != SEGMORPH_STATUS_OK) return fail(segmorph_decoder_message(decoder));
    if (run > 0) milliseconds.push_back(std::chrono::duration<double, std::milli>(end - start).count());
  }
  segmorph_decoder_destroy(decoder);
  std::vector<double> sorted = milliseconds;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[(sorted.size() - 1) / 2];
  std::printf("{\"vertex_frames\":%zu,\"threads\":%d,\"runs\":%d,\"median_ms\":%.3f,\"min_ms\":%.3f,\"mvfs\":%.1f}\n",
              vertex_frames, threads, runs, median, sorted.front(), double(vertex_frames) / median / 1e3);
  return 0;
}
