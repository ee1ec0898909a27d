// The smallest eigenpairs of the Laplace–Beltrami operator: K φ = λ M φ (K stiffness, M = diag(mass),
// from laplacian.h), whole mesh or per connected component.
//
// Large problems use Spectra's Lanczos solver in shift-invert mode, (K − σM)⁻¹ M φ = φ / (λ − σ), with
// the linear solves by a sparse Cholesky factorization (LDLᵀ) of K − σM. K is singular (constants are in
// its kernel), so the shift is slightly negative: K − σM is then positive definite, and the eigenvalues
// nearest σ are exactly the smallest ones. Small problems use a dense generalized solver, which is
// faster there and has no restriction on how many pairs are asked for. Very large problems (above
// EigenSettings::multilevel_limit vertices) solve a coarse problem instead and refine its pairs on the whole mesh
// without factorizing it (EigenMethod::multilevel).
//
// A mesh with C connected components has C zero eigenvalues, and its eigenvectors can mix components
// arbitrarily; heat-kernel distances are meaningful only within a component, so the spectral stage
// works per component (component_spectra).
//
// This file is the only one that sees Spectra; its exceptions become a Status here.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/topology.h"
#include "encode/segmentation/laplacian.h"
#include "segmorph/status.h"

namespace segmorph {

struct Eigenpairs {
  // n eigenvalues λ, ascending, in 1/(units of the positions)². K is positive semidefinite, so values
  // below 0 can only be rounding and are returned as 0; the first value of a connected mesh is 0 up to
  // rounding (below 1e-10 of the next one in the tests) with a constant eigenvector.
  Eigen::VectorXd values;
  // W × n, column-major, column i the eigenvector φ_i of values[i]. M-orthonormal: ΦᵀMΦ = I.
  // Deterministic sign: in each column the entry of largest magnitude is positive (on exact ties the
  // one of lowest index). Within a repeated eigenvalue the basis is whichever the solver found.
  Eigen::MatrixXd vectors;
};

enum class EigenMethod {
  automatic,     // dense up to EigenSettings::dense_limit vertices (or when count ≥ W/2), multilevel above
                 // EigenSettings::multilevel_limit, else shift_invert
  dense,         // Eigen::GeneralizedSelfAdjointEigenSolver on dense W × W matrices: O(W³) time, O(W²) memory
  shift_invert,  // Spectra Lanczos with sparse LDLᵀ solves; needs count < W − 1
  // The pairs of a coarse problem (aggregates of vertices, smoothed aggregation: see smallest_eigenpairs), solved by
  // shift_invert (or dense), carried back to every vertex, smoothed and made the Ritz pairs of K and M on their span.
  // Approximate (the eigenvalues are upper bounds; on the tests' 10⁴-vertex meshes within 0.5 %), for a fraction of
  // the time and memory of a factorization of the whole mesh.
  multilevel,
};

struct EigenSettings {
  EigenMethod method = EigenMethod::automatic;
  size_t dense_limit = 300;  // vertices
  // automatic: above this many vertices (of a component: component_spectra solves each on its own), multilevel (the
  // shared samples and sequences all stay below it).
  size_t multilevel_limit = 60000;
  // multilevel: the coarse problem has at most this many aggregates (and at least 8 vertices each on average, and at
  // least twice as many aggregates as coarse pairs), else the problem is solved by shift_invert.
  size_t coarse_vertices = 20000;
  // multilevel: degree of the Chebyshev filter applied to the carried-back vectors before the Rayleigh–Ritz step.
  int filter_degree = 32;
  // Threads (0: every hardware thread): component_spectra's components up to multilevel_limit, solved side by side,
  // and multilevel's filter (it works on blocks of 8 vectors, so at most count / 4 threads have work); the pairs are
  // the same for any number.
  size_t threads = 1;
  // Spectra's convergence test: each Ritz value ν = 1/(λ − σ) has a residual below tolerance · |ν|.
  double tolerance = 1e-10;
  int max_restarts = 1000;  // implicit restarts of the Lanczos iteration before giving up
  // Told each step of the shift-invert search ("factorizing", "Lanczos iteration", ...); empty: nothing. The Lanczos
  // iteration, whose length is not known ahead, also tells how many solves it has made, at most every
  // `solve_report_seconds`.
  std::function<void(const std::string& step)> progress;
  double solve_report_seconds = 2;
};

// Shift of the shift-invert mode: σ = −kShiftAreaFraction / (Σ mass). The first nonzero eigenvalue of a
// surface of area A is 8π/A for a sphere and about 0.1/A to 1/A for long thin shapes (a snake), so σ is
// one to three orders of magnitude closer to 0 than λ₁: negative enough to make K − σM safely positive
// definite (its condition number is about λ_max / |σ|, ~1e8 at 1e5 vertices), small enough to keep the
// wanted eigenvalues well separated after the inversion.
constexpr double kShiftAreaFraction = 1e-2;

// The min(count, W) smallest eigenpairs of K φ = λ M φ. stiffness: W × W symmetric positive
// semidefinite (CotangentLaplacian::stiffness); mass: W strictly positive entries.
//
// Lanczos may skip a copy of a repeated eigenvalue (exact multiplicities occur on symmetric meshes), so
// the shift-invert result is verified by Sylvester's law of inertia (an LDLᵀ of K − τM counts the
// eigenvalues below τ, τ in the gap before the last wanted cluster), and skipped pairs are searched
// again with the found ones deflated. Values within 1e-3 (relative) of the last wanted value count as
// one cluster: when `count` ends inside such a cluster, which of its members are returned is not
// specified (they agree to 1e-3).
//
// The multilevel method (smoothed aggregation, as in algebraic multigrid): vertices are grouped into connected
// aggregates of a few hops' radius (greedy, in vertex order; at most `coarse_vertices` of them and about 8 vertices or
// more each), P₀ the aggregates' indicator functions and P = (I − ωD⁻¹K) P₀ (D = diag K, ω = 4 / (3ρ), ρ Gershgorin's
// bound on the spectral radius of D⁻¹K). The coarse problem PᵀKP ψ = λ M_c ψ (M_c: each aggregate's mass; P keeps
// constants, so the coarse operator has K's structure) is solved for max(2·count, count + 8) pairs; their vectors Pψ
// are filtered by a Chebyshev polynomial of D⁻¹K of degree `filter_degree` (1 at 0, damping [max(2β, ρm/n), ρ], β
// the largest Rayleigh quotient of D⁻¹K among them, m/n aggregates per vertex: what the coarse space cannot represent)
// and replaced by the Ritz pairs of K and M on their span, of which the `count` smallest are returned: M-orthonormal
// vectors and their Rayleigh quotients, which bound the true eigenvalues from above. A problem too small to coarsen
// (fewer than twice as many aggregates as coarse pairs), or one no radius up to 64 coarsens to the target, is solved
// by shift_invert.
//
// Fails with numerical when the Lanczos iteration does not converge, K − σM cannot be factorized, or
// skipped eigenvalues are still missing after a few deflated restarts; with invalid_argument when
// shift_invert is forced with count ≥ W − 1.
Status smallest_eigenpairs(const Eigen::SparseMatrix<double>& stiffness, const Eigen::VectorXd& mass, size_t count,
                           Eigenpairs& out, const EigenSettings& settings = EigenSettings());

struct ComponentSpectrum {
  // n welded vertex indices of the component, ascending; vertices[local] is the welded vertex of local index.
  std::vector<uint32_t> vertices;
  // min(count, n) eigenpairs of the component's own operator; eigenvector rows are local indices.
  Eigenpairs eigenpairs;
};

struct ComponentSpectra {
  std::vector<ComponentSpectrum> components;  // topology.component_count, in component order
  std::vector<uint32_t> local_index;          // W: the index of each welded vertex within its component
};

// The smallest eigenpairs of every connected component of `topology`, each from the rows and columns of
// `laplacian` (built from the same welded vertices and triangles) that belong to it. Components above
// settings.multilevel_limit vertices (unless a method other than multilevel is forced) one after another, each with
// settings.threads for its filter; the others side by side on up to settings.threads threads, larger first,
// `progress` told from the calling thread's only. A component's first eigenvalue is 0 with a constant eigenvector; a
// component of one vertex has only that pair.
Status component_spectra(const CotangentLaplacian& laplacian, const WeldedTopology& topology, size_t count,
                         ComponentSpectra& out, const EigenSettings& settings = EigenSettings());

}  // namespace segmorph
