// Normals that follow a deforming surface.
//
// segmorph stores positions only; normals of each frame are derived from the rest normals and the
// motion of the surface: each vertex's rest normal is turned by the smallest rotation that takes the
// surface's geometric normal at rest to its geometric normal in the frame. Authored normals (hard
// edges, custom shading normals) are kept at rest and follow the surface as it bends. Baking and
// decoding both use this one rule, so a decoded file shades like the baked reference.
#pragma once

#include <cstddef>
#include <vector>

#include "common/topology.h"

namespace segmorph {

// Area-weighted geometric normals of the welded vertices (W × 3, not normalized; zero where no
// triangle touches the vertex). positions: V × 3 original-order positions.
std::vector<double> welded_vertex_normals(const float* positions, const WeldedTopology& topology);

// Rest normals (V × 3, unit) carried from the rest positions to the frame positions (both V × 3).
// out: V × 3 unit normals. A vertex whose geometric normal vanishes keeps its rest normal.
void deform_normals(const float* rest_positions, const float* rest_normals, const float* frame_positions,
                    const WeldedTopology& topology, float* out);

// The same, reusing the rest geometric normals (from welded_vertex_normals) across many frames.
void deform_normals(const std::vector<double>& rest_geometric, const float* rest_normals, const float* frame_positions,
                    const WeldedTopology& topology, float* out);

}  // namespace segmorph
