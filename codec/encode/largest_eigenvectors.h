// The eigenvectors of a symmetric matrix's largest eigenvalues only, for the transform's PCA bases, which keep few
// of their frames' vectors (a cluster's basis 11–31 of 400 on the chicken). A dense solver finds every eigenvector
// by accumulating each rotation of its QR iterations into an n × n matrix, most of its time; here the matrix is
// reduced to tridiagonal form once, its eigenvalues found without vectors (the same values as the dense solver's),
// and only the wanted vectors computed: by inverse iteration on the tridiagonal matrix (vectors of close eigenvalues
// kept orthogonal to each other), taken back through the reduction's Householder reflections.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace segmorph {

class LargestEigenvectors {
 public:
  // Reads the lower triangle of `symmetric` (n × n) only.
  explicit LargestEigenvectors(const Eigen::MatrixXd& symmetric);

  // All n eigenvalues, ascending (as Eigen::SelfAdjointEigenSolver gives them).
  const Eigen::VectorXd& values() const { return values_; }

  // The unit eigenvectors of the `count` largest eigenvalues, as columns, largest first; each signed so that its
  // entry of largest magnitude (the first such) is positive. Beyond a quarter of n, from the QR iterations with
  // their rotations accumulated instead (the dense solver's way).
  Eigen::MatrixXd vectors(Eigen::Index count) const;

 private:
  Eigen::MatrixXd in_matrix_basis(const Eigen::MatrixXd& tridiagonal_vectors) const;
  Eigen::MatrixXd all_vectors(const Eigen::VectorXd& diagonal, const Eigen::VectorXd& off, Eigen::Index count) const;

  Eigen::Tridiagonalization<Eigen::MatrixXd> reduction_;
  Eigen::VectorXd values_;  // of the matrix
  double scale_ = 1;        // the matrix's largest entry: the reduction is of the matrix over it
};

// Signs `vector` so that its entry of largest magnitude (the first such) is positive.
void sign_by_largest_entry(Eigen::Ref<Eigen::VectorXd> vector);

}  // namespace segmorph
