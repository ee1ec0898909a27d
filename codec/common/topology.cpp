#include "common/topology.h"

#include <algorithm>
#include <cassert>
#include <cstring>
#include <numeric>

namespace segmorph {
namespace {

// Bits of a coordinate with -0 folded onto +0, so that the two zeros weld.
uint32_t coordinate_bits(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  return bits == 0x80000000u ? 0u : bits;
}

uint32_t raw_bits(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  return bits;
}

bool same_trajectory(const std::vector<FrameSequence>& clips, const float* also, uint32_t a, uint32_t b) {
  if (also && std::memcmp(&also[a * 3], &also[b * 3], 3 * sizeof(float)) != 0) return false;  // bits: +0 ≠ −0
  for (const FrameSequence& clip : clips)
    for (size_t f = 0; f < clip.frame_count; ++f) {
      const float* frame = clip.frame(f);
      for (int c = 0; c < 3; ++c)
        if (coordinate_bits(frame[a * 3 + c]) != coordinate_bits(frame[b * 3 + c])) return false;
    }
  return true;
}

uint32_t find_root(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];  // path halving
    x = parent[x];
  }
  return x;
}

}  // namespace

WeldedTopology welded_topology(std::vector<uint32_t> welded_index, size_t welded_count,
                               const std::vector<uint32_t>& triangles) {
  WeldedTopology topology;
  topology.welded_index = std::move(welded_index);
  topology.representative.assign(welded_count, UINT32_MAX);
  for (uint32_t v = 0; v < topology.welded_index.size(); ++v) {
    uint32_t& representative = topology.representative[topology.welded_index[v]];
    if (representative == UINT32_MAX) representative = v;
  }

  topology.triangles.reserve(triangles.size());
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    uint32_t a = topology.welded_index[triangles[t]];
    uint32_t b = topology.welded_index[triangles[t + 1]];
    uint32_t c = topology.welded_index[triangles[t + 2]];
    if (a == b || b == c || a == c) continue;
    topology.triangles.insert(topology.triangles.end(), {a, b, c});
  }

  std::vector<uint32_t> parent(welded_count);
  std::iota(parent.begin(), parent.end(), 0u);
  for (size_t t = 0; t < topology.triangles.size(); t += 3)
    for (int k = 1; k < 3; ++k) {
      uint32_t a = find_root(parent, topology.triangles[t]);
      uint32_t b = find_root(parent, topology.triangles[t + k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  topology.component.assign(welded_count, 0);
  std::vector<uint32_t> component_of_root(welded_count, UINT32_MAX);
  for (uint32_t w = 0; w < welded_count; ++w) {
    uint32_t& component = component_of_root[find_root(parent, w)];
    if (component == UINT32_MAX) component = uint32_t(topology.component_count++);
    topology.component[w] = component;
  }
  return topology;
}

WeldedTopology weld_topology(const std::vector<FrameSequence>& clips, const std::vector<float>* also_equal) {
  assert(!clips.empty());
  const size_t vertex_count = clips[0].vertex_count;
  for (const FrameSequence& clip : clips) {
    assert(clip.vertex_count == vertex_count);
    assert(clip.triangles == clips[0].triangles);
    (void)clip;
  }

  assert(!also_equal || also_equal->size() == vertex_count * 3);
  const float* also = also_equal ? also_equal->data() : nullptr;

  // FNV-1a over each vertex's whole trajectory (and its `also_equal` position).
  std::vector<uint64_t> hash(vertex_count, 1469598103934665603ull);
  if (also)
    for (size_t v = 0; v < vertex_count; ++v)
      for (int c = 0; c < 3; ++c) {
        hash[v] ^= raw_bits(also[v * 3 + c]);
        hash[v] *= 1099511628211ull;
      }
  for (const FrameSequence& clip : clips)
    for (size_t f = 0; f < clip.frame_count; ++f) {
      const float* frame = clip.frame(f);
      for (size_t v = 0; v < vertex_count; ++v)
        for (int c = 0; c < 3; ++c) {
          hash[v] ^= coordinate_bits(frame[v * 3 + c]);
          hash[v] *= 1099511628211ull;
        }
    }

  std::vector<uint32_t> order(vertex_count);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return hash[a] != hash[b] ? hash[a] < hash[b] : a < b; });

  // Within a run of equal hashes, each vertex joins the first earlier vertex with the same trajectory.
  // The first original vertex of each group becomes its representative.
  std::vector<uint32_t> leader(vertex_count);
  std::vector<uint32_t> run_leaders;
  for (size_t begin = 0; begin < vertex_count;) {
    size_t end = begin + 1;
    while (end < vertex_count && hash[order[end]] == hash[order[begin]]) ++end;
    run_leaders.clear();
    for (size_t i = begin; i < end; ++i) {
      const uint32_t v = order[i];
      leader[v] = v;
      for (uint32_t candidate : run_leaders)
        if (same_trajectory(clips, also, v, candidate)) {
          leader[v] = candidate;
          break;
        }
      if (leader[v] == v) run_leaders.push_back(v);
    }
    begin = end;
  }

  std::vector<uint32_t> welded_index(vertex_count, 0);
  std::vector<uint32_t> welded_of_leader(vertex_count, UINT32_MAX);
  uint32_t welded_count = 0;
  for (uint32_t v = 0; v < vertex_count; ++v) {
    uint32_t& welded = welded_of_leader[leader[v]];
    if (welded == UINT32_MAX) welded = welded_count++;
    welded_index[v] = welded;
  }
  return welded_topology(std::move(welded_index), welded_count, clips[0].triangles);
}

VertexAdjacency vertex_adjacency(const WeldedTopology& topology) {
  // Each triangle's three edges in both directions, bucketed by their first vertex (a counting sort: a sort of
  // all 6T directed edges took a tenth of the decoder's frame loop on the cow), then each vertex's short list
  // sorted and its duplicates (edges shared by two triangles) dropped.
  const size_t welded_count = topology.welded_count();
  std::vector<uint32_t> start(welded_count + 1, 0);
  for (uint32_t v : topology.triangles) start[v + 1] += 2;
  for (size_t w = 0; w < welded_count; ++w) start[w + 1] += start[w];
  std::vector<uint32_t> fill(start.begin(), start.end() - 1), bucket(start.back());
  for (size_t t = 0; t < topology.triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = topology.triangles[t + size_t(k)], b = topology.triangles[t + size_t((k + 1) % 3)];
      bucket[fill[a]++] = b;
      bucket[fill[b]++] = a;
    }
  VertexAdjacency adjacency;
  adjacency.offset.assign(welded_count + 1, 0);
  adjacency.neighbour.reserve(bucket.size() / 2);
  for (size_t w = 0; w < welded_count; ++w) {
    const auto begin = bucket.begin() + ptrdiff_t(start[w]), end = bucket.begin() + ptrdiff_t(start[w + 1]);
    std::sort(begin, end);
    adjacency.neighbour.insert(adjacency.neighbour.end(), begin, std::unique(begin, end));
    adjacency.offset[w + 1] = uint32_t(adjacency.neighbour.size());
  }
  return adjacency;
}

}  // namespace segmorph
