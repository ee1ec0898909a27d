#include "encode/segmentation/eigensolver.h"

#include <Spectra/SymGEigsShiftSolver.h>
#include <Spectra/Util/SimpleRandom.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <new>
#include <string>
#include <thread>
#include <utility>

#include "common/parallel.h"

namespace segmorph {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Factorization = Eigen::SimplicialLDLT<SparseMatrix>;

// Deflated restarts allowed when the inertia check finds eigenvalues the Lanczos iteration skipped.
constexpr int kMaxDeflations = 4;
// Computed eigenvalues within this relative distance of the last wanted one count as its cluster, and
// values below kZeroFraction · |σ| as zero: rounding makes exact multiplicities differ by ~1e-10, and
// inertia counts are only trusted for a τ well inside a gap.
constexpr double kClusterWidth = 1e-3;
constexpr double kZeroFraction = 1e-3;

// K + s·M as a sparse matrix (K has no diagonal entry where a vertex has no triangle, so M is added
// as a matrix of its own rather than on K's diagonal).
SparseMatrix plus_mass(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, double s) {
  const Eigen::Index n = stiffness.rows();
  SparseMatrix diagonal(n, n);
  diagonal.reserve(Eigen::VectorXi::Constant(n, 1));
  for (Eigen::Index i = 0; i < n; ++i) diagonal.insert(i, i) = s * mass[i];
  return stiffness + diagonal;
}

// Spectra's operator for y = P (K − σM)⁻¹ z, z = M x, on the M-orthogonal complement of the locked
// vectors Φ (P = I − ΦΦᵀM; z is projected as M P x = z − MΦΦᵀz). With no locked vectors it is the plain
// shift-invert solve. The factorization of K − σM is computed beforehand; Spectra's set_shift, called
// while its solver is constructed, only passes the same σ. `solved` is told the number of solves so far, at most
// every `report_seconds`.
class ShiftedCholeskySolve {
 public:
  using Scalar = double;

  ShiftedCholeskySolve(const Factorization& factorization, const Eigen::VectorXd& mass, const Eigen::MatrixXd& locked,
                       std::function<void(size_t solves)> solved, double report_seconds)
      : factorization_(factorization), mass_(mass), locked_(locked), mass_locked_(mass.asDiagonal() * locked),
        solved_(std::move(solved)), report_seconds_(report_seconds), reported_(std::chrono::steady_clock::now()) {}

  Eigen::Index rows() const { return mass_.size(); }
  Eigen::Index cols() const { return mass_.size(); }
  void set_shift(double) {}

  void perform_op(const double* x_in, double* y_out) const {
    ++solves_;
    if (solved_) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - reported_).count() >= report_seconds_) {
        reported_ = now;
        solved_(solves_);
      }
    }
    Eigen::Map<const Eigen::VectorXd> z(x_in, rows());
    Eigen::Map<Eigen::VectorXd> y(y_out, rows());
    if (locked_.cols() == 0) {
      y.noalias() = factorization_.solve(z);
      return;
    }
    const Eigen::VectorXd projected = z - mass_locked_ * (locked_.transpose() * z);
    y.noalias() = factorization_.solve(projected);
    y -= locked_ * (mass_locked_.transpose() * y);
  }

 private:
  const Factorization& factorization_;
  const Eigen::VectorXd& mass_;
  const Eigen::MatrixXd& locked_;
  const Eigen::MatrixXd mass_locked_;  // MΦ
  const std::function<void(size_t)> solved_;
  const double report_seconds_;
  mutable size_t solves_ = 0;  // Spectra calls perform_op on a const operator
  mutable std::chrono::steady_clock::time_point reported_;
};

// Spectra's operator for y = M x, M diagonal; it also defines the M inner product of the Lanczos basis.
class DiagonalMassProduct {
 public:
  using Scalar = double;

  explicit DiagonalMassProduct(const Eigen::VectorXd& mass) : mass_(mass) {}

  Eigen::Index rows() const { return mass_.size(); }
  Eigen::Index cols() const { return mass_.size(); }

  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd> y(y_out, rows());
    y = mass_.cwiseProduct(x);
  }

 private:
  const Eigen::VectorXd& mass_;
};

// Rayleigh–Ritz on the span of `vectors` (W × k): makes them M-orthonormal to rounding whatever the
// Lanczos bases lost, and the values their Rayleigh quotients, ascending. k × k problem, O(W·k²).
Status rayleigh_ritz(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, Eigenpairs& pairs) {
  const Eigen::MatrixXd projected_stiffness = pairs.vectors.transpose() * (stiffness * pairs.vectors);
  const Eigen::MatrixXd projected_mass = pairs.vectors.transpose() * mass.asDiagonal() * pairs.vectors;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ritz(
      0.5 * (projected_stiffness + projected_stiffness.transpose()),
      0.5 * (projected_mass + projected_mass.transpose()), Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (ritz.info() != Eigen::Success || !(projected_mass.diagonal().minCoeff() > 0.5)) {
    return Status(StatusCode::numerical, "eigensolver: the Lanczos vectors are not linearly independent (" +
                                             std::to_string(stiffness.rows()) + " vertices)");
  }
  pairs.values = ritz.eigenvalues();
  pairs.vectors = pairs.vectors * ritz.eigenvectors();
  return Status::Ok();
}

// `count` Lanczos vectors of the smallest eigenvalues on the M-orthogonal complement of `locked`.
Status lanczos(const Factorization& factorization, const Eigen::VectorXd& mass, double sigma,
               const Eigen::MatrixXd& locked, Eigen::Index count, const EigenSettings& settings,
               Eigen::MatrixXd& vectors) {
  const Eigen::Index n = mass.size();
  // Lanczos basis size: Spectra advises at least twice the wanted pairs; +20 helps small counts converge.
  // It cannot exceed the dimension of the space searched.
  const Eigen::Index basis = std::min(n - locked.cols(), std::max(2 * count + 1, count + 20));
  if (basis <= count) {
    return Status(StatusCode::numerical, "eigensolver: " + std::to_string(count) + " more eigenpairs asked of a " +
                                             std::to_string(n - locked.cols()) + "-dimensional space");
  }
  std::function<void(size_t)> solved;
  if (settings.progress)
    solved = [&](size_t solves) {
      settings.progress("eigenpairs: Lanczos iteration, " + std::to_string(solves) + " solves (" + std::to_string(n) +
                        " vertices)");
    };
  ShiftedCholeskySolve solve(factorization, mass, locked, std::move(solved), settings.solve_report_seconds);
  DiagonalMassProduct mass_product(mass);
  // Spectra's own fixed-seed start vector (the same input gives the same output), without locked parts.
  Eigen::VectorXd start = Spectra::SimpleRandom<double>(0).random_vec(n);
  if (locked.cols() > 0) start -= locked * (locked.transpose() * mass.cwiseProduct(start));
  try {
    Spectra::SymGEigsShiftSolver<ShiftedCholeskySolve, DiagonalMassProduct, Spectra::GEigsMode::ShiftInvert> solver(
        solve, mass_product, count, basis, sigma);
    solver.init(start.data());
    // The largest ν = 1/(λ − σ) are the λ nearest σ, i.e. the smallest λ since σ is below them all.
    solver.compute(Spectra::SortRule::LargestMagn, settings.max_restarts, settings.tolerance,
                   Spectra::SortRule::SmallestAlge);
    if (solver.info() != Spectra::CompInfo::Successful) {
      return Status(StatusCode::numerical, "eigensolver: " + std::to_string(solver.eigenvalues().size()) + " of " +
                                               std::to_string(count) + " eigenpairs converged after " +
                                               std::to_string(solver.num_iterations()) + " restarts (" +
                                               std::to_string(n) + " vertices)");
    }
    vectors = solver.eigenvectors();
  } catch (const std::exception& error) {
    return Status(StatusCode::numerical, std::string("eigensolver: ") + error.what());
  }
  return Status::Ok();
}

// How many eigenvalues of K φ = λ M φ lie below tau: the number of negative pivots of an LDLᵀ
// factorization of K − τM (Sylvester's law of inertia). −1 when the factorization meets a zero pivot.
Eigen::Index eigenvalues_below(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, double tau) {
  Factorization factorization(plus_mass(stiffness, mass, -tau));
  if (factorization.info() != Eigen::Success) return -1;
  return Eigen::Index((factorization.vectorD().array() < 0).count());
}

Status dense_eigenpairs(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, Eigen::Index count,
                        Eigenpairs& out) {
  const Eigen::MatrixXd dense_stiffness(stiffness);
  const Eigen::MatrixXd dense_mass(mass.asDiagonal());
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(dense_stiffness, dense_mass,
                                                                   Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (solver.info() != Eigen::Success) {
    return Status(StatusCode::numerical, "eigensolver: the dense generalized eigensolver did not converge (" +
                                             std::to_string(stiffness.rows()) + " vertices)");
  }
  // Eigen returns the values ascending and the vectors M-orthonormal (it solves through M's Cholesky factor).
  out.values = solver.eigenvalues().head(count);
  out.vectors = solver.eigenvectors().leftCols(count);
  return Status::Ok();
}

// Lanczos can skip a copy of a repeated eigenvalue (a single start vector has no component along
// it but for rounding; symmetric meshes have exact multiplicities). So the result is checked by inertia:
// with τ between the last wanted cluster and the computed value before it, the number of eigenvalues
// below τ must equal the number found below τ. When some were skipped, the pairs found below τ are
// locked and the rest is searched again on their M-orthogonal complement.
Status shift_invert_eigenpairs(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, Eigen::Index count,
                               const EigenSettings& settings, Eigenpairs& out) {
  const Eigen::Index n = stiffness.rows();
  const double sigma = -kShiftAreaFraction / mass.sum();
  const auto say = [&](const std::string& step) {
    if (settings.progress) settings.progress(step + " (" + std::to_string(n) + " vertices)");
  };
  say("eigenpairs: factorizing");
  const Factorization factorization(plus_mass(stiffness, mass, -sigma));
  // K − σM is positive definite when K is positive semidefinite: a non-positive pivot means it is not.
  if (factorization.info() != Eigen::Success || !(factorization.vectorD().minCoeff() > 0)) {
    return Status(StatusCode::numerical, "eigensolver: K - sigma M is not positive definite (" + std::to_string(n) +
                                             " vertices); the stiffness matrix is not positive semidefinite");
  }

  Eigen::MatrixXd locked(n, 0);
  say("eigenpairs: Lanczos iteration");
  SEGMORPH_RETURN_IF_ERROR(lanczos(factorization, mass, sigma, locked, count, settings, out.vectors));
  for (int deflation = 0;; ++deflation) {
    SEGMORPH_RETURN_IF_ERROR(rayleigh_ritz(stiffness, mass, out));
    const double last = out.values[count - 1];
    Eigen::Index found_below = count - 1;  // values below the last cluster
    const double cluster_floor = std::min(last * (1 - kClusterWidth), last - kZeroFraction * std::fabs(sigma));
    while (found_below > 0 && out.values[found_below - 1] >= cluster_floor) --found_below;
    if (found_below == 0) return Status::Ok();  // only the last cluster: nothing can have been skipped below it
    const double tau = 0.5 * (out.values[found_below - 1] + last);
    say("eigenpairs: checking by inertia");
    const Eigen::Index below = eigenvalues_below(stiffness, mass, tau);
    if (below < 0) {
      return Status(StatusCode::numerical,
                    "eigensolver: the inertia check met a zero pivot (" + std::to_string(n) + " vertices)");
    }
    if (below <= found_below) return Status::Ok();
    if (deflation == kMaxDeflations) {
      return Status(StatusCode::numerical,
                    "eigensolver: " + std::to_string(below) + " eigenvalues lie below " + std::to_string(tau) +
                        " but Lanczos found " + std::to_string(found_below) + " after " +
                        std::to_string(kMaxDeflations) + " deflated restarts (" + std::to_string(n) + " vertices)");
    }
    say("eigenpairs: deflated restart " + std::to_string(deflation + 1));
    locked = out.vectors.leftCols(found_below);
    Eigen::MatrixXd fresh;
    SEGMORPH_RETURN_IF_ERROR(lanczos(factorization, mass, sigma, locked, count - found_below, settings, fresh));
    out.vectors.resize(n, count);
    out.vectors << locked, fresh;
  }
}

// Aggregates of the graph of K (its off-diagonal pattern: the mesh's edges): vertices in index order, each one not yet
// in an aggregate starts one of the vertices not yet in one within `radius` edges of it (breadth first). Returns the
// aggregate of every vertex; `count` receives how many there are.
std::vector<int32_t> aggregate_vertices(const SparseMatrix& stiffness, int radius, Eigen::Index& count) {
  const Eigen::Index n = stiffness.rows();
  std::vector<int32_t> aggregate(size_t(n), -1);
  std::vector<Eigen::Index> queue;
  std::vector<int> depth(size_t(n), 0);
  count = 0;
  for (Eigen::Index seed = 0; seed < n; ++seed) {
    if (aggregate[size_t(seed)] >= 0) continue;
    const int32_t label = int32_t(count++);
    queue.assign(1, seed);
    aggregate[size_t(seed)] = label, depth[size_t(seed)] = 0;
    for (size_t head = 0; head < queue.size(); ++head) {
      const Eigen::Index v = queue[head];
      if (depth[size_t(v)] == radius) continue;
      for (SparseMatrix::InnerIterator it(stiffness, v); it; ++it) {
        const Eigen::Index w = it.row();
        if (aggregate[size_t(w)] >= 0) continue;
        aggregate[size_t(w)] = label, depth[size_t(w)] = depth[size_t(v)] + 1;
        queue.push_back(w);
      }
    }
  }
  return aggregate;
}

// Applies p(D⁻¹K) to the columns of `vectors`, p the Chebyshev polynomial of `degree` that is 1 at 0 and at most
// 1 / T_degree((b + a) / (b − a)) in magnitude on [a, b] (Zhou & Saad's scaled three-term recurrence): components of
// eigenvalues in [a, b] are damped by that factor, those well below a kept almost whole. Each column's recurrence is
// its own: blocks of kFilterBlock columns run on up to `threads` threads, with the same results for any number.
constexpr Eigen::Index kFilterBlock = 8;

void chebyshev_filter(const SparseMatrix& stiffness, const Eigen::VectorXd& inverse_diagonal, double a, double b,
                      int degree, size_t threads, Eigen::MatrixXd& vectors) {
  if (degree < 1 || !(b > a) || !(a > 0)) return;
  const double e = (b - a) / 2, c = (b + a) / 2;
  const Eigen::Index n = vectors.rows(), columns = vectors.cols();
  const size_t blocks = size_t((columns + kFilterBlock - 1) / kFilterBlock);
  parallel_items(blocks, thread_count(threads), [&](size_t block) {
    const Eigen::Index first = Eigen::Index(block) * kFilterBlock;
    const Eigen::Index width = std::min(kFilterBlock, columns - first);
    // Four n × width buffers for the whole recurrence, rotated rather than allocated at every step.
    Eigen::MatrixXd previous = vectors.middleCols(first, width), current(n, width), next(n, width), product(n, width);
    double sigma = -e / c;
    const double tau = 2 / sigma;
    product.noalias() = stiffness * previous;
    current = (inverse_diagonal.asDiagonal() * product - c * previous) * (sigma / e);
    for (int i = 2; i <= degree; ++i) {
      const double next_sigma = 1 / (tau - sigma);
      product.noalias() = stiffness * current;
      next = (inverse_diagonal.asDiagonal() * product - c * current) * (2 * next_sigma / e) -
             (sigma * next_sigma) * previous;
      previous.swap(current);
      current.swap(next);
      sigma = next_sigma;
    }
    vectors.middleCols(first, width) = current;
  });
}

Status multilevel_eigenpairs(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, Eigen::Index count,
                             const EigenSettings& settings, Eigenpairs& out) {
  const Eigen::Index n = stiffness.rows();
  const Eigen::Index coarse_pairs = std::max<Eigen::Index>(2 * count, count + 8);
  const Eigen::Index target =
      std::max(Eigen::Index(std::min(settings.coarse_vertices, size_t(n) / 8)), 2 * coarse_pairs);
  // The smallest radius whose aggregates are few enough.
  Eigen::Index m = 0;
  std::vector<int32_t> aggregate;
  for (int radius = 1; radius <= 64; ++radius) {
    aggregate = aggregate_vertices(stiffness, radius, m);
    if (m <= target) break;
  }
  // Too few aggregates for the coarse pairs, or (a graph no radius up to 64 coarsens enough) too many to be cheap.
  if (m < 2 * coarse_pairs || m > target) return shift_invert_eigenpairs(stiffness, mass, count, settings, out);
  if (settings.progress)
    settings.progress("eigenpairs: coarse problem of " + std::to_string(m) + " aggregates (" + std::to_string(n) +
                      " vertices)");

  // Damped Jacobi on K: ωD⁻¹ with D = diag(K), ω = 4 / (3ρ), ρ Gershgorin's bound on the spectral radius of D⁻¹K.
  const Eigen::VectorXd diagonal = stiffness.diagonal();
  double rho = 0;
  for (Eigen::Index j = 0; j < n; ++j) {
    double sum = 0;
    for (SparseMatrix::InnerIterator it(stiffness, j); it; ++it) sum += std::fabs(it.value());
    if (diagonal[j] > 0) rho = std::max(rho, sum / diagonal[j]);
  }
  if (!(rho > 0) || !std::isfinite(rho)) {
    return Status(StatusCode::numerical, "eigensolver: the stiffness matrix has no positive finite diagonal (" +
                                             std::to_string(n) + " vertices)");
  }
  Eigen::VectorXd inverse_diagonal(n);  // 0 where a vertex has no stiffness: the smoothing leaves it alone
  for (Eigen::Index i = 0; i < n; ++i) inverse_diagonal[i] = diagonal[i] > 0 ? 1 / diagonal[i] : 0.0;

  // P = (I − ωD⁻¹K) P₀, the coarse problem PᵀKP ψ = λ M_c ψ.
  std::vector<Eigen::Triplet<double>> indicator;
  indicator.reserve(size_t(n));
  for (Eigen::Index i = 0; i < n; ++i) indicator.emplace_back(i, aggregate[size_t(i)], 1.0);
  SparseMatrix tentative(n, m);
  tentative.setFromTriplets(indicator.begin(), indicator.end());
  aggregate = {};
  const Eigen::VectorXd jacobi = (4.0 / (3.0 * rho)) * inverse_diagonal;
  const SparseMatrix prolongation = tentative - SparseMatrix(jacobi.asDiagonal() * (stiffness * tentative));
  const SparseMatrix coarse_stiffness = SparseMatrix(prolongation.transpose()) * (stiffness * prolongation);
  // M_c: the aggregates' masses, P₀ᵀM1, a lumped stand-in for PᵀMP (positive, and exact on constants' total mass);
  // the Ritz step on the whole mesh's K and M below makes the pairs those of the span, whatever the coarse mass was.
  const Eigen::VectorXd coarse_mass = tentative.transpose() * mass;
  EigenSettings coarse_settings = settings;
  coarse_settings.method = EigenMethod::automatic;
  coarse_settings.multilevel_limit = size_t(-1);
  Eigenpairs coarse;
  SEGMORPH_RETURN_IF_ERROR(
      smallest_eigenpairs(coarse_stiffness, coarse_mass, size_t(coarse_pairs), coarse, coarse_settings));

  // Carried back, filtered, Ritz pairs.
  if (settings.progress)
    settings.progress("eigenpairs: carrying back and filtering (" + std::to_string(n) + " vertices)");
  out.vectors = prolongation * coarse.vectors;
  double band = 0;
  for (Eigen::Index j = 0; j < out.vectors.cols(); ++j) {
    const double energy = out.vectors.col(j).dot(stiffness * out.vectors.col(j));
    band = std::max(band, energy / out.vectors.col(j).cwiseAbs2().dot(diagonal));
  }
  // The damped band starts at twice the largest Rayleigh quotient among the carried-back vectors, and no lower than
  // ρ·m/n, about where the modes the aggregates cannot represent begin (at 10⁶ vertices the quotients lie 10⁴ times
  // below ρ, where a polynomial of this degree damps nothing).
  const double lower = std::max(2 * band, rho * double(m) / double(n));
  chebyshev_filter(stiffness, inverse_diagonal, lower, rho, settings.filter_degree, settings.threads, out.vectors);
  for (Eigen::Index j = 0; j < out.vectors.cols(); ++j) {
    const double norm = std::sqrt(out.vectors.col(j).cwiseAbs2().dot(mass));
    if (!(norm > 0) || !std::isfinite(norm)) {
      return Status(StatusCode::numerical,
                    "eigensolver: a carried-back vector vanished (" + std::to_string(n) + " vertices)");
    }
    out.vectors.col(j) /= norm;
  }
  SEGMORPH_RETURN_IF_ERROR(rayleigh_ritz(stiffness, mass, out));
  out.values.conservativeResize(count);
  out.vectors.conservativeResize(Eigen::NoChange, count);
  return Status::Ok();
}

// Values below 0 to 0; each vector's entry of largest magnitude positive (the first on ties).
void normalize(Eigenpairs& pairs) {
  pairs.values = pairs.values.cwiseMax(0.0);
  for (Eigen::Index j = 0; j < pairs.vectors.cols(); ++j) {
    Eigen::Index largest = 0;
    for (Eigen::Index i = 1; i < pairs.vectors.rows(); ++i) {
      if (std::fabs(pairs.vectors(i, j)) > std::fabs(pairs.vectors(largest, j))) largest = i;
    }
    if (pairs.vectors.rows() > 0 && pairs.vectors(largest, j) < 0) pairs.vectors.col(j) *= -1.0;
  }
}

}  // namespace

Status smallest_eigenpairs(const SparseMatrix& stiffness, const Eigen::VectorXd& mass, size_t count, Eigenpairs& out,
                           const EigenSettings& settings) {
  assert(stiffness.rows() == stiffness.cols() && stiffness.rows() == mass.size());
  assert(mass.size() == 0 || mass.minCoeff() > 0);
  const Eigen::Index n = stiffness.rows();
  const Eigen::Index wanted = Eigen::Index(std::min(count, size_t(n)));
  if (wanted == 0) {
    out.values.resize(0);
    out.vectors.resize(n, 0);
    return Status::Ok();
  }
  EigenMethod method = settings.method;
  if (method == EigenMethod::automatic) {
    method = size_t(n) <= settings.dense_limit || 2 * wanted >= n ? EigenMethod::dense
             : size_t(n) > settings.multilevel_limit              ? EigenMethod::multilevel
                                                                  : EigenMethod::shift_invert;
  }
  const bool dense = method == EigenMethod::dense;
  if (!dense && wanted >= n - 1) {
    return Status(StatusCode::invalid_argument,
                  "eigensolver: shift-invert finds at most W - 2 = " + std::to_string(n - 2) + " eigenpairs, " +
                      std::to_string(wanted) + " asked");
  }
  Status status;
  try {
    status = dense                                ? dense_eigenpairs(stiffness, mass, wanted, out)
             : method == EigenMethod::multilevel ? multilevel_eigenpairs(stiffness, mass, wanted, settings, out)
                                                 : shift_invert_eigenpairs(stiffness, mass, wanted, settings, out);
  } catch (const std::bad_alloc&) {
    status = Status(StatusCode::numerical, "eigensolver: out of memory (" + std::to_string(n) + " vertices)");
  }
  if (!status.ok()) return status;
  for (Eigen::Index i = 0; i < out.values.size(); ++i) {
    if (!std::isfinite(out.values[i]) || !out.vectors.col(i).allFinite()) {
      return Status(StatusCode::numerical,
                    "eigensolver: non-finite eigenpair " + std::to_string(i) + " (" + std::to_string(n) + " vertices)");
    }
  }
  normalize(out);
  return Status::Ok();
}

Status component_spectra(const CotangentLaplacian& laplacian, const WeldedTopology& topology, size_t count,
                         ComponentSpectra& out, const EigenSettings& settings) {
  const size_t vertex_count = topology.welded_count();
  assert(size_t(laplacian.stiffness.rows()) == vertex_count && size_t(laplacian.mass.size()) == vertex_count);
  assert(topology.component.size() == vertex_count);

  out.components.assign(topology.component_count, ComponentSpectrum());
  out.local_index.assign(vertex_count, 0);
  for (size_t w = 0; w < vertex_count; ++w) {
    ComponentSpectrum& component = out.components[topology.component[w]];
    out.local_index[w] = uint32_t(component.vertices.size());
    component.vertices.push_back(uint32_t(w));
  }

  // Each component's block of K; entries between components would mean K and topology disagree.
  std::vector<std::vector<Eigen::Triplet<double>>> blocks(topology.component_count);
  for (Eigen::Index j = 0; j < laplacian.stiffness.outerSize(); ++j) {
    const uint32_t component = topology.component[size_t(j)];
    for (SparseMatrix::InnerIterator it(laplacian.stiffness, j); it; ++it) {
      assert(topology.component[size_t(it.row())] == component);
      blocks[component].emplace_back(out.local_index[size_t(it.row())], out.local_index[size_t(j)], it.value());
    }
  }

  // The components the multilevel method may take (above its limit, unless another method is forced) one after
  // another, each with every thread (its filter's); then the others side by side, larger first, each on one (a solve
  // is its own: the pairs do not depend on the threads), the steps told only from the calling thread's. The first
  // failure in component order is the one returned.
  const bool filtered = settings.method == EigenMethod::automatic || settings.method == EigenMethod::multilevel;
  std::vector<size_t> large, order;
  for (size_t c = 0; c < topology.component_count; ++c)
    (filtered && out.components[c].vertices.size() > settings.multilevel_limit ? large : order).push_back(c);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return out.components[a].vertices.size() > out.components[b].vertices.size();
  });
  std::vector<Status> statuses(topology.component_count, Status::Ok());
  auto solve = [&](size_t c, const EigenSettings& own) {
    ComponentSpectrum& component = out.components[c];
    const Eigen::Index n = Eigen::Index(component.vertices.size());
    SparseMatrix stiffness(n, n);
    stiffness.setFromTriplets(blocks[c].begin(), blocks[c].end());
    blocks[c] = {};
    Eigen::VectorXd mass(n);
    for (Eigen::Index i = 0; i < n; ++i) mass[i] = laplacian.mass[component.vertices[size_t(i)]];
    statuses[c] = smallest_eigenpairs(stiffness, mass, count, component.eigenpairs, own);
  };
  for (size_t c : large) solve(c, settings);
  const std::thread::id caller = std::this_thread::get_id();
  parallel_items(order.size(), thread_count(settings.threads), [&](size_t item) {
    EigenSettings own = settings;
    own.threads = 1;
    if (std::this_thread::get_id() != caller) own.progress = nullptr;
    solve(order[item], own);
  });
  for (size_t c = 0; c < statuses.size(); ++c)
    if (!statuses[c].ok())
      return Status(statuses[c].code(), "component " + std::to_string(c) + " of " +
                                            std::to_string(topology.component_count) + ": " + statuses[c].message());
  return Status::Ok();
}

}  // namespace segmorph
