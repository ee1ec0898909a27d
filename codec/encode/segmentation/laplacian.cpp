#include "encode/segmentation/laplacian.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace segmorph {
namespace {

double distance(const std::vector<double>& positions, uint32_t a, uint32_t b) {
  const double dx = positions[3 * size_t(a)] - positions[3 * size_t(b)];
  const double dy = positions[3 * size_t(a) + 1] - positions[3 * size_t(b) + 1];
  const double dz = positions[3 * size_t(a) + 2] - positions[3 * size_t(b) + 2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Area of a triangle from its edge lengths by Kahan's rearrangement of Heron's formula, accurate for
// needle- and cap-shaped triangles where the textbook formula cancels catastrophically. The four factors
// are multiplied in pairs so that lengths up to ~1e150 do not overflow. Returns 0 when the lengths
// violate the triangle inequality (which mollification rules out except through rounding).
bool has_repeated_corner(const std::vector<uint32_t>& triangles, size_t t) {
  const uint32_t a = triangles[3 * t], b = triangles[3 * t + 1], c = triangles[3 * t + 2];
  return a == b || b == c || c == a;
}

double triangle_area(double l0, double l1, double l2) {
  double a = l0, b = l1, c = l2;  // sorted a ≥ b ≥ c
  if (a < b) std::swap(a, b);
  if (b < c) std::swap(b, c);
  if (a < b) std::swap(a, b);
  const double slack = c - (a - b);
  if (!(slack > 0) || !(c > 0)) return 0;
  return 0.25 * std::sqrt((a + (b + c)) * slack) * std::sqrt((c + (a - b)) * (a + (b - c)));
}

}  // namespace

Status cotangent_laplacian(const std::vector<double>& positions, const std::vector<uint32_t>& triangles,
                           CotangentLaplacian& out) {
  assert(positions.size() % 3 == 0 && triangles.size() % 3 == 0);
  const size_t vertex_count = positions.size() / 3;
  const size_t triangle_count = triangles.size() / 3;
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!std::isfinite(positions[i])) {
      return Status(StatusCode::bad_data, "laplacian: vertex " + std::to_string(i / 3) + " has a non-finite position");
    }
  }

  // Edge lengths, lengths[3t + k] opposite corner k of triangle t, and the mollification δ: the
  // smallest length that, added to every edge, gives every corner k a slack l_i + l_j − l_k ≥ ε.
  std::vector<double> lengths(3 * triangle_count);
  double length_sum = 0;
  size_t used_triangles = 0;
  for (size_t t = 0; t < triangle_count; ++t) {
    if (has_repeated_corner(triangles, t)) continue;
    ++used_triangles;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = triangles[3 * t + (k + 1) % 3], b = triangles[3 * t + (k + 2) % 3];
      assert(a < vertex_count && b < vertex_count);
      lengths[3 * t + k] = distance(positions, a, b);
      length_sum += lengths[3 * t + k];
    }
  }
  if (!std::isfinite(length_sum)) {
    return Status(StatusCode::bad_data, "laplacian: positions are too large for double-precision edge lengths");
  }
  const double margin = used_triangles ? kMollificationMargin * length_sum / double(3 * used_triangles) : 0;
  double delta = 0;
  for (size_t t = 0; t < triangle_count; ++t) {
    if (has_repeated_corner(triangles, t)) continue;
    const double* l = &lengths[3 * t];
    for (int k = 0; k < 3; ++k) delta = std::max(delta, margin - (l[(k + 1) % 3] + l[(k + 2) % 3] - l[k]));
  }

  // Per triangle: cot of the angle at corner k, from the law of cosines (l_i² + l_j² − l_k²) / (4 area),
  // goes to the edge opposite k; a third of the area goes to each corner.
  std::vector<Eigen::Triplet<double>> edge_weights;  // (i < j, −cot/2), summed per edge below
  edge_weights.reserve(3 * triangle_count);
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(Eigen::Index(vertex_count));
  for (size_t t = 0; t < triangle_count; ++t) {
    if (has_repeated_corner(triangles, t)) continue;
    const double l[3] = {lengths[3 * t] + delta, lengths[3 * t + 1] + delta, lengths[3 * t + 2] + delta};
    const double area = triangle_area(l[0], l[1], l[2]);
    if (!(area > 0)) continue;  // only when every edge has length 0 (margin 0): contributes nothing
    for (int k = 0; k < 3; ++k) {
      const double li = l[(k + 1) % 3], lj = l[(k + 2) % 3];
      const double cot = (li * li + lj * lj - l[k] * l[k]) / (4 * area);
      const uint32_t a = triangles[3 * t + (k + 1) % 3], b = triangles[3 * t + (k + 2) % 3];
      edge_weights.emplace_back(std::min(a, b), std::max(a, b), -0.5 * cot);
      mass[triangles[3 * t + k]] += area / 3;
    }
  }

  // Upper triangle summed per edge, then mirrored: K is symmetric bit for bit, and each diagonal entry
  // is minus the sum of exactly the off-diagonal values stored in its row.
  const Eigen::Index n = Eigen::Index(vertex_count);
  Eigen::SparseMatrix<double> upper(n, n);
  upper.setFromTriplets(edge_weights.begin(), edge_weights.end());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(2 * size_t(upper.nonZeros()) + vertex_count);
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(Eigen::Index(vertex_count));
  for (Eigen::Index j = 0; j < upper.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(upper, j); it; ++it) {
      entries.emplace_back(it.row(), it.col(), it.value());
      entries.emplace_back(it.col(), it.row(), it.value());
      diagonal[it.row()] -= it.value();
      diagonal[it.col()] -= it.value();
    }
  }
  for (size_t i = 0; i < vertex_count; ++i) {
    if (diagonal[Eigen::Index(i)] != 0) {
      entries.emplace_back(Eigen::Index(i), Eigen::Index(i), diagonal[Eigen::Index(i)]);
    }
  }
  for (const auto& entry : entries) {
    if (!std::isfinite(entry.value())) {
      return Status(StatusCode::bad_data, "laplacian: positions are too large for double-precision cotangents");
    }
  }

  // Strictly positive masses: vertices without a triangle get a tiny share of the mean.
  double mass_sum = 0;
  size_t massive = 0;
  for (size_t i = 0; i < vertex_count; ++i) {
    if (mass[Eigen::Index(i)] > 0) {
      mass_sum += mass[Eigen::Index(i)];
      ++massive;
    }
  }
  const double isolated_mass = massive ? kIsolatedMassFraction * mass_sum / double(massive) : 1.0;
  for (size_t i = 0; i < vertex_count; ++i) {
    if (!(mass[Eigen::Index(i)] > 0)) mass[Eigen::Index(i)] = isolated_mass;
  }

  out.stiffness.resize(n, n);
  out.stiffness.setFromTriplets(entries.begin(), entries.end());
  out.mass = std::move(mass);
  out.mollification = delta;
  return Status::Ok();
}

std::vector<double> welded_positions(const float* frame, const WeldedTopology& topology) {
  std::vector<double> positions(3 * topology.welded_count());
  for (size_t w = 0; w < topology.welded_count(); ++w) {
    for (int c = 0; c < 3; ++c) positions[3 * w + c] = frame[3 * size_t(topology.representative[w]) + c];
  }
  return positions;
}

}  // namespace segmorph
