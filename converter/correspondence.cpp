#include "correspondence.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "metrics.h"

namespace segmorph {

std::vector<uint32_t> match_vertices(const std::vector<FrameSequence>& reference, const std::vector<FrameSequence>& other) {
  const size_t count = reference[0].vertex_count, other_count = other[0].vertex_count;
  std::vector<uint32_t> match(count);
  const float* first = reference[0].frame(0);
  const float* other_first = other[0].frame(0);
  if (count == other_count && std::equal(first, first + count * 3, other_first)) {
    for (uint32_t v = 0; v < count; ++v) match[v] = v;
    return match;
  }

  // A grid of the other's first-frame positions, cells about the mean spacing of the vertices.
  const double diagonal = std::max(bounding_box_diagonal(first, count), 1e-30);
  const double cell = diagonal / std::max(1.0, std::cbrt(double(other_count)));
  auto index = [&](double x) { return int64_t(std::floor(x / cell)); };
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return uint64_t(x * 73856093) ^ uint64_t(y * 19349663) ^ uint64_t(z * 83492791);
  };
  std::unordered_multimap<uint64_t, uint32_t> grid;
  grid.reserve(other_count);
  for (uint32_t u = 0; u < other_count; ++u)
    grid.emplace(key(index(other_first[u * 3]), index(other_first[u * 3 + 1]), index(other_first[u * 3 + 2])), u);

  auto distance2 = [](const float* a, const float* b) {
    double sum = 0;
    for (int c = 0; c < 3; ++c) sum += (double(a[c]) - b[c]) * (double(a[c]) - b[c]);
    return sum;
  };
  auto trajectory_distance = [&](uint32_t v, uint32_t u) {
    double sum = 0;
    for (size_t c = 0; c < reference.size(); ++c)
      for (size_t f = 0; f < reference[c].frame_count; ++f)
        sum += distance2(reference[c].frame(f) + v * 3, other[c].frame(f) + u * 3);
    return sum;
  };
  const double tie = 1e-4 * diagonal;
  std::vector<uint32_t> candidates;
  for (uint32_t v = 0; v < count; ++v) {
    const float* p = first + v * 3;
    const int64_t cx = index(p[0]), cy = index(p[1]), cz = index(p[2]);
    double nearest = INFINITY;
    // Search shells of cells outwards until the nearest found is closer than the next shell can be.
    for (int64_t radius = 0; radius <= 1 << 20; ++radius) {
      if (std::isfinite(nearest) && std::sqrt(nearest) + tie < (double(radius) - 1) * cell) break;
      for (int64_t dx = -radius; dx <= radius; ++dx)
        for (int64_t dy = -radius; dy <= radius; ++dy)
          for (int64_t dz = -radius; dz <= radius; ++dz) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != radius) continue;
            const auto range = grid.equal_range(key(cx + dx, cy + dy, cz + dz));
            for (auto it = range.first; it != range.second; ++it) nearest = std::min(nearest, distance2(p, other_first + it->second * 3));
          }
      if (radius > 2 && !std::isfinite(nearest) && double(radius) * cell > 4 * diagonal) break;
    }
    // Among the (nearly) nearest, the best trajectory.
    candidates.clear();
    const double limit = std::pow(std::sqrt(nearest) + tie, 2);
    const int64_t reach = int64_t(std::ceil((std::sqrt(nearest) + tie) / cell)) + 1;
    for (int64_t dx = -reach; dx <= reach; ++dx)
      for (int64_t dy = -reach; dy <= reach; ++dy)
        for (int64_t dz = -reach; dz <= reach; ++dz) {
          const auto range = grid.equal_range(key(cx + dx, cy + dy, cz + dz));
          for (auto it = range.first; it != range.second; ++it)
            if (distance2(p, other_first + it->second * 3) <= limit) candidates.push_back(it->second);
        }
    uint32_t best = candidates.empty() ? 0 : candidates[0];
    double best_distance = INFINITY;
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    for (uint32_t u : candidates) {
      const double d = candidates.size() == 1 ? 0 : trajectory_distance(v, u);
      if (d < best_distance) best_distance = d, best = u;
    }
    match[v] = best;
  }
  return match;
}

}  // namespace segmorph
