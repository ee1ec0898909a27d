// FrameSequence: one animated primitive sampled over one clip, the codec's input and the decoder's output.
#pragma once

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace segmorph {

struct FrameSequence {
  size_t vertex_count = 0;  // V, in the primitive's own vertex order
  size_t frame_count = 0;   // F

  // F × V × 3 floats, frame-major: positions[(f * V + v) * 3 + c].
  std::vector<float> positions;
  // F frame times in seconds, strictly increasing. Float because glTF stores key times as float:
  // a time written out and read back is the same number.
  std::vector<float> times;
  // T × 3 vertex indices into V; empty for point and line primitives.
  std::vector<uint32_t> triangles;

  const float* frame(size_t f) const {
    assert(f < frame_count);
    return positions.data() + f * vertex_count * 3;
  }
  float* frame(size_t f) {
    assert(f < frame_count);
    return positions.data() + f * vertex_count * 3;
  }
  size_t triangle_count() const { return triangles.size() / 3; }
};

}  // namespace segmorph
