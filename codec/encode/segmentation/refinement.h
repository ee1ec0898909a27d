// Boundary refinement of a segmentation.
//
// The paper's refinement (Hachani et al., Eq. 6) moves each band boundary, a level set of μ, to the level
// where it runs through the most concave surface: part boundaries of shapes lie along concave creases (the
// "minima rule"), and so do the joints where one rigid part turns against another. For each level, a window
// of candidate levels is tried, each scored by the concavity of its boundary; levels move until none does (or
// max_iterations). Two scores (docs/codec.md measures both):
// - level_curves, Eq. 6 as the paper states it: the boundary is the level set of μ on the mesh, ordered curves
//   through the points where μ crosses the level on the edges, each parameterized by its normalized arc length t;
//   E_concave is the least value along the curves of the Taubin minimum curvature (interpolated along the edges)
//   convolved with a Gaussian G_σ in t.
// - boundary_vertices (the default, whose clusters cost fewer bytes on the sequences measured): the boundary is the
//   unordered set of vertices at or above the level next to one below it, κ_min averaged a few times over the
//   boundary's own neighbours in place of G_σ; the score is its least value.
//
// Beyond the paper, refine_by_motion moves boundary vertices to the neighbouring cluster whose affine motion
// predicts them best over all frames, which lowers E(Π) directly.
#pragma once

#include <vector>

#include "common/topology.h"
#include "encode/motion.h"
#include "encode/segmentation/segmentation.h"

namespace segmorph {

enum class ConcavityProfile { boundary_vertices, level_curves };

struct RefinementSettings {
  ConcavityProfile profile = ConcavityProfile::boundary_vertices;
  int max_iterations = 25;
  double window = 0.5;  // a level may move up to this share of the way to its neighbouring levels
  int candidates = 9;   // candidate levels per window, the current one included
  int smoothing = 3;    // boundary_vertices: averaging passes of κ_min along the boundary
  double sigma = 0.03;  // level_curves: G_σ's width, a share of each curve's length
  int samples = 128;    // level_curves: κ_min sampled at this many points of equal arc length per curve
};

// Eq. 6: refined band levels. positions: W × 3 welded positions; mu: W values of the Morse function; curvature: W
// minimum curvatures (curvature.h). `iterations` receives the number of passes made over all levels.
MorseBands refine_levels(const std::vector<double>& positions, const std::vector<double>& mu,
                         const std::vector<double>& curvature, const WeldedTopology& topology,
                         const VertexAdjacency& adjacency, const MorseBands& bands, const RefinementSettings& settings,
                         int* iterations = nullptr);

// Motion-driven refinement: at most `max_iterations` rounds of moving each boundary vertex to the adjacent
// cluster whose transforms predict it best (refitting the transforms after each round).
// The vertices are weighed on up to `threads` threads (0: every hardware thread), with the same result for any number.
// `motion`, if any, receives fit_affine_motion of the clusters returned: the last round's fit when that round moved
// nothing, else a fit of its own.
Clusters refine_by_motion(const Clusters& clusters, const float* base, const Trajectories& frames,
                          const VertexAdjacency& adjacency, int max_iterations, int* iterations = nullptr,
                          size_t threads = 1, AffineMotion* motion = nullptr);

}  // namespace segmorph
