#include "common/vertex_gather.h"

#include <cstring>

namespace segmorph {

VertexGather::VertexGather(const std::vector<uint32_t>& index) : index_(index) {
  const size_t vertex_count = index.size();
  bool long_runs = true;
  for (size_t v = 0; v < vertex_count && long_runs; ++v) {
    const size_t w = index[v];
    if (!runs_.empty() && runs_.back().from + runs_.back().count == w)
      ++runs_.back().count;
    else
      runs_.push_back({w, 1});
    long_runs = runs_.size() * 8 <= vertex_count;
  }
  if (!long_runs) runs_.clear();
}

void VertexGather::gather(const float* in, float* out) const {
  if (!runs_.empty()) {
    for (const Run& run : runs_) {
      std::memcpy(out, in + run.from * 3, run.count * 3 * sizeof(float));
      out += run.count * 3;
    }
    return;
  }
  for (size_t v = 0; v < index_.size(); ++v) {
    const float* row = &in[size_t(index_[v]) * 3];
    out[v * 3] = row[0], out[v * 3 + 1] = row[1], out[v * 3 + 2] = row[2];
  }
}

void VertexGather::append(const float* in, std::vector<float>& out) const {
  if (!runs_.empty()) {
    for (const Run& run : runs_) out.insert(out.end(), in + run.from * 3, in + (run.from + run.count) * 3);
    return;
  }
  const size_t at = out.size();
  out.resize(at + index_.size() * 3);
  gather(in, &out[at]);
}

}  // namespace segmorph
