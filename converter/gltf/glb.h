// The GLB container (glTF 2.0, "Binary glTF Layout"): its little-endian words and chunk types, which the loader
// checks, the writer writes and the delivered-size estimate reads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <ostream>
#include <string>

namespace segmorph {

constexpr uint32_t kGlbJsonChunk = 0x4E4F534A, kGlbBinChunk = 0x004E4942;  // "JSON", "BIN\0"

inline uint32_t read_u32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

inline void put_u32(std::string& out, size_t at, uint32_t value) {
  for (int i = 0; i < 4; ++i) out[at + size_t(i)] = char(value >> (8 * i));
}

inline void write_le32(std::ostream& out, uint32_t value) {
  const unsigned char bytes[4] = {uint8_t(value), uint8_t(value >> 8), uint8_t(value >> 16), uint8_t(value >> 24)};
  out.write(reinterpret_cast<const char*>(bytes), 4);
}

}  // namespace segmorph
