#include "correspondence.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <unordered_map>

#include "metrics.h"
#include "parallel.h"

namespace segmorph {

std::vector<uint32_t> match_vertices(const std::vector<FrameSequence>& reference,
                                     const std::vector<FrameSequence>& other, size_t threads) {
  assert(!reference.empty() && reference.size() == other.size() && other[0].vertex_count > 0);
  const size_t count = reference[0].vertex_count, other_count = other[0].vertex_count;
  std::vector<uint32_t> match(count);
  const float* first = reference[0].frame(0);
  const float* other_first = other[0].frame(0);
  if (count == other_count && std::equal(first, first + count * 3, other_first)) {
    for (uint32_t v = 0; v < count; ++v) match[v] = v;
    return match;
  }

  // A grid of the other's first-frame positions, cells about the mean spacing of the vertices.
  const double diagonal = bounding_box_diagonal(other_first, other_count);
  const double cell = diagonal > 0 ? diagonal / std::max(1.0, std::cbrt(double(other_count))) : 1.0;
  // Clamped so that far outliers cannot overflow; clamping only brings a point nearer the grid's box.
  auto index = [&](double x) { return int64_t(std::clamp(std::floor(x / cell), -1e15, 1e15)); };
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return uint64_t(x * 73856093) ^ uint64_t(y * 19349663) ^ uint64_t(z * 83492791);
  };
  std::unordered_multimap<uint64_t, uint32_t> grid;
  grid.reserve(other_count);
  int64_t low[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, high[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  for (uint32_t u = 0; u < other_count; ++u) {
    int64_t cell_index[3];
    for (int k = 0; k < 3; ++k) {
      cell_index[k] = index(other_first[u * 3 + size_t(k)]);
      low[k] = std::min(low[k], cell_index[k]);
      high[k] = std::max(high[k], cell_index[k]);
    }
    grid.emplace(key(cell_index[0], cell_index[1], cell_index[2]), u);
  }

  auto distance2 = [](const float* a, const float* b) {
    double sum = 0;
    for (int c = 0; c < 3; ++c) sum += (double(a[c]) - b[c]) * (double(a[c]) - b[c]);
    return sum;
  };
  // The trajectory distance of v and u, or a value >= bound as soon as it is known to reach it.
  auto trajectory_distance = [&](uint32_t v, uint32_t u, double bound) {
    double sum = 0;
    for (size_t c = 0; c < reference.size(); ++c)
      for (size_t f = 0; f < reference[c].frame_count; ++f) {
        sum += distance2(reference[c].frame(f) + v * 3, other[c].frame(f) + u * 3);
        if (sum >= bound) return sum;
      }
    return sum;
  };
  const auto match_range = [&](size_t begin, size_t end) {
    for (uint32_t v = uint32_t(begin); v < end; ++v) {
      const float* p = first + v * 3;
      const int64_t centre[3] = {index(p[0]), index(p[1]), index(p[2])};
      // Shells of cells outwards, from the first that meets the grid's box to the last: a vertex in shell r
      // is at least (r - 1) cells away in the first frame alone, so the search also ends once that exceeds
      // the best trajectory distance found. Only the part of a shell inside the box is visited.
      int64_t near_shell = 0, far_shell = 0, from[3], to[3];
      for (int k = 0; k < 3; ++k) {
        near_shell = std::max({near_shell, low[k] - centre[k], centre[k] - high[k]});
        far_shell = std::max({far_shell, centre[k] - low[k], high[k] - centre[k]});
      }
      double best = INFINITY;
      uint32_t best_u = 0;
      auto visit = [&](int64_t dx, int64_t dy, int64_t dz) {
        const auto range = grid.equal_range(key(centre[0] + dx, centre[1] + dy, centre[2] + dz));
        for (auto it = range.first; it != range.second; ++it) {
          const double d = trajectory_distance(v, it->second, best);
          if (d < best) best = d, best_u = it->second;
        }
      };
      for (int64_t radius = near_shell; radius <= far_shell; ++radius) {
        if (std::isfinite(best) && (double(radius) - 1) * cell > std::sqrt(best)) break;
        for (int k = 0; k < 3; ++k)
          from[k] = std::max(-radius, low[k] - centre[k]), to[k] = std::min(radius, high[k] - centre[k]);
        for (int64_t dx = from[0]; dx <= to[0]; ++dx)
          for (int64_t dy = from[1]; dy <= to[1]; ++dy) {
            if (std::abs(dx) == radius || std::abs(dy) == radius) {
              for (int64_t dz = from[2]; dz <= to[2]; ++dz) visit(dx, dy, dz);
            } else {
              if (from[2] == -radius) visit(dx, dy, -radius);
              if (to[2] == radius) visit(dx, dy, radius);
            }
          }
      }
      match[v] = best_u;
    }
  };
  // Each vertex's search reads the grid and the frames only: the vertices are split over threads.
  parallel_ranges(count, thread_count(threads), match_range);
  return match;
}

}  // namespace segmorph
