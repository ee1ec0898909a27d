// Boundary refinement of a segmentation.
//
// The paper's refinement (Hachani et al., Eq. 6) moves each band boundary, a level set of μ, to the level
// where it runs through the most concave surface: part boundaries of shapes lie along concave creases (the
// "minima rule"), and so do the joints where one rigid part turns against another. For each level, a window
// of candidate levels is tried; the boundary curve of a candidate is the set of vertices where μ crosses it,
// its profile is the Taubin minimum curvature along the curve smoothed by a few averaging passes (the
// Gaussian G_σ), and its score is the profile's minimum. Levels move until none does (or max_iterations).
//
// Beyond the paper, refine_by_motion moves boundary vertices to the neighbouring cluster whose affine motion
// predicts them best over all frames, which lowers E(Π) directly.
#pragma once

#include <vector>

#include "motion.h"
#include "segmentation.h"
#include "topology.h"

namespace segmorph {

struct RefinementSettings {
  int max_iterations = 25;
  double window = 0.5;  // a level may move up to this share of the way to its neighbouring levels
  int candidates = 9;   // candidate levels per window, the current one included
  int smoothing = 3;    // averaging passes of κ_min along the boundary
};

// Eq. 6: refined band levels. curvature: W minimum curvatures (curvature.h). `iterations` receives the number
// of passes made over all levels.
MorseBands refine_levels(const std::vector<double>& mu, const std::vector<double>& curvature,
                         const WeldedTopology& topology, const VertexAdjacency& adjacency, const MorseBands& bands,
                         const RefinementSettings& settings, int* iterations = nullptr);

// Motion-driven refinement: at most `max_iterations` rounds of moving each boundary vertex to the adjacent
// cluster whose transforms predict it best (refitting the transforms after each round).
// The vertices are weighed on up to `threads` threads (0: every hardware thread), with the same result for any number.
Clusters refine_by_motion(const Clusters& clusters, const float* base, const Trajectories& frames,
                          const VertexAdjacency& adjacency, int max_iterations, int* iterations = nullptr,
                          size_t threads = 1);

}  // namespace segmorph
