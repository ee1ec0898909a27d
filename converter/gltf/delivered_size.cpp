#include "gltf/delivered_size.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "gltf/glb.h"
#include "gltf/save.h"

namespace segmorph {

double compressed_estimate(const unsigned char* data, size_t count) {
  if (count == 0) return 0;
  auto entropy_bytes = [](const auto& counts, double total) {
    double bits = 0;
    for (const auto& entry : counts) bits -= double(entry.second) * std::log2(double(entry.second) / total);
    return bits / 8;
  };
  std::map<unsigned char, size_t> bytes;
  for (size_t i = 0; i < count; ++i) ++bytes[data[i]];
  double estimate = std::min(double(count), entropy_bytes(bytes, double(count)));
  if (count >= 64 && count % 4 == 0) {
    std::unordered_map<uint32_t, size_t> words;
    for (size_t i = 0; i < count; i += 4) {
      uint32_t word;
      std::memcpy(&word, data + i, 4);
      ++words[word];
    }
    estimate = std::min(estimate, entropy_bytes(words, double(count / 4)) + 4.0 * double(words.size()));
  }
  return estimate;
}

size_t glb_delivered_estimate(tinygltf::Model model, size_t* size) {
  const std::string glb = glb_bytes(model);
  if (size) *size = glb.size();
  if (glb.empty()) return 0;
  const auto* bytes = reinterpret_cast<const unsigned char*>(glb.data());
  auto u32 = [&](size_t at) { return read_u32(bytes + at); };
  if (glb.size() < 20) return glb.size();
  const size_t json = u32(12);
  double estimate = 20 + compressed_estimate(bytes + 20, std::min(json, glb.size() - 20));
  const size_t bin = 20 + json;
  if (bin + 8 <= glb.size()) {
    const size_t length = std::min<size_t>(u32(bin), glb.size() - bin - 8);
    size_t covered = 0;
    for (const tinygltf::BufferView& view : model.bufferViews)
      if (view.buffer == 0 && view.byteOffset + view.byteLength <= length) {
        estimate += compressed_estimate(bytes + bin + 8 + view.byteOffset, view.byteLength);
        covered += view.byteLength;
      }
    estimate += 8 + double(length - std::min(covered, length));
  }
  return size_t(std::ceil(estimate));
}

}  // namespace segmorph
