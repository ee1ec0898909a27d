// Principal curvatures of a triangle mesh by Taubin's method (G. Taubin, "Estimating the tensor of curvature
// of a surface from a polyhedral approximation", ICCV 1995).
#pragma once

#include <vector>

#include "common/topology.h"

namespace segmorph {

// Per welded vertex, the minimum principal curvature κ_min (1 / units of the positions; negative where the
// surface is concave across some direction, for outward normals). positions: W × 3 doubles, row-major.
// Taubin's estimate: M = Σ_j w_j κ_j T_j T_jᵀ over the 1-ring, κ_j = 2 nᵀ(v − v_j) / ‖v_j − v‖² the normal
// curvature towards neighbour j, T_j the unit projection of v_j − v on the tangent plane, w_j proportional to
// the area of the triangles on edge (v, v_j); the eigenvalues m1 ≥ m2 of M in the tangent plane give
// κ1 = 3 m1 − m2, κ2 = 3 m2 − m1. Sign: positive where the surface bends away from its normal (a convex
// bump; a unit sphere has κ = 1), negative across a concave crease. Vertices without triangles, and vertices on an open
// border (where half the ring is missing and the estimate means nothing), get 0.
std::vector<double> minimum_curvature(const std::vector<double>& positions, const WeldedTopology& topology);

}  // namespace segmorph
