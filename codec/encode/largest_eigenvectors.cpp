#include "encode/largest_eigenvectors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace segmorph {
namespace {

// Eigenvalues closer than this share of the tridiagonal matrix's norm count as a cluster: their vectors are made
// orthogonal to each other (as LAPACK's dstein does).
constexpr double kClusterGap = 1e-3;
// Inverse iterations per vector: the eigenvalues are accurate to rounding, so each iteration multiplies the wanted
// component's share by about 1 / (n ε); two suffice, the third settles the last bits.
constexpr int kIterations = 3;
// Inverse iteration for at most n / kMostByIteration vectors; more come from the QR iterations.
constexpr Eigen::Index kMostByIteration = 4;

// (T − λI) for the symmetric tridiagonal T = (diagonal, off), factored by Gaussian elimination with partial pivoting
// (rows i and i + 1 exchanged where the subdiagonal entry is the larger): P L U, U with two superdiagonals. A pivot
// that vanishes is replaced by a tiny one (the matrix is singular to working precision at an eigenvalue: that is
// what makes inverse iteration converge); `guarded`, every pivot smaller than that, so that no solve can overflow
// (LAPACK's dlagtf), for the rare matrix whose unguarded iteration does.
class ShiftedTridiagonal {
 public:
  ShiftedTridiagonal(const Eigen::VectorXd& diagonal, const Eigen::VectorXd& off, double shift, double tiny,
                     bool guarded) {
    auto pivot = [&](double p) { return (guarded ? std::fabs(p) < tiny : p == 0) ? std::copysign(tiny, p) : p; };
    const size_t n = size_t(diagonal.size());
    u0_.resize(n), u1_.assign(n, 0.0), u2_.assign(n, 0.0), l_.assign(n, 0.0), swapped_.assign(n, 0);
    for (size_t i = 0; i < n; ++i) u0_[i] = diagonal(Eigen::Index(i)) - shift;
    for (size_t i = 0; i + 1 < n; ++i) u1_[i] = off(Eigen::Index(i));
    // Row i + 1 before elimination: (sub = off[i], diag, super).
    for (size_t i = 0; i + 1 < n; ++i) {
      const double sub = off(Eigen::Index(i));
      double& next_diagonal = u0_[i + 1];
      const double next_super = i + 2 < n ? off(Eigen::Index(i + 1)) : 0.0;
      if (std::fabs(u0_[i]) >= std::fabs(sub)) {
        u0_[i] = pivot(u0_[i]);
        l_[i] = sub / u0_[i];
        next_diagonal -= l_[i] * u1_[i];
        u1_[i + 1] = next_super;
      } else {
        // Exchange rows i and i + 1: row i becomes (sub, next_diagonal, next_super).
        swapped_[i] = 1;
        const double p = pivot(sub);  // sub, unless guarded and tiny
        l_[i] = u0_[i] / p;
        u0_[i] = p;
        const double old_super = u1_[i];
        u1_[i] = next_diagonal;
        u2_[i] = next_super;
        next_diagonal = old_super - l_[i] * next_diagonal;
        u1_[i + 1] = -l_[i] * next_super;
      }
    }
    if (n > 0) u0_[n - 1] = pivot(u0_[n - 1]);
  }

  // x := (T − λI)⁻¹ x.
  void solve(Eigen::VectorXd& x) const {
    const size_t n = u0_.size();
    for (size_t i = 0; i + 1 < n; ++i) {
      if (swapped_[i]) std::swap(x(Eigen::Index(i)), x(Eigen::Index(i + 1)));
      x(Eigen::Index(i + 1)) -= l_[i] * x(Eigen::Index(i));
    }
    for (size_t i = n; i-- > 0;) {
      double sum = x(Eigen::Index(i));
      if (i + 1 < n) sum -= u1_[i] * x(Eigen::Index(i + 1));
      if (i + 2 < n) sum -= u2_[i] * x(Eigen::Index(i + 2));
      x(Eigen::Index(i)) = sum / u0_[i];
    }
  }

 private:
  std::vector<double> u0_, u1_, u2_, l_;
  std::vector<uint8_t> swapped_;
};

}  // namespace

void sign_by_largest_entry(Eigen::Ref<Eigen::VectorXd> vector) {
  Eigen::Index largest = 0;
  for (Eigen::Index i = 1; i < vector.size(); ++i)
    if (std::fabs(vector(i)) > std::fabs(vector(largest))) largest = i;
  if (vector.size() > 0 && vector(largest) < 0) vector = -vector;
}

LargestEigenvectors::LargestEigenvectors(const Eigen::MatrixXd& symmetric) {
  // Scaled by the largest entry, as the dense solver does, so that the eigenvalues are the dense solver's.
  Eigen::MatrixXd full = symmetric.selfadjointView<Eigen::Lower>();
  scale_ = full.cwiseAbs().maxCoeff();
  if (!(scale_ > 0)) scale_ = 1;
  full /= scale_;
  reduction_.compute(full);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> tridiagonal;
  tridiagonal.computeFromTridiagonal(reduction_.diagonal(), reduction_.subDiagonal(), Eigen::EigenvaluesOnly);
  values_ = tridiagonal.eigenvalues() * scale_;
}

Eigen::MatrixXd LargestEigenvectors::vectors(Eigen::Index count) const {
  const Eigen::Index n = values_.size();
  count = std::clamp<Eigen::Index>(count, 0, n);
  const Eigen::VectorXd diagonal = reduction_.diagonal(), off = reduction_.subDiagonal();
  // Many vectors: the QR iterations' own, the rotations accumulated (their cost no longer falls with the count).
  if (count > n / kMostByIteration) return all_vectors(diagonal, off, count);
  double norm = 0;  // the tridiagonal matrix's 1-norm
  for (Eigen::Index i = 0; i < n; ++i)
    norm = std::max(norm, std::fabs(diagonal(i)) + (i > 0 ? std::fabs(off(i - 1)) : 0.0) +
                              (i + 1 < n ? std::fabs(off(i)) : 0.0));
  Eigen::MatrixXd tridiagonal_vectors(n, count);
  const double epsilon = std::numeric_limits<double>::epsilon();
  const double tiny = (norm > 0 ? norm : 1.0) * epsilon;  // a zero matrix: any orthonormal vectors
  Eigen::Index cluster_first = 0;
  double previous_shift = 0;
  for (Eigen::Index j = 0; j < count; ++j) {
    double shift = values_(n - 1 - j) / scale_;
    if (j > 0 && previous_shift - shift > kClusterGap * norm) cluster_first = j;
    // Equal eigenvalues: shifts a little apart, so that each iteration does not find the same vector.
    if (j > cluster_first) shift = std::min(shift, previous_shift - 10 * epsilon * std::max(std::fabs(shift), tiny));
    previous_shift = shift;
    Eigen::VectorXd x(n);
    auto iterate = [&](bool guarded) {
      const ShiftedTridiagonal factored(diagonal, off, shift, tiny, guarded);
      // A fixed start with a component along every vector (a deterministic pseudo-random sequence).
      uint64_t state = 0x9E3779B97F4A7C15ull ^ uint64_t(j);
      for (Eigen::Index i = 0; i < n; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        x(i) = double(state >> 11) * 0x1.0p-53 - 0.5;
      }
      for (int iteration = 0; iteration <= kIterations; ++iteration) {
        if (guarded) x /= x.cwiseAbs().maxCoeff();  // no overflow in the norm
        x /= x.norm();
        if (iteration == kIterations) break;
        factored.solve(x);
        for (Eigen::Index k = cluster_first; k < j; ++k)
          x -= tridiagonal_vectors.col(k).dot(x) * tridiagonal_vectors.col(k);
      }
      return x.allFinite();
    };
    // An iteration that overflowed (pivots tiny but not zero) again with its pivots guarded; should that fail too,
    // every vector from the QR sweeps.
    if (!iterate(false) && !iterate(true)) return all_vectors(diagonal, off, count);
    tridiagonal_vectors.col(j) = x;
  }
  return in_matrix_basis(tridiagonal_vectors);
}

Eigen::MatrixXd LargestEigenvectors::all_vectors(const Eigen::VectorXd& diagonal, const Eigen::VectorXd& off,
                                                 Eigen::Index count) const {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> all;
  all.computeFromTridiagonal(diagonal, off, Eigen::ComputeEigenvectors);
  return in_matrix_basis(all.eigenvectors().rightCols(count).rowwise().reverse());
}

Eigen::MatrixXd LargestEigenvectors::in_matrix_basis(const Eigen::MatrixXd& tridiagonal_vectors) const {
  Eigen::MatrixXd out = reduction_.matrixQ() * tridiagonal_vectors;
  for (Eigen::Index j = 0; j < out.cols(); ++j) {
    out.col(j).normalize();
    sign_by_largest_entry(out.col(j));
  }
  return out;
}

}  // namespace segmorph
