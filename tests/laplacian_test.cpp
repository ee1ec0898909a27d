#include "encode/segmentation/laplacian.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::Mesh;

// An nx × ny grid over [0, 1]², each vertex moved by up to `jitter` cells in x and y, each quad split
// along a random diagonal, z = height(x, y): irregular, with obtuse triangles (negative cotangent weights).
template <typename Height>
Mesh jittered_grid(int nx, int ny, double jitter, unsigned seed, Height height) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(-jitter, jitter);
  Mesh mesh;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const bool boundary = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
      const double x = (i + (boundary ? 0 : offset(random))) / (nx - 1);
      const double y = (j + (boundary ? 0 : offset(random))) / (ny - 1);
      mesh.positions.insert(mesh.positions.end(), {x, y, height(x, y)});
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const uint32_t a = uint32_t(j * nx + i), b = a + 1, c = a + uint32_t(nx), d = c + 1;
      if (random() % 2) {
        mesh.triangles.insert(mesh.triangles.end(), {a, b, d, a, d, c});
      } else {
        mesh.triangles.insert(mesh.triangles.end(), {a, b, c, b, d, c});
      }
    }
  }
  return mesh;
}

Mesh bumpy_grid() {
  return jittered_grid(17, 13, 0.35, 7, [](double x, double y) { return 0.3 * std::sin(5 * x) * std::cos(4 * y); });
}

Mesh flat_grid() {
  // Jitter 0.2 of a cell keeps every triangle positively oriented (a vertex is 0.7 cells from the opposite side).
  return jittered_grid(15, 15, 0.2, 11, [](double, double) { return 0.0; });
}

double cross_area(const Mesh& mesh, size_t t) {
  const double* p[3];
  for (int k = 0; k < 3; ++k) p[k] = &mesh.positions[3 * size_t(mesh.triangles[3 * t + k])];
  const Eigen::Vector3d u(p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]);
  const Eigen::Vector3d v(p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]);
  return 0.5 * u.cross(v).norm();
}

CotangentLaplacian build(const Mesh& mesh) {
  CotangentLaplacian laplacian;
  const Status status = cotangent_laplacian(mesh.positions, mesh.triangles, laplacian);
  EXPECT_TRUE(status.ok()) << status.message();
  return laplacian;
}

double max_diagonal(const CotangentLaplacian& laplacian) {
  return Eigen::VectorXd(laplacian.stiffness.diagonal()).cwiseAbs().maxCoeff();
}

// The properties every operator must have: symmetric bit for bit, K·1 = 0 to rounding, finite, masses > 0,
// positive semidefinite (checked densely when small).
void expect_well_formed(const CotangentLaplacian& laplacian) {
  const Eigen::SparseMatrix<double>& stiffness = laplacian.stiffness;
  const Eigen::SparseMatrix<double> transposed = stiffness.transpose();
  EXPECT_EQ((stiffness - transposed).norm(), 0.0);
  for (Eigen::Index j = 0; j < stiffness.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(stiffness, j); it; ++it) {
      ASSERT_TRUE(std::isfinite(it.value())) << it.row() << ", " << it.col();
    }
  }
  const Eigen::VectorXd row_sums = stiffness * Eigen::VectorXd::Ones(stiffness.cols());
  EXPECT_LE(row_sums.cwiseAbs().maxCoeff(), 1e-13 * max_diagonal(laplacian));
  EXPECT_TRUE(laplacian.mass.allFinite());
  EXPECT_GT(laplacian.mass.minCoeff(), 0.0);
  if (stiffness.rows() <= 400) {
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(stiffness),
                                                                                       Eigen::EigenvaluesOnly)
                                            .eigenvalues();
    EXPECT_GE(eigenvalues.minCoeff(), -1e-12 * eigenvalues.maxCoeff());
  }
}

TEST(Laplacian, RightTriangleHasTheTextbookEntries) {
  // Right angle at vertex 0, 45° at 1 and 2: cot 90° = 0, cot 45° = 1, each boundary edge has one angle.
  const Mesh mesh{{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}};
  const CotangentLaplacian laplacian = build(mesh);
  Eigen::Matrix3d expected;
  expected << 1, -0.5, -0.5,  //
      -0.5, 0.5, 0,           //
      -0.5, 0, 0.5;
  EXPECT_LE((Eigen::MatrixXd(laplacian.stiffness) - expected).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((laplacian.mass - Eigen::Vector3d::Constant(1.0 / 6)).cwiseAbs().maxCoeff(), 1e-16);
  EXPECT_EQ(laplacian.mollification, 0.0);
}

TEST(Laplacian, IrregularMeshIsSymmetricWithZeroRowSums) {
  const Mesh mesh = bumpy_grid();
  const CotangentLaplacian laplacian = build(mesh);
  ASSERT_EQ(size_t(laplacian.stiffness.rows()), mesh.vertex_count());
  expect_well_formed(laplacian);
  EXPECT_EQ(laplacian.mollification, 0.0);
  // Some weights are positive (obtuse pairs of opposite angles): the test mesh exercises that case.
  bool positive_off_diagonal = false;
  for (Eigen::Index j = 0; j < laplacian.stiffness.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(laplacian.stiffness, j); it; ++it) {
      positive_off_diagonal |= it.row() != it.col() && it.value() > 0;
    }
  }
  EXPECT_TRUE(positive_off_diagonal);
}

TEST(Laplacian, MassIsAThirdOfIncidentAreasAndSumsToSurfaceArea) {
  const Mesh mesh = bumpy_grid();
  const CotangentLaplacian laplacian = build(mesh);
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(Eigen::Index(mesh.vertex_count()));
  double area = 0;
  for (size_t t = 0; t < mesh.triangles.size() / 3; ++t) {
    const double a = cross_area(mesh, t);
    area += a;
    for (int k = 0; k < 3; ++k) expected[mesh.triangles[3 * t + k]] += a / 3;
  }
  EXPECT_NEAR(laplacian.mass.sum(), area, 1e-13 * area);
  EXPECT_LE((laplacian.mass - expected).cwiseAbs().maxCoeff(), 1e-13 * area);
}

TEST(Laplacian, LinearFunctionsOnAPlaneAreHarmonicWithExactDirichletEnergy) {
  // Linear precision of the cotangent operator: on a planar mesh, fᵀKf = ∫|∇f|² exactly for linear f
  // (|∇f|² times the area) and (Kf)_i = 0 at interior vertices, whatever the triangle shapes.
  const Mesh mesh = flat_grid();
  const CotangentLaplacian laplacian = build(mesh);
  Eigen::VectorXd f(Eigen::Index(mesh.vertex_count()));
  for (Eigen::Index i = 0; i < f.size(); ++i) f[i] = 2 * mesh.positions[3 * i] - 3 * mesh.positions[3 * i + 1] + 5;
  const double energy = f.dot(laplacian.stiffness * f);
  EXPECT_NEAR(energy, (4 + 9) * 1.0, 1e-12 * 13);  // the grid covers the unit square
  const Eigen::VectorXd kf = laplacian.stiffness * f;
  for (int j = 1; j + 1 < 15; ++j) {
    for (int i = 1; i + 1 < 15; ++i) EXPECT_NEAR(kf[j * 15 + i], 0.0, 1e-12) << i << ", " << j;
  }
}

TEST(Laplacian, StiffnessIsScaleInvariantAndMassScalesWithArea) {
  const Mesh mesh = bumpy_grid();
  Mesh scaled = mesh;
  for (double& p : scaled.positions) p *= 1000;
  const CotangentLaplacian a = build(mesh), b = build(scaled);
  EXPECT_LE((a.stiffness - b.stiffness).norm(), 1e-12 * a.stiffness.norm());
  EXPECT_LE((b.mass - 1e6 * a.mass).cwiseAbs().maxCoeff(), 1e-12 * b.mass.maxCoeff());
}

// The unit square around a centre vertex 5, with vertex 4 on the bottom edge, a duplicate 6 of the
// centre (a zero-length edge, as points that touch at rest and separate later), and two zero-area
// triangles: the cap (0, 1, 4) with a straight angle at 4, and (2, 6, 5) with two coincident corners.
Mesh degenerate_square() {
  return Mesh{{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0, 0, 0.5, 0.5, 0, 0.5, 0.5, 0},
              {0, 4, 5, 4, 1, 5, 1, 2, 5, 2, 6, 5, 2, 3, 6, 3, 0, 6, 0, 5, 6, 0, 1, 4}};
}

TEST(Laplacian, DegenerateTrianglesGiveAFiniteSemidefiniteOperator) {
  const Mesh mesh = degenerate_square();
  const CotangentLaplacian laplacian = build(mesh);
  expect_well_formed(laplacian);
  // δ is the margin, 1e-6 of the mean edge length (edges here are 0.5 to 1 long).
  EXPECT_GT(laplacian.mollification, 0.0);
  EXPECT_LE(laplacian.mollification, kMollificationMargin * 1.0);
  // A mollified zero-area triangle gets the area of a needle of width ~sqrt(δ·l): the total here is the
  // square's plus 9.2e-4 (measured), checked within 2e-3.
  EXPECT_NEAR(laplacian.mass.sum(), 1.0, 2e-3);
  // Cotangents stay bounded: the largest is the angle opposite the zero-length edge, cot ≈ 2l/δ (K_ii is
  // 1.1e5 here), which ties the two coincident vertices together as strongly as their distance asks.
  EXPECT_LE(max_diagonal(laplacian), 10 / kMollificationMargin);
}

TEST(Laplacian, TriangleWithRepeatedCornerIsIgnored) {
  const Mesh with{{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2, 0, 0, 1}};
  const Mesh without{{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}};
  const CotangentLaplacian a = build(with), b = build(without);
  EXPECT_EQ((a.stiffness - b.stiffness).norm(), 0.0);
  EXPECT_EQ(a.mass, b.mass);
  EXPECT_EQ(a.mollification, 0.0);
}

TEST(Laplacian, VertexWithoutTrianglesGetsATinyPositiveMassAndAnEmptyRow) {
  Mesh mesh = bumpy_grid();
  const size_t isolated = mesh.vertex_count();
  mesh.positions.insert(mesh.positions.end(), {5, 5, 5});
  const CotangentLaplacian laplacian = build(mesh);
  const double mean = (laplacian.mass.sum() - laplacian.mass[Eigen::Index(isolated)]) / double(isolated);
  EXPECT_NEAR(laplacian.mass[Eigen::Index(isolated)], kIsolatedMassFraction * mean,
              1e-6 * kIsolatedMassFraction * mean);
  const Eigen::SparseMatrix<double> column = laplacian.stiffness.col(Eigen::Index(isolated));
  EXPECT_EQ(column.nonZeros(), 0);
}

TEST(Laplacian, NoTrianglesGivesUnitMasses) {
  const Mesh mesh{{0, 0, 0, 1, 0, 0}, {}};
  const CotangentLaplacian laplacian = build(mesh);
  EXPECT_EQ(laplacian.mass, Eigen::Vector2d(1, 1));
  EXPECT_EQ(laplacian.stiffness.nonZeros(), 0);
}

TEST(Laplacian, NonFinitePositionIsBadData) {
  Mesh mesh = bumpy_grid();
  mesh.positions[3 * 5 + 1] = std::nan("");
  CotangentLaplacian laplacian;
  EXPECT_EQ(cotangent_laplacian(mesh.positions, mesh.triangles, laplacian).code(), StatusCode::bad_data);
  mesh.positions[3 * 5 + 1] = 1e300;  // finite, but its squared distances overflow
  EXPECT_EQ(cotangent_laplacian(mesh.positions, mesh.triangles, laplacian).code(), StatusCode::bad_data);
}

TEST(Laplacian, WeldedPositionsAreReadAtRepresentatives) {
  WeldedTopology topology;
  topology.welded_index = {0, 1, 0};
  topology.representative = {0, 1};
  const float frame[] = {1, 2, 3, 4, 5, 6, 1, 2, 3};
  EXPECT_EQ(welded_positions(frame, topology), (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

}  // namespace
}  // namespace segmorph
