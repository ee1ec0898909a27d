// The bit pattern of a binary32 float and back: how streams store floats, compare them exactly (+0.0 and -0.0
// differ) and order non-negative ones.
#pragma once

#include <cstdint>
#include <cstring>

namespace segmorph {

inline uint32_t float_bits(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, 4);
  return bits;
}

inline float bits_float(uint32_t bits) {
  float x;
  std::memcpy(&x, &bits, 4);
  return x;
}

}  // namespace segmorph
