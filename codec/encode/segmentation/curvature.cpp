#include "encode/segmentation/curvature.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace segmorph {

std::vector<double> minimum_curvature(const std::vector<double>& positions, const WeldedTopology& topology) {
  const size_t vertex_count = topology.welded_count();
  auto point = [&](uint32_t w) {
    return Eigen::Vector3d(positions[w * 3], positions[w * 3 + 1], positions[w * 3 + 2]);
  };

  // Area-weighted normals, and per directed edge (v, j) the area of the triangles beside it.
  std::vector<Eigen::Vector3d> normal(vertex_count, Eigen::Vector3d::Zero());
  const VertexAdjacency adjacency = vertex_adjacency(topology);
  std::vector<double> edge_area(adjacency.neighbour.size(), 0.0);
  std::vector<int> edge_triangles(adjacency.neighbour.size(), 0);
  auto edge_slot = [&](uint32_t v, uint32_t j) {
    const auto begin = adjacency.neighbour.begin() + adjacency.offset[v],
               end = adjacency.neighbour.begin() + adjacency.offset[v + 1];
    return size_t(std::lower_bound(begin, end, j) - adjacency.neighbour.begin());
  };
  for (size_t t = 0; t < topology.triangles.size(); t += 3) {
    const uint32_t a = topology.triangles[t], b = topology.triangles[t + 1], c = topology.triangles[t + 2];
    const Eigen::Vector3d n = (point(b) - point(a)).cross(point(c) - point(a));
    const double area = 0.5 * n.norm();
    for (uint32_t v : {a, b, c}) normal[v] += n;
    for (auto [v, j] : {std::pair{a, b}, {b, a}, {b, c}, {c, b}, {c, a}, {a, c}}) {
      edge_area[edge_slot(v, j)] += area;
      ++edge_triangles[edge_slot(v, j)];
    }
  }

  std::vector<double> curvature(vertex_count, 0.0);
  for (uint32_t v = 0; v < vertex_count; ++v) {
    const double length = normal[v].norm();
    if (!(length > 0) || adjacency.offset[v] == adjacency.offset[v + 1]) continue;
    // On an open border the ring is cut in half and the estimate meaningless.
    bool border = false;
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) border = border || edge_triangles[i] == 1;
    if (border) continue;
    const Eigen::Vector3d n = normal[v] / length;
    const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - n * n.transpose();
    Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero();
    double total = 0;
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
      const Eigen::Vector3d edge = point(adjacency.neighbour[i]) - point(v);
      const double squared = edge.squaredNorm();
      const Eigen::Vector3d tangent = projector * edge;
      if (!(squared > 0) || !(tangent.norm() > 0)) continue;
      const double kappa = -2.0 * n.dot(edge) / squared;  // positive where the surface bends away from n
      const Eigen::Vector3d direction = tangent.normalized();
      tensor += edge_area[i] * kappa * direction * direction.transpose();
      total += edge_area[i];
    }
    if (!(total > 0)) continue;
    tensor /= total;
    // The two eigenvalues of M in the tangent plane (its third eigenvector is n, with eigenvalue ~0).
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(tensor);
    const Eigen::Vector3d values = solver.eigenvalues();
    const Eigen::Matrix3d vectors = solver.eigenvectors();
    int normal_index = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(vectors.col(k).dot(n)) > std::fabs(vectors.col(normal_index).dot(n))) normal_index = k;
    double m[2];
    for (int k = 0, j = 0; k < 3; ++k)
      if (k != normal_index) m[j++] = values(k);
    const double k1 = 3 * m[0] - m[1], k2 = 3 * m[1] - m[0];
    curvature[v] = std::min(k1, k2);
  }
  return curvature;
}

}  // namespace segmorph
