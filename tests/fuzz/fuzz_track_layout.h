// The inputs of fuzz_track_stream: a few bytes that describe a TrackLayout, then the track stream. Shared with
// fuzz_track_seeds, which writes valid streams in this form. Every layout this can describe is small (at most
// 4 key-time arrays of 256 keys, 7 samplers, 64 weights), so the decoder's allocations stay bounded, as the
// caller's bound keeps them in the converter.
//
//   byte 0            key-time arrays T = 1 + byte % 4
//   T bytes           keys of each array: 1 + byte
//   1 byte            samplers S = byte % 8
//   2 bytes each      time array = first % T; path = second & 3; components: 3, 4 for rotation, for weights
//                     1 + (second >> 2)
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/track_set.h"

namespace segmorph::fuzz {

// Reads the layout at the front of `data`; false when there are too few bytes. `used`: the layout's bytes.
inline bool read_track_layout(const uint8_t* data, size_t size, TrackLayout& layout, size_t& used) {
  layout = TrackLayout();
  size_t at = 0;
  if (at >= size) return false;
  const size_t arrays = 1 + data[at++] % 4;
  for (size_t i = 0; i < arrays; ++i) {
    if (at >= size) return false;
    layout.time_counts.push_back(size_t(1) + data[at++]);
  }
  if (at >= size) return false;
  const size_t samplers = data[at++] % 8;
  for (size_t s = 0; s < samplers; ++s) {
    if (at + 2 > size) return false;
    TrackLayout::Sampler sampler;
    sampler.times = int(data[at] % arrays);
    sampler.path = TrackPath(data[at + 1] & 3);
    sampler.components = sampler.path == TrackPath::weights    ? 1 + (data[at + 1] >> 2)
                         : sampler.path == TrackPath::rotation ? 4
                                                               : 3;
    layout.samplers.push_back(sampler);
    at += 2;
  }
  used = at;
  return true;
}

// The bytes read_track_layout reads as `layout`, which must be within the limits above.
inline std::vector<uint8_t> track_layout_bytes(const TrackLayout& layout) {
  std::vector<uint8_t> bytes = {uint8_t(layout.time_counts.size() - 1)};
  for (size_t count : layout.time_counts) bytes.push_back(uint8_t(count - 1));
  bytes.push_back(uint8_t(layout.samplers.size()));
  for (const TrackLayout::Sampler& sampler : layout.samplers) {
    bytes.push_back(uint8_t(sampler.times));
    const int weights = sampler.path == TrackPath::weights ? sampler.components - 1 : 0;
    bytes.push_back(uint8_t(int(sampler.path) | weights << 2));
  }
  return bytes;
}

// Whether track_layout_bytes can describe `layout`.
inline bool fits_track_layout_bytes(const TrackLayout& layout) {
  if (layout.time_counts.empty() || layout.time_counts.size() > 4 || layout.samplers.size() > 7) return false;
  for (size_t count : layout.time_counts)
    if (count < 1 || count > 256) return false;
  for (const TrackLayout::Sampler& sampler : layout.samplers)
    if (sampler.path == TrackPath::weights && (sampler.components < 1 || sampler.components > 64)) return false;
  return true;
}

}  // namespace segmorph::fuzz
