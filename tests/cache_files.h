// Hand-made vertex caches for the tests: PC2 and MDD files whose point p of frame f is at coordinate(f, p, c).
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "test_files.h"

namespace segmorph::testing {

inline void put(std::string& out, uint32_t value, bool big) {
  for (int i = 0; i < 4; ++i) out += char(big ? value >> (24 - 8 * i) : value >> (8 * i));
}
inline void put_float(std::string& out, float value, bool big) {
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  put(out, bits, big);
}

// Point p of frame f: (f + p / 10, -p, 0.5 f).
inline float coordinate(size_t f, size_t p, int c) {
  return c == 0 ? float(f) + float(p) / 10 : c == 1 ? -float(p) : 0.5f * float(f);
}

inline std::string pc2(uint32_t points, uint32_t samples, float start, float rate, uint32_t version = 1) {
  std::string out("POINTCACHE2\0", 12);
  put(out, version, false);
  put(out, points, false);
  put_float(out, start, false);
  put_float(out, rate, false);
  put(out, samples, false);
  for (size_t f = 0; f < samples; ++f)
    for (size_t p = 0; p < points; ++p)
      for (int c = 0; c < 3; ++c) put_float(out, coordinate(f, p, c), false);
  return out;
}

inline std::string mdd(uint32_t frames, uint32_t points, const std::vector<float>& times) {
  std::string out;
  put(out, frames, true);
  put(out, points, true);
  for (float t : times) put_float(out, t, true);
  for (size_t f = 0; f < frames; ++f)
    for (size_t p = 0; p < points; ++p)
      for (int c = 0; c < 3; ++c) put_float(out, coordinate(f, p, c), true);
  return out;
}

inline std::string written(const std::string& name, const std::string& bytes) {
  const std::string path = temporary_path(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

}  // namespace segmorph::testing
