#include "encode/segmentation/feature_points.h"

#include <algorithm>
#include <cmath>

#include "encode/segmentation/diffusion.h"

namespace segmorph {
namespace {

uint32_t farthest(const std::vector<double>& distance, const std::vector<uint32_t>& vertices) {
  uint32_t best = vertices.front();
  for (uint32_t v : vertices)
    if (distance[v] > distance[best] && std::isfinite(distance[v])) best = v;
  return best;
}

}  // namespace

std::vector<uint32_t> maxima(const std::vector<double>& f, const std::vector<uint32_t>& vertices,
                             const std::vector<double>& positions, const VertexAdjacency& adjacency, double radius) {
  std::vector<uint8_t> in_component(f.size(), 0);
  for (uint32_t v : vertices) in_component[v] = 1;
  GeodesicBall ball(positions, adjacency);
  std::vector<uint32_t> found;
  for (uint32_t v : vertices) {
    bool ring_maximum = true;  // cheap first test: the 1-ring
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1] && ring_maximum; ++i) {
      const uint32_t u = adjacency.neighbour[i];
      ring_maximum = f[u] < f[v] || (f[u] == f[v] && v < u);
    }
    if (!ring_maximum) continue;
    // Ended by the first vertex within the radius that is larger (most are found within a few rings).
    ball.reach(v, radius, [&](uint32_t u) {
      return in_component[u] && u != v && (f[u] > f[v] || (f[u] == f[v] && u < v));
    });
    if (!ball.stopped()) found.push_back(v);
  }
  return found;
}

std::array<uint32_t, 2> farthest_points(const std::vector<double>& positions, const VertexAdjacency& adjacency,
                                        const std::vector<uint32_t>& vertices) {
  const uint32_t v1 = farthest(edge_path_distances(positions, adjacency, vertices.front()), vertices);
  const uint32_t v2 = farthest(edge_path_distances(positions, adjacency, v1), vertices);
  return {v1, v2};
}

std::vector<uint32_t> feature_points(const std::vector<double>& f1, const std::vector<double>& f2,
                                     const std::vector<uint32_t>& vertices, const std::vector<double>& positions,
                                     const VertexAdjacency& adjacency, double radius,
                                     const std::array<uint32_t, 2>& farthest) {
  const std::vector<uint32_t> e1 = maxima(f1, vertices, positions, adjacency, radius);
  const std::vector<uint32_t> e2 = maxima(f2, vertices, positions, adjacency, radius);
  GeodesicBall ball(positions, adjacency);
  std::vector<uint32_t> features;
  for (uint32_t p : e1) {
    ball.reach(p, radius);
    const bool near = std::any_of(e2.begin(), e2.end(), [&](uint32_t q) { return ball.distance(q) <= radius; });
    if (near) features.push_back(p);
  }
  if (features.empty()) features = {farthest[0], farthest[1]};
  return features;
}

}  // namespace segmorph
