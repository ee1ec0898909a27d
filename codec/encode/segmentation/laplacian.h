// The cotangent Laplace–Beltrami operator of a triangle mesh, with a lumped mass matrix.
//
// The spectral stage (heat-kernel distances, paper eq. 4) needs the eigenpairs of the surface's
// Laplace–Beltrami operator. Its standard finite-element discretisation with linear elements is the
// generalized problem K φ = λ M φ: K the cotangent stiffness matrix, M the mass matrix, lumped here to
// a diagonal so that the eigensolver's inner products and the heat kernel's area weights are per vertex.
//
// Degenerate triangles (zero area, zero-length edges: collinear corners, points that touch in the first
// frame and only separate later) are handled by intrinsic mollification (Sharp & Crane 2020, "A Laplacian
// for Nonmanifold Triangle Meshes"): every edge length is lengthened by the same small δ, just
// enough that every triangle satisfies the triangle inequality with a margin ε = kMollificationMargin of
// the mean edge length, and the operator is built from those lengths. Cotangents then stay finite
// instead of becoming inf/NaN: about sqrt(l/δ) ~ 300 for a triangle with collinear corners, about
// 2l/δ ~ 2e5 on a zero-length edge (tying the two coincident vertices together, as their distance
// asks). K stays positive semidefinite, and a mollified zero-area triangle gets the area of a needle of
// width ~sqrt(δ·l). On a mesh without (near-)degenerate triangles δ = 0 and nothing changes.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "common/topology.h"
#include "segmorph/status.h"

namespace segmorph {

struct CotangentLaplacian {
  // K: W × W, column-major, symmetric positive semidefinite (the weak form of −Δ, so the eigenvalues
  // λ of K φ = λ M φ are ≥ 0). Sign convention: for an edge ij,
  //   K_ij = −(cot α_ij + cot β_ij) / 2   (α, β the angles opposite the edge; one term on a boundary edge),
  //   K_ii = −Σ_{j≠i} K_ij,               so K·1 = 0 and fᵀK f = ∫|∇f|² for piecewise-linear f.
  // Entries are zero between vertices that share no triangle; a vertex with no triangle has an empty row.
  Eigen::SparseMatrix<double> stiffness;
  // M: the W diagonal entries of the lumped mass matrix, in units of area: one third of the area of
  // every incident triangle (barycentric lumping), so Σ mass = surface area. Strictly positive: a vertex
  // no (non-degenerate) triangle touches gets kIsolatedMassFraction × the mean mass of the others, so M
  // stays invertible; its stiffness row is empty, so it only adds its own zero eigenvalue.
  Eigen::VectorXd mass;
  // δ, in the units of the positions: the length added to every edge by mollification (0 when every
  // triangle already has the margin).
  double mollification = 0;
};

// Mass of a vertex no triangle touches, as a fraction of the mean mass of the vertices that have
// triangles (1 in absolute units when no vertex has one).
constexpr double kIsolatedMassFraction = 1e-8;

// Mollification margin ε, as a fraction of the mean edge length of the triangles (the default of Sharp
// & Crane's robust-laplacians package; libigl's tufted_cover_laplacian uses 1e-6).
constexpr double kMollificationMargin = 1e-5;

// Builds K and M. positions: W × 3 doubles, row-major (positions[3 * w + c]); triangles: T × 3 indices
// into W (such as WeldedTopology::triangles; indices out of range are the caller's bug); a triangle with
// a repeated corner is no triangle and is ignored. Fails with bad_data when a position is not finite or
// so large that squared lengths overflow. O(T + W) time.
Status cotangent_laplacian(const std::vector<double>& positions, const std::vector<uint32_t>& triangles,
                           CotangentLaplacian& out);

// W × 3 doubles, row-major: the welded vertices' positions in one frame, read at each welded vertex's
// representative. frame: V × 3 floats in the primitive's own vertex order (FrameSequence::frame(f)).
std::vector<double> welded_positions(const float* frame, const WeldedTopology& topology);

}  // namespace segmorph
