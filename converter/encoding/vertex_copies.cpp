// merge_copies (compress_primitives.h): the copies of a vertex a glTF file stores once per triangle, coded once.
#include <algorithm>
#include <cstring>

#include "encoding/compress_primitives.h"

namespace segmorph {

BaseMesh merge_copies(const BaseMesh& base, const std::vector<FrameSequence>& frames, std::vector<uint32_t>& first) {
  const size_t vertex_count = base.vertex_count;
  // What a vertex is made of, as columns of `width` floats per vertex: each attribute, then each frame's positions.
  struct Column {
    const float* values;
    size_t width;
  };
  std::vector<Column> columns;
  for (const BaseMeshAttribute& attribute : base.attributes)
    columns.push_back({attribute.values.data(), size_t(attribute.components)});
  for (const FrameSequence& clip : frames)
    for (size_t f = 0; f < clip.frame_count; ++f) columns.push_back({clip.frame(f), 3});
  // Each vertex's bits, hashed (FNV-1a over the 32-bit words); equal hashes are compared in full (only distinct
  // vertices whose hashes collide cost more than one comparison).
  std::vector<std::pair<uint64_t, uint32_t>> hashed(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    uint64_t hash = 0xcbf29ce484222325u;
    for (const Column& column : columns)
      for (size_t c = 0; c < column.width; ++c) {
        uint32_t bits;
        std::memcpy(&bits, &column.values[v * column.width + c], 4);
        hash = (hash ^ bits) * 0x100000001b3u;
      }
    hashed[v] = {hash, uint32_t(v)};
  }
  std::sort(hashed.begin(), hashed.end());
  auto same = [&](uint32_t a, uint32_t b) {
    for (const Column& column : columns)
      if (std::memcmp(&column.values[a * column.width], &column.values[b * column.width],
                      column.width * sizeof(float)) != 0)
        return false;
    return true;
  };
  std::vector<uint32_t> leader(vertex_count);
  for (size_t i = 0; i < vertex_count;) {
    size_t end = i;
    while (end < vertex_count && hashed[end].first == hashed[i].first) ++end;
    // Within a run of equal hashes (ascending vertex order), each vertex joins the first earlier one it equals.
    for (size_t j = i; j < end; ++j) {
      const uint32_t v = hashed[j].second;
      leader[v] = v;
      for (size_t k = i; k < j; ++k)
        if (leader[hashed[k].second] == hashed[k].second && same(hashed[k].second, v)) {
          leader[v] = hashed[k].second;
          break;
        }
    }
    i = end;
  }
  // Never two corners of one triangle: Draco drops a triangle with a repeated vertex, and with it a vertex that
  // only such triangles use (and its animation). A corner that would repeat another keeps its own vertex.
  for (size_t t = 0; t + 2 < base.triangles.size(); t += 3) {
    const uint32_t* corner = &base.triangles[t];
    for (int k = 1; k < 3; ++k)
      for (int j = 0; j < k; ++j)
        if (corner[k] != corner[j] && leader[corner[k]] == leader[corner[j]]) {
          // The one that is not the leader goes back to itself (nothing joined it, so nothing else moves).
          const uint32_t copy = leader[corner[k]] == corner[k] ? corner[j] : corner[k];
          leader[copy] = copy;
        }
  }
  std::vector<uint32_t> index(vertex_count);
  first.clear();
  for (size_t v = 0; v < vertex_count; ++v) {
    if (leader[v] == v) {
      index[v] = uint32_t(first.size());
      first.push_back(uint32_t(v));
    } else {
      index[v] = index[leader[v]];
    }
  }
  BaseMesh merged;
  merged.vertex_count = first.size();
  for (const BaseMeshAttribute& attribute : base.attributes) {
    BaseMeshAttribute out = attribute;
    const size_t components = size_t(attribute.components);
    out.values.resize(first.size() * components);
    for (size_t m = 0; m < first.size(); ++m)
      std::copy_n(&attribute.values[first[m] * components], components, &out.values[m * components]);
    merged.attributes.push_back(std::move(out));
  }
  merged.triangles.reserve(base.triangles.size());
  for (uint32_t v : base.triangles) merged.triangles.push_back(index[v]);
  return merged;
}

}  // namespace segmorph
