// Piecewise-affine motion (Hachani et al., Eqs. 1 and 3), the encoder's side: fitting one affine transform per cluster
// and frame, and per vertex a few weights blending the transforms of nearby clusters. The types and the prediction
// (Eq. 2), which the decoder needs too, are prediction.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/prediction.h"

namespace segmorph {

// The welded trajectories the codec works on: W vertices over F frames (all clips end to end).
struct Trajectories {
  size_t vertex_count = 0;       // W
  size_t frame_count = 0;        // F
  std::vector<float> positions;  // F × W × 3, frame-major

  const float* frame(size_t f) const { return positions.data() + f * vertex_count * 3; }
};

// Eq. 1: per cluster and frame, the least-squares affine map from the base positions (W × 3) to the frame,
// regularized towards the cluster's rigid motion so that flat or tiny clusters stay well behaved. The frames are
// fitted on up to `threads` threads (0: every hardware thread), with the same result for any number.
AffineMotion fit_affine_motion(const float* base, const Trajectories& frames, const Clusters& clusters,
                               size_t threads = 1);

// fit_affine_motion of `clusters`, where `previous` is fit_affine_motion of `previous_clusters` (labels of the same
// vertices) with the same base and frames: a cluster with the vertices of a previous one takes its fit over (the
// same numbers), and only the others are fitted.
AffineMotion refit_affine_motion(const float* base, const Trajectories& frames, const Clusters& clusters,
                                 const Clusters& previous_clusters, const AffineMotion& previous, size_t threads = 1);

// E(Π) of the paper's Table 2: mean squared distance between each vertex and its cluster's affine image of
// its base position, over all vertices and frames, divided by the squared bounding-box diagonal of the base.
double motion_compensation_error(const float* base, const Trajectories& frames, const Clusters& clusters,
                                 const AffineMotion& motion);

// Eq. 3: per vertex, weights over a few clusters so that Σ_k w_k (AT_ik x) best predicts the vertex over all
// frames. Candidates for a vertex are its own cluster and the clusters met within `rings` edge rings of it, at most
// `max_clusters` of them (the own cluster and the ones whose transforms alone fit it best). The weights
// solve the least-squares problem of Eq. 3 under Σ w = 1, pulled slightly towards the own cluster so that
// nearly identical candidate motions do not produce wild weights. `adjacency` is CSR (W + 1 offsets, then
// neighbours). On up to `threads` threads (0: every core), the same weights for every count.
ClusterWeights fit_cluster_weights(const float* base, const Trajectories& frames, const Clusters& clusters,
                                   const AffineMotion& motion, const std::vector<uint32_t>& adjacency_offset,
                                   const std::vector<uint32_t>& adjacency, int rings, int max_clusters,
                                   size_t threads = 1);

// One-hot weights: every vertex follows its own cluster only (the prediction of Eq. 2 without blending).
ClusterWeights own_cluster_weights(const Clusters& clusters);

}  // namespace segmorph
