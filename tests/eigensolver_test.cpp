#include "encode/segmentation/eigensolver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "common/topology.h"
#include "encode/segmentation/laplacian.h"

#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::Mesh;

// The icosahedron subdivided `level` times (10·4^level + 2 vertices), projected onto the sphere of
// `radius` around `center`.
Mesh icosphere(int level, double radius = 1, Eigen::Vector3d center = Eigen::Vector3d::Zero()) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> points = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                         {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<uint32_t> triangles = {0, 11, 5, 0, 5,  1,  0,  1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                                     4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9,  4, 3, 4,  2,  3, 2, 6, 3,
                                     6, 8,  3, 8,  9,  4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      points.push_back((points[a] + points[b]) / 2);
      return midpoints[key] = uint32_t(points.size() - 1);
    };
    std::vector<uint32_t> finer;
    for (size_t t = 0; t < triangles.size(); t += 3) {
      const uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    triangles = std::move(finer);
  }
  Mesh mesh;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d q = center + radius * p.normalized();
    mesh.positions.insert(mesh.positions.end(), {q.x(), q.y(), q.z()});
  }
  mesh.triangles = std::move(triangles);
  return mesh;
}

// An irregular ellipsoid (semi-axes 1, 0.7, 0.45): an icosphere whose vertices are moved at random by up
// to a third of an edge, projected back to the sphere, then stretched. No symmetry, so its low
// eigenvalues are simple and eigenvectors are defined up to sign.
Mesh irregular_ellipsoid(int level, unsigned seed) {
  Mesh mesh = icosphere(level);
  std::mt19937 random(seed);
  const double edge = 1.1 / std::pow(2.0, level);
  std::uniform_real_distribution<double> offset(-edge / 3, edge / 3);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    Eigen::Vector3d p(&mesh.positions[3 * v]);
    p += Eigen::Vector3d(offset(random), offset(random), offset(random));
    p.normalize();
    mesh.positions[3 * v] = p.x();
    mesh.positions[3 * v + 1] = 0.7 * p.y();
    mesh.positions[3 * v + 2] = 0.45 * p.z();
  }
  return mesh;
}

CotangentLaplacian build(const Mesh& mesh) {
  CotangentLaplacian laplacian;
  const Status status = cotangent_laplacian(mesh.positions, mesh.triangles, laplacian);
  EXPECT_TRUE(status.ok()) << status.message();
  return laplacian;
}

Eigenpairs solve(const CotangentLaplacian& laplacian, size_t count, EigenMethod method = EigenMethod::automatic) {
  Eigenpairs pairs;
  EigenSettings settings;
  settings.method = method;
  const Status status = smallest_eigenpairs(laplacian.stiffness, laplacian.mass, count, pairs, settings);
  EXPECT_TRUE(status.ok()) << status.message();
  return pairs;
}

// ΦᵀMΦ = I within 1e-8; values ascending and ≥ 0; K φ = λ M φ with a residual ‖Kφ − λMφ‖_{M⁻¹} below
// 1e-9 of max_i K_ii / M_ii (the Rayleigh quotient of one vertex's hat function, a lower bound on the
// largest eigenvalue, so the scale of the backward error a double-precision solver can promise);
// largest-magnitude entries positive.
void expect_eigenpairs(const CotangentLaplacian& laplacian, const Eigenpairs& pairs) {
  const Eigen::MatrixXd& phi = pairs.vectors;
  ASSERT_EQ(phi.rows(), laplacian.mass.size());
  ASSERT_EQ(phi.cols(), pairs.values.size());
  const Eigen::MatrixXd gram = phi.transpose() * laplacian.mass.asDiagonal() * phi;
  EXPECT_LE((gram - Eigen::MatrixXd::Identity(phi.cols(), phi.cols())).cwiseAbs().maxCoeff(), 1e-8);
  const Eigen::VectorXd inverse_sqrt_mass = laplacian.mass.cwiseSqrt().cwiseInverse();
  const double scale = Eigen::VectorXd(laplacian.stiffness.diagonal()).cwiseQuotient(laplacian.mass).maxCoeff();
  for (Eigen::Index i = 0; i < phi.cols(); ++i) {
    if (i > 0) {
      EXPECT_LE(pairs.values[i - 1], pairs.values[i]);
    }
    EXPECT_GE(pairs.values[i], 0.0);
    const Eigen::VectorXd k_phi = laplacian.stiffness * phi.col(i);
    const Eigen::VectorXd m_phi = laplacian.mass.cwiseProduct(phi.col(i));
    const double residual = inverse_sqrt_mass.cwiseProduct(k_phi - pairs.values[i] * m_phi).norm();
    EXPECT_LE(residual, 1e-9 * scale) << "pair " << i;
    Eigen::Index largest;
    phi.col(i).cwiseAbs().maxCoeff(&largest);
    EXPECT_GT(phi(largest, i), 0.0) << "pair " << i;
  }
}

TEST(Eigensolver, SphereSpectrumIsSphericalHarmonics) {
  // The unit sphere's Laplace–Beltrami eigenvalues are l(l+1) with multiplicity 2l + 1: 0; 2 ×3; 6 ×5;
  // 12 ×7; 20 ×9. At 2562 vertices (edges ~0.075) the cotangent/lumped-mass discretisation is O(h²)
  // accurate: the measured worst errors are < 0.001 % (l = 1), 0.14 % (l = 2), 0.43 % (l = 3) and 0.65 %
  // (l = 4), and they shrink 4× per subdivision. The tolerance, 1 %, leaves room for that and still
  // tells l(l+1) from its neighbours by far: a multiplicity off by one puts a value 40 % or more away.
  const Mesh mesh = icosphere(4);
  ASSERT_EQ(mesh.vertex_count(), 2562u);
  const CotangentLaplacian laplacian = build(mesh);
  const Eigenpairs pairs = solve(laplacian, 25, EigenMethod::shift_invert);
  ASSERT_EQ(pairs.values.size(), 25);
  expect_eigenpairs(laplacian, pairs);
  EXPECT_LE(pairs.values[0], 1e-10);
  Eigen::Index index = 1;
  for (int l = 1; l <= 4; ++l) {
    const double expected = l * (l + 1), tolerance = 0.01 * expected;
    for (int m = 0; m < 2 * l + 1; ++m, ++index) {
      EXPECT_NEAR(pairs.values[index], expected, tolerance) << "l = " << l << ", eigenvalue " << index;
    }
  }
}

// Regression: single-vector Lanczos skipped one copy of the 9-fold l = 4 eigenvalue of a 10242-vertex
// sphere and returned l = 5's 30 in its place, reporting success. The inertia check must catch it.
TEST(Eigensolver, RepeatedEigenvaluesAreNotSkipped) {
  const Mesh sphere = icosphere(5);
  const CotangentLaplacian laplacian = build(sphere);
  const Eigenpairs pairs = solve(laplacian, 25, EigenMethod::shift_invert);
  ASSERT_EQ(pairs.values.size(), 25);
  for (Eigen::Index i = 16; i < 25; ++i) EXPECT_NEAR(pairs.values[i], 20.0, 0.01 * 20) << i;

  // Two copies of one irregular ellipsoid side by side: every eigenvalue is exactly double.
  const Mesh one = irregular_ellipsoid(3, 2);
  Mesh two = one;
  for (size_t v = 0; v < one.vertex_count(); ++v) {
    two.positions.insert(two.positions.end(),
                         {one.positions[3 * v] + 3, one.positions[3 * v + 1], one.positions[3 * v + 2]});
  }
  for (uint32_t v : one.triangles) two.triangles.push_back(v + uint32_t(one.vertex_count()));
  const CotangentLaplacian two_laplacian = build(two);
  const Eigenpairs doubled = solve(two_laplacian, 16, EigenMethod::shift_invert);
  const Eigenpairs single = solve(build(one), 8, EigenMethod::shift_invert);
  expect_eigenpairs(two_laplacian, doubled);
  for (Eigen::Index i = 0; i < 16; ++i) {
    EXPECT_NEAR(doubled.values[i], single.values[i / 2], 1e-8 * single.values[1]) << i;
  }
}

TEST(Eigensolver, FirstEigenpairIsZeroWithAConstantVector) {
  // Both paths: shift-invert on 2562 vertices, dense on 162.
  for (const auto& [level, method] : {std::pair(4, EigenMethod::shift_invert), std::pair(2, EigenMethod::dense)}) {
    const Mesh mesh = irregular_ellipsoid(level, 3);
    const CotangentLaplacian laplacian = build(mesh);
    const Eigenpairs pairs = solve(laplacian, 6, method);
    expect_eigenpairs(laplacian, pairs);
    EXPECT_LE(pairs.values[0], 1e-10 * pairs.values[1]);
    // M-normalized constant: 1/sqrt(area), positive by the sign rule.
    const double constant = 1 / std::sqrt(laplacian.mass.sum());
    EXPECT_LE((pairs.vectors.col(0).array() - constant).abs().maxCoeff(), 1e-8 * constant);
  }
}

TEST(Eigensolver, DenseAndShiftInvertAgree) {
  // 642 vertices: above the automatic dense limit, small enough for a dense reference.
  const Mesh mesh = irregular_ellipsoid(3, 5);
  const CotangentLaplacian laplacian = build(mesh);
  const Eigenpairs dense = solve(laplacian, 20, EigenMethod::dense);
  const Eigenpairs sparse = solve(laplacian, 20, EigenMethod::shift_invert);
  expect_eigenpairs(laplacian, dense);
  expect_eigenpairs(laplacian, sparse);
  ASSERT_EQ(dense.values.size(), sparse.values.size());
  for (Eigen::Index i = 1; i < dense.values.size(); ++i) {
    EXPECT_NEAR(dense.values[i], sparse.values[i], 1e-9 * dense.values[i]) << i;
  }
  // Same vectors with the same signs: ΦdᵀMΦs = I (the ellipsoid's eigenvalues are simple).
  const Eigen::MatrixXd overlap = dense.vectors.transpose() * laplacian.mass.asDiagonal() * sparse.vectors;
  EXPECT_LE((overlap - Eigen::MatrixXd::Identity(20, 20)).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(Eigensolver, TwoCallsGiveIdenticalVectors) {
  const Mesh mesh = irregular_ellipsoid(4, 9);
  const CotangentLaplacian laplacian = build(mesh);
  const Eigenpairs first = solve(laplacian, 12), second = solve(laplacian, 12);
  EXPECT_EQ(first.values, second.values);
  EXPECT_EQ(first.vectors, second.vectors);
  // The sign rule holds on the symmetric sphere too, where the solver's basis of each eigenspace is arbitrary.
  const Mesh sphere = icosphere(3);
  const CotangentLaplacian sphere_laplacian = build(sphere);
  const Eigenpairs a = solve(sphere_laplacian, 10), b = solve(sphere_laplacian, 10);
  EXPECT_EQ(a.vectors, b.vectors);
  expect_eigenpairs(sphere_laplacian, a);
}

// Meshes side by side in one frame sequence, welded like real input.
struct WeldedMesh {
  Mesh mesh;
  WeldedTopology topology;
  CotangentLaplacian laplacian;
};

WeldedMesh welded(const std::vector<Mesh>& parts) {
  FrameSequence clip;
  clip.frame_count = 1;
  clip.times = {0};
  for (const Mesh& part : parts) {
    const uint32_t first = uint32_t(clip.positions.size() / 3);
    for (double p : part.positions) clip.positions.push_back(float(p));
    for (uint32_t v : part.triangles) clip.triangles.push_back(v + first);
  }
  clip.vertex_count = clip.positions.size() / 3;
  WeldedMesh out;
  out.topology = weld_topology({clip});
  out.mesh.positions = welded_positions(clip.frame(0), out.topology);
  out.mesh.triangles = out.topology.triangles;
  out.laplacian = build(out.mesh);
  return out;
}

// Two spheres (radii 1 and 0.5, level 3).
WeldedMesh two_spheres() { return welded({icosphere(3, 1.0), icosphere(3, 0.5, Eigen::Vector3d(4, 0, 0))}); }

TEST(Eigensolver, EachComponentHasItsOwnZeroEigenvalue) {
  const WeldedMesh spheres = two_spheres();
  ASSERT_EQ(spheres.topology.component_count, 2u);
  // Whole mesh: two zero eigenvalues, whose vectors mix the components arbitrarily.
  const Eigenpairs whole = solve(spheres.laplacian, 4);
  EXPECT_LE(whole.values[1], 1e-10 * whole.values[2]);

  ComponentSpectra spectra;
  const Status status = component_spectra(spheres.laplacian, spheres.topology, 10, spectra);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(spectra.components.size(), 2u);
  ASSERT_EQ(spectra.local_index.size(), spheres.topology.welded_count());
  const double radii[] = {1.0, 0.5};
  for (size_t c = 0; c < 2; ++c) {
    const ComponentSpectrum& component = spectra.components[c];
    ASSERT_EQ(component.vertices.size(), 642u);
    for (size_t local = 0; local < component.vertices.size(); ++local) {
      EXPECT_EQ(spheres.topology.component[component.vertices[local]], c);
      EXPECT_EQ(spectra.local_index[component.vertices[local]], local);
    }
    const Eigenpairs& pairs = component.eigenpairs;
    ASSERT_EQ(pairs.values.size(), 10);
    // Exactly one zero, then 2/r² three times (level 3: the measured error of l = 1 is below 0.001 %).
    EXPECT_LE(pairs.values[0], 1e-10 * pairs.values[1]);
    for (int i = 1; i <= 3; ++i) {
      EXPECT_NEAR(pairs.values[i], 2 / (radii[c] * radii[c]), 0.01 * 2 / (radii[c] * radii[c]));
    }
    // Against the component's own operator (its rows of K and entries of M).
    CotangentLaplacian own;
    const Eigen::Index n = Eigen::Index(component.vertices.size());
    own.mass.resize(n);
    Eigen::MatrixXd dense(n, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      own.mass[i] = spheres.laplacian.mass[component.vertices[size_t(i)]];
      for (Eigen::Index j = 0; j < n; ++j) {
        dense(i, j) = spheres.laplacian.stiffness.coeff(component.vertices[size_t(i)], component.vertices[size_t(j)]);
      }
    }
    own.stiffness = dense.sparseView();
    expect_eigenpairs(own, pairs);
  }
}

TEST(Eigensolver, ComponentCountIsClampedToTheComponentSize) {
  // A triangle, a lone vertex and a tetrahedron: components of 3, 1 and 4 vertices.
  FrameSequence clip;
  clip.vertex_count = 8;
  clip.frame_count = 1;
  clip.times = {0};
  clip.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, /*lone*/ 5, 5, 5, /*tetrahedron*/ 2, 0, 0, 3, 0, 0, 2, 1, 0, 2, 0, 1};
  clip.triangles = {0, 1, 2, 4, 6, 5, 4, 5, 7, 5, 6, 7, 6, 4, 7};
  const WeldedTopology topology = weld_topology({clip});
  ASSERT_EQ(topology.component_count, 3u);
  CotangentLaplacian laplacian;
  ASSERT_TRUE(cotangent_laplacian(welded_positions(clip.frame(0), topology), topology.triangles, laplacian).ok());
  ComponentSpectra spectra;
  ASSERT_TRUE(component_spectra(laplacian, topology, 6, spectra).ok());
  ASSERT_EQ(spectra.components.size(), 3u);
  const Eigen::Index sizes[] = {3, 1, 4};
  for (size_t c = 0; c < 3; ++c) {
    const Eigenpairs& pairs = spectra.components[c].eigenpairs;
    EXPECT_EQ(pairs.values.size(), sizes[c]);
    EXPECT_LE(pairs.values[0], sizes[c] > 1 ? 1e-12 * pairs.values[1] : 0.0);
  }
  // The lone vertex: λ = 0 and φ = 1/sqrt(its tiny mass).
  const Eigenpairs& lone = spectra.components[1].eigenpairs;
  EXPECT_NEAR(lone.vectors(0, 0), 1 / std::sqrt(laplacian.mass[3]), 1e-12 / std::sqrt(laplacian.mass[3]));
}

// A triangle, spheres of 642, 162, 42 and 2562 vertices (dense and shift-invert solves) and a lone vertex: the
// components' order is not their sizes'.
WeldedMesh several_components() {
  Mesh triangle, lone;
  triangle.positions = {12, 0, 0, 13, 0, 0, 12, 1, 0};
  triangle.triangles = {0, 1, 2};
  lone.positions = {15, 5, 5};
  return welded({triangle, icosphere(3, 1.0), icosphere(2, 0.7, Eigen::Vector3d(3, 0, 0)),
                 icosphere(1, 0.4, Eigen::Vector3d(6, 0, 0)), icosphere(4, 0.5, Eigen::Vector3d(9, 0, 0)), lone});
}

TEST(Eigensolver, ComponentsOnThreadsAreEachSolvedAlone) {
  const WeldedMesh mesh = several_components();
  ASSERT_EQ(mesh.topology.component_count, 6u);
  // With a multilevel limit of 2000 the 2562-vertex sphere is solved first, alone (multilevel).
  const size_t usual = EigenSettings().multilevel_limit;
  for (auto [limit, threads] : {std::pair<size_t, size_t>(usual, 1), {usual, 3}, {2000, 1}, {2000, 3}}) {
    SCOPED_TRACE(::testing::Message() << limit << " " << threads);
    EigenSettings settings;
    settings.threads = threads;
    settings.multilevel_limit = limit;
    std::vector<std::string> steps;
    std::mutex told;
    bool elsewhere = false;
    const std::thread::id caller = std::this_thread::get_id();
    settings.progress = [&](const std::string& step) {
      const std::lock_guard<std::mutex> lock(told);
      steps.push_back(step);
      elsewhere = elsewhere || std::this_thread::get_id() != caller;
    };
    ComponentSpectra spectra;
    ASSERT_TRUE(component_spectra(mesh.laplacian, mesh.topology, 12, spectra, settings).ok());
    ASSERT_EQ(spectra.components.size(), 6u);
    EXPECT_FALSE(steps.empty());  // the largest component is the calling thread's
    EXPECT_FALSE(elsewhere);      // and only its steps are told
    if (limit == 2000) {  // the large sphere took the multilevel path
      EXPECT_NE(std::find(steps.begin(), steps.end(), "eigenpairs: carrying back and filtering (2562 vertices)"),
                steps.end());
    }
    for (const ComponentSpectrum& component : spectra.components) {
      // The reference: the component's own operator, solved alone on this thread.
      const Eigen::Index n = Eigen::Index(component.vertices.size());
      std::vector<Eigen::Triplet<double>> entries;
      for (Eigen::Index j = 0; j < mesh.laplacian.stiffness.outerSize(); ++j)
        for (Eigen::SparseMatrix<double>::InnerIterator it(mesh.laplacian.stiffness, j); it; ++it)
          if (mesh.topology.component[size_t(j)] == mesh.topology.component[component.vertices[0]])
            entries.emplace_back(spectra.local_index[size_t(it.row())], spectra.local_index[size_t(j)], it.value());
      Eigen::SparseMatrix<double> stiffness(n, n);
      stiffness.setFromTriplets(entries.begin(), entries.end());
      Eigen::VectorXd mass(n);
      for (Eigen::Index i = 0; i < n; ++i) mass[i] = mesh.laplacian.mass[component.vertices[size_t(i)]];
      EigenSettings reference;
      reference.multilevel_limit = limit;
      Eigenpairs alone;
      ASSERT_TRUE(smallest_eigenpairs(stiffness, mass, 12, alone, reference).ok());
      ASSERT_EQ(component.eigenpairs.values.size(), alone.values.size());
      ASSERT_EQ(component.eigenpairs.vectors.size(), alone.vectors.size());
      EXPECT_EQ(0, std::memcmp(component.eigenpairs.values.data(), alone.values.data(),
                               sizeof(double) * size_t(alone.values.size())));
      EXPECT_EQ(0, std::memcmp(component.eigenpairs.vectors.data(), alone.vectors.data(),
                               sizeof(double) * size_t(alone.vectors.size())));
    }
  }
  // Failures: the first in component order is the one told (the triangle, handed out after the larger ones), whichever
  // thread met it first. Forced shift-invert cannot find 100 pairs of the 3-, 42- and 1-vertex components.
  EigenSettings forced;
  forced.method = EigenMethod::shift_invert;
  forced.threads = 3;
  ComponentSpectra spectra;
  const Status status = component_spectra(mesh.laplacian, mesh.topology, 100, spectra, forced);
  EXPECT_EQ(status.code(), StatusCode::invalid_argument);
  EXPECT_EQ(status.message().rfind("component 0 of 6: ", 0), 0u) << status.message();
}

TEST(Eigensolver, MeshWithDegenerateTrianglesStillSolves) {
  // Level-3 sphere with (a) a vertex moved onto the midpoint of the opposite edge of one of its triangles
  // (a zero-area triangle with a straight angle) and (b) another vertex moved onto its neighbour (a
  // zero-length edge; both triangles on it collapse).
  Mesh mesh = icosphere(3);
  const Mesh reference = mesh;
  auto vertex = [&](uint32_t v) { return Eigen::Vector3d(&mesh.positions[3 * size_t(v)]); };
  auto place = [&](uint32_t v, const Eigen::Vector3d& p) {
    for (int c = 0; c < 3; ++c) mesh.positions[3 * size_t(v) + c] = p[c];
  };
  const uint32_t a = mesh.triangles[0], b = mesh.triangles[1], c = mesh.triangles[2];
  place(c, (vertex(a) + vertex(b)) / 2);
  const uint32_t d = mesh.triangles[300], e = mesh.triangles[301];
  place(e, vertex(d));
  const CotangentLaplacian laplacian = build(mesh);
  EXPECT_GT(laplacian.mollification, 0.0);
  const Eigenpairs reference_pairs = solve(build(reference), 10, EigenMethod::shift_invert);
  for (EigenMethod method : {EigenMethod::shift_invert, EigenMethod::dense}) {
    const Eigenpairs pairs = solve(laplacian, 10, method);
    ASSERT_EQ(pairs.values.size(), 10);
    expect_eigenpairs(laplacian, pairs);
    EXPECT_LE(pairs.values[0], 1e-10 * pairs.values[1]);
    // Two local defects among 642 vertices barely move the low spectrum.
    for (Eigen::Index i = 1; i < 10; ++i) {
      EXPECT_NEAR(pairs.values[i], reference_pairs.values[i], 0.02 * reference_pairs.values[i]);
    }
  }
}

TEST(Eigensolver, CountIsClampedAndShiftInvertLimitIsAStatus) {
  const Mesh tetrahedron{{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3}};
  const CotangentLaplacian laplacian = build(tetrahedron);
  const Eigenpairs pairs = solve(laplacian, 10);
  EXPECT_EQ(pairs.values.size(), 4);
  expect_eigenpairs(laplacian, pairs);
  Eigenpairs unused;
  EigenSettings settings;
  settings.method = EigenMethod::shift_invert;
  EXPECT_EQ(smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 3, unused, settings).code(),
            StatusCode::invalid_argument);
  EXPECT_TRUE(smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 0, unused).ok());
  EXPECT_EQ(unused.values.size(), 0);
}

TEST(Eigensolver, ProgressNamesEachStepAndCountsTheSolves) {
  // Reported at every solve here (solve_report_seconds 0): the counts rise by one from 1.
  const CotangentLaplacian laplacian = build(icosphere(3));
  EigenSettings settings;
  settings.method = EigenMethod::shift_invert;
  settings.solve_report_seconds = 0;
  std::vector<std::string> steps;
  settings.progress = [&](const std::string& step) { steps.push_back(step); };
  Eigenpairs pairs;
  ASSERT_TRUE(smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 12, pairs, settings).ok());
  ASSERT_GE(steps.size(), 3u);
  EXPECT_EQ(steps[0], "eigenpairs: factorizing (642 vertices)");
  EXPECT_EQ(steps[1], "eigenpairs: Lanczos iteration (642 vertices)");
  size_t solves = 0;
  for (size_t i = 2; i < steps.size() && steps[i].find(" solves ") != std::string::npos; ++i)
    EXPECT_EQ(steps[i], "eigenpairs: Lanczos iteration, " + std::to_string(++solves) + " solves (642 vertices)");
  EXPECT_GT(solves, 12u);
}

TEST(Eigensolver, NoConvergenceIsANumericalStatus) {
  const Mesh mesh = irregular_ellipsoid(3, 1);
  const CotangentLaplacian laplacian = build(mesh);
  EigenSettings settings;
  settings.method = EigenMethod::shift_invert;
  settings.max_restarts = 1;
  settings.tolerance = 1e-300;  // unreachable
  Eigenpairs pairs;
  const Status status = smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 20, pairs, settings);
  EXPECT_EQ(status.code(), StatusCode::numerical);
  EXPECT_EQ(status.message().find('\n'), std::string::npos);
  EXPECT_NE(status.message().find("converged"), std::string::npos) << status.message();
}

// The multilevel method against shift-invert on 10242-vertex meshes (about 8 vertices an aggregate, the coarsest the
// method allows): eigenvalues from above and within 1 % (measured: at worst 0.43 % on the sphere, 0.54 % on the
// irregular ellipsoid; at 163,842 vertices 0.05 % and 0.90 %; without the filter the sphere's first pairs come out
// 59 % too large), vectors M-orthonormal and in the exact vectors' span (the sphere's clusters, l ≤ 3, compared as one
// 16-dimensional subspace; measured at least 0.9999 and 0.9988 of each vector's norm).
TEST(Eigensolver, MultilevelApproximatesTheSmallestPairs) {
  for (const bool sphere : {true, false}) {
    const Mesh mesh = sphere ? icosphere(5) : irregular_ellipsoid(5, 11);
    ASSERT_EQ(mesh.vertex_count(), 10242u);
    const CotangentLaplacian laplacian = build(mesh);
    const Eigenpairs exact = solve(laplacian, 40, EigenMethod::shift_invert);
    std::vector<std::string> steps;
    EigenSettings settings;
    settings.method = EigenMethod::multilevel;
    settings.progress = [&](const std::string& step) { steps.push_back(step); };
    Eigenpairs coarse;
    const Status status = smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 40, coarse, settings);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(coarse.values.size(), 40);
    ASSERT_FALSE(steps.empty());
    EXPECT_NE(steps.front().find("coarse problem of"), std::string::npos) << steps.front();
    const Eigen::MatrixXd gram = coarse.vectors.transpose() * laplacian.mass.asDiagonal() * coarse.vectors;
    EXPECT_LE((gram - Eigen::MatrixXd::Identity(40, 40)).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LE(coarse.values[0], 1e-10 * coarse.values[1]);
    for (Eigen::Index i = 1; i < 40; ++i) {
      EXPECT_GE(coarse.values[i], exact.values[i] * (1 - 1e-9)) << "pair " << i;
      EXPECT_LE(coarse.values[i], exact.values[i] * 1.01) << "pair " << i;
    }
    const Eigen::Index span = sphere ? 16 : 40;
    const Eigen::MatrixXd overlap =
        exact.vectors.leftCols(span).transpose() * laplacian.mass.asDiagonal() * coarse.vectors.leftCols(span);
    for (Eigen::Index i = 0; i < span; ++i) EXPECT_GE(overlap.col(i).norm(), 0.99) << "vector " << i;
    // The same pairs, bit for bit, on any number of threads.
    for (const size_t threads : {size_t(2), size_t(3)}) {
      settings.threads = threads;
      Eigenpairs threaded;
      ASSERT_TRUE(smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 40, threaded, settings).ok());
      EXPECT_EQ(threaded.values, coarse.values) << threads << " threads";
      EXPECT_EQ(threaded.vectors, coarse.vectors) << threads << " threads";
    }
  }
}

// automatic takes the multilevel method above multilevel_limit only; a problem too small to coarsen is solved by
// shift-invert, with its exact pairs.
TEST(Eigensolver, MultilevelIsChosenAboveItsLimitAndFallsBackWhenTooSmall) {
  const CotangentLaplacian laplacian = build(irregular_ellipsoid(4, 3));  // 2562 vertices
  for (const size_t limit : {size_t(2000), size_t(3000)}) {
    std::vector<std::string> steps;
    EigenSettings settings;
    settings.multilevel_limit = limit;
    settings.progress = [&](const std::string& step) { steps.push_back(step); };
    Eigenpairs pairs;
    ASSERT_TRUE(smallest_eigenpairs(laplacian.stiffness, laplacian.mass, 10, pairs, settings).ok());
    const bool coarse = std::any_of(steps.begin(), steps.end(),
                                    [](const std::string& step) { return step.find("coarse") != std::string::npos; });
    EXPECT_EQ(coarse, limit < 2562) << limit;
  }
  // 100 pairs take 200 coarse pairs, so at most 400 aggregates and no fewer than 400: the smallest radius that brings
  // 2562 vertices to 400 or fewer leaves fewer (radius 1 leaves more), and the problem goes to shift-invert.
  const Eigenpairs exact = solve(laplacian, 100, EigenMethod::shift_invert);
  const Eigenpairs fallback = solve(laplacian, 100, EigenMethod::multilevel);
  ASSERT_EQ(fallback.values.size(), 100);
  EXPECT_EQ((fallback.values - exact.values).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace segmorph
