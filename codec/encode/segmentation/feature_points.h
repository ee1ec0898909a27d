// The feature points of Hachani et al. (§2.2): the tips of a shape where the Morse function's level sets start. From
// the two most distant points v1, v2 of a component, the functions f1, f2 (integrated diffusion distance to v1, v2,
// diffusion.cpp) have their maxima at the tips; the tips found by both (Tierny et al.'s extrema, within a geodesic
// neighbourhood) are the feature points.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "common/topology.h"

namespace segmorph {

// The two most distant points of a component (its welded vertices), geodesically: a double sweep of Dijkstra from
// its first vertex. positions: W × 3.
std::array<uint32_t, 2> farthest_points(const std::vector<double>& positions, const VertexAdjacency& adjacency,
                                        const std::vector<uint32_t>& vertices);

// Vertices of the component whose f is the largest within geodesic distance `radius` (ties to the lowest index).
std::vector<uint32_t> maxima(const std::vector<double>& f, const std::vector<uint32_t>& vertices,
                             const std::vector<double>& positions, const VertexAdjacency& adjacency, double radius);

// The maxima of f1 that have a maximum of f2 within `radius` of them; the farthest points when there are none.
std::vector<uint32_t> feature_points(const std::vector<double>& f1, const std::vector<double>& f2,
                                     const std::vector<uint32_t>& vertices, const std::vector<double>& positions,
                                     const VertexAdjacency& adjacency, double radius,
                                     const std::array<uint32_t, 2>& farthest);

}  // namespace segmorph
