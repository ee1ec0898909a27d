// Frames from one vertex order into another: out[v] = in[index[v]], rows of 3 floats. The decoder (welded frames into
// the base mesh's order), the encoder (its reconstruction likewise) and the container (frames into Draco's order)
// gather so.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace segmorph {

class VertexGather {
 public:
  // index: V entries, the source row of each output row.
  explicit VertexGather(const std::vector<uint32_t>& index);

  size_t vertex_count() const { return index_.size(); }
  // out[0 .. V × 3) := the rows of `in` the index names.
  void gather(const float* in, float* out) const;
  // The same, appended to `out` (which grows without being zero-filled first).
  void append(const float* in, std::vector<float>& out) const;

 private:
  // Output rows v, v + 1, ... from source rows w, w + 1, ... (usually few and long where the index comes from welding):
  // copied run by run. Empty when runs are short (then row by row).
  struct Run {
    size_t from, count;
  };
  std::vector<uint32_t> index_;
  std::vector<Run> runs_;
};

}  // namespace segmorph
