#include "common/stream.h"

#include <algorithm>
#include <array>
#include <numeric>

#include "common/float_bits.h"
#include "common/stream_format.h"

namespace segmorph {

size_t StreamContent::frame_count() const {
  return std::accumulate(clip_frames.begin(), clip_frames.end(), size_t(0));
}

uint32_t frame_reference(const StreamContent& content, size_t frame, size_t frame_in_clip) {
  if (content.flags & format::kFlagFrameReferences) return content.references[frame];
  return (content.flags & format::kFlagTemporalResiduals) && frame_in_clip > 0 ? 1 : 0;
}

uint32_t reference_window(const StreamContent& content) {
  return content.flags & format::kFlagFrameReferences ? content.reference_window : 1;
}

int64_t ordered_bits(float x) {
  const uint32_t bits = float_bits(x);
  return (bits & 0x80000000u) ? -int64_t(bits & 0x7fffffffu) - 1 : int64_t(bits);
}

float from_ordered_bits(int64_t value) {
  if (value < 0) return bits_float(uint32_t(-(value + 1)) | 0x80000000u);
  return bits_float(uint32_t(value));
}

std::vector<std::vector<uint32_t>> identical_position_groups(const std::vector<float>& base) {
  const size_t vertex_count = base.size() / 3;
  std::vector<uint32_t> order(vertex_count);
  std::iota(order.begin(), order.end(), 0u);
  auto key = [&](uint32_t v) {
    return std::array<uint32_t, 3>{float_bits(base[v * 3]), float_bits(base[v * 3 + 1]), float_bits(base[v * 3 + 2])};
  };
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  std::vector<std::vector<uint32_t>> groups;
  std::vector<uint32_t> group_of(vertex_count);
  for (size_t i = 0; i < vertex_count; ++i) {
    if (i == 0 || key(order[i]) != key(order[i - 1])) groups.emplace_back();
    groups.back().push_back(order[i]);
    group_of[order[i]] = uint32_t(groups.size() - 1);
  }
  // Renumber groups in order of their first vertex.
  std::vector<std::vector<uint32_t>> ordered;
  std::vector<bool> seen(groups.size(), false);
  for (uint32_t v = 0; v < vertex_count; ++v)
    if (!seen[group_of[v]]) {
      seen[group_of[v]] = true;
      ordered.push_back(std::move(groups[group_of[v]]));
    }
  return ordered;
}

}  // namespace segmorph
