// LargestEigenvectors (codec/encode/largest_eigenvectors.h) against Eigen's dense solver: the same eigenvalues, bit for
// bit; the same largest vectors up to rounding (and sign), orthonormal, also where eigenvalues repeat; the dense
// solver's way beyond a quarter of the vectors.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "encode/largest_eigenvectors.h"

namespace segmorph {
namespace {

// Q diag(values) Qᵀ with a random orthogonal Q.
Eigen::MatrixXd with_spectrum(const Eigen::VectorXd& values, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  const Eigen::Index n = values.size();
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index i = 0; i < a.size(); ++i) a(i) = normal(random);
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(a).householderQ();
  return q * values.asDiagonal() * q.transpose();
}

// A weighted Gram matrix as the PCA bases have: rows of a few smooth motions plus noise.
Eigen::MatrixXd gram(Eigen::Index rows, Eigen::Index n, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd x(rows, n);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index f = 0; f < n; ++f)
      x(r, f) = std::sin(0.05 * double(f) * double(1 + r % 7)) * double(1 + r % 3) + 1e-3 * normal(random);
  return x.transpose() * x;
}

void expect_largest(const Eigen::MatrixXd& a, Eigen::Index count, double tolerance) {
  SCOPED_TRACE("n " + std::to_string(a.rows()) + ", count " + std::to_string(count));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> dense(a);
  const LargestEigenvectors largest(a);
  const Eigen::Index n = a.rows();
  ASSERT_EQ(largest.values().size(), n);
  for (Eigen::Index i = 0; i < n; ++i) EXPECT_EQ(largest.values()(i), dense.eigenvalues()(i)) << i;
  const Eigen::MatrixXd v = largest.vectors(count);
  ASSERT_EQ(v.rows(), n);
  ASSERT_EQ(v.cols(), count);
  const double norm = std::max(dense.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
  if (count > 0) {
    EXPECT_LE((v.transpose() * v - Eigen::MatrixXd::Identity(count, count)).cwiseAbs().maxCoeff(), tolerance);
  }
  for (Eigen::Index j = 0; j < count; ++j) {
    const double value = dense.eigenvalues()(n - 1 - j);
    EXPECT_LE((a * v.col(j) - value * v.col(j)).norm(), tolerance * norm) << j;
    Eigen::Index at = 0;
    v.col(j).cwiseAbs().maxCoeff(&at);
    EXPECT_GT(v(at, j), 0.0) << j;
  }
}

TEST(LargestEigenvectors, TheDenseSolversValuesAndVectors) {
  for (Eigen::Index n : {1, 2, 7, 60, 200}) {
    const Eigen::MatrixXd a = gram(3 * n + 5, n, unsigned(n));
    for (Eigen::Index count : {Eigen::Index(0), Eigen::Index(1), std::max<Eigen::Index>(n / 8, 1), n / 4, n / 4 + 1, n})
      if (count <= n) expect_largest(a, count, 1e-9);
  }
}

// Distinct eigenvalues: the vectors are determined up to sign, and equal the dense solver's after signing.
TEST(LargestEigenvectors, DistinctValuesGiveTheDenseSolversVectors) {
  Eigen::VectorXd values(40);
  for (Eigen::Index i = 0; i < 40; ++i) values(i) = std::pow(0.7, double(i));
  const Eigen::MatrixXd a = with_spectrum(values, 3);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> dense(a);
  const Eigen::MatrixXd v = LargestEigenvectors(a).vectors(8);
  for (Eigen::Index j = 0; j < 8; ++j) {
    Eigen::VectorXd expected = dense.eigenvectors().col(39 - j);
    sign_by_largest_entry(expected);
    EXPECT_LE((v.col(j) - expected).cwiseAbs().maxCoeff(), 1e-10) << j;
  }
}

// Repeated and nearly repeated eigenvalues, and a zero block: the vectors stay orthonormal eigenvectors.
TEST(LargestEigenvectors, RepeatedValuesStayOrthogonal) {
  Eigen::VectorXd values = Eigen::VectorXd::Zero(48);
  values.head(5).setConstant(3.0);
  values.segment(5, 4) << 2.0, 2.0 + 1e-13, 2.0 - 1e-13, 2.0;
  values.segment(9, 3).setConstant(1e-9);
  expect_largest(with_spectrum(values, 11), 12, 1e-9);
  expect_largest(Eigen::MatrixXd::Identity(20, 20), 5, 1e-12);
  // Tiny but nonzero eigenvalues next to the wanted ones: pivots far below the norm's rounding (an unguarded solve
  // overflows to infinity and NaN here).
  Eigen::VectorXd denormal = Eigen::VectorXd::Zero(8);
  denormal.head(2) << 1.0, 1e-310;
  expect_largest(Eigen::MatrixXd(denormal.asDiagonal()), 2, 1e-12);
  Eigen::VectorXd tiny = Eigen::VectorXd::Zero(8);
  tiny.head(3) << 1.0, 1e-200, 1e-200 * (1 + 1e-15);
  expect_largest(Eigen::MatrixXd(tiny.asDiagonal()), 2, 1e-12);
  expect_largest(Eigen::MatrixXd::Zero(16, 16), 4, 1e-12);
}

}  // namespace
}  // namespace segmorph
