// The base mesh the bench tools encode against before any container: the first frame quantized to 14 bits over
// its bounding box's largest extent, as Draco's default position quantization would.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/frame_sequence.h"
#include "encode/metrics.h"

namespace segmorph::bench {

inline std::vector<float> stand_in_base(const FrameSequence& clip) {
  std::vector<float> base(clip.frame(0), clip.frame(0) + clip.vertex_count * 3);
  float low[3], high[3];
  bounding_box(base.data(), clip.vertex_count, low, high);
  const float range = std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2]});
  for (size_t i = 0; i < base.size(); ++i)
    base[i] = low[i % 3] + std::round((base[i] - low[i % 3]) / range * 16383) * range / 16383;
  return base;
}

}  // namespace segmorph::bench
