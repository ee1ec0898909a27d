// Piecewise-affine motion (Hachani et al., Eqs. 1–3): one affine transform per cluster and frame, and per
// vertex a few weights blending the transforms of nearby clusters.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace segmorph {

// The welded trajectories the codec works on: W vertices over F frames (all clips end to end).
struct Trajectories {
  size_t vertex_count = 0;       // W
  size_t frame_count = 0;        // F
  std::vector<float> positions;  // F × W × 3, frame-major

  const float* frame(size_t f) const { return positions.data() + f * vertex_count * 3; }
};

// A partition of the welded vertices into K clusters (the key vector π).
struct Clusters {
  size_t count = 0;             // K
  std::vector<uint32_t> label;  // W: cluster of each vertex, < K
};

// Affine transforms in centred form: frame i maps a base position x of cluster k to
//   y = L_ik (x − c_k) + t_ik,
// c_k the centroid of cluster k in the base frame, L_ik 3 × 3, t_ik the translation (the centroid's image).
// Centring keeps the 12 coefficients well conditioned and makes t a position, which predicts well in time.
struct AffineMotion {
  size_t cluster_count = 0;      // K
  size_t frame_count = 0;        // F
  std::vector<double> centroid;  // K × 3
  // F × K × 12: row-major 3 × 4 [L | t] per frame and cluster.
  std::vector<double> transforms;

  const double* transform(size_t frame, size_t cluster) const {
    return transforms.data() + (frame * cluster_count + cluster) * 12;
  }
  double* transform(size_t frame, size_t cluster) { return transforms.data() + (frame * cluster_count + cluster) * 12; }
};

// Centroids of the clusters in `base` (W × 3), in double, summed in vertex order.
std::vector<double> cluster_centroids(const float* base, const Clusters& clusters);

// Eq. 1: per cluster and frame, the least-squares affine map from the base positions (W × 3) to the frame,
// regularized towards the cluster's rigid motion so that flat or tiny clusters stay well behaved.
AffineMotion fit_affine_motion(const float* base, const Trajectories& frames, const Clusters& clusters);

// E(Π) of the paper's Table 2: mean squared distance between each vertex and its cluster's affine image of
// its base position, over all vertices and frames, divided by the squared bounding-box diagonal of the base.
double motion_compensation_error(const float* base, const Trajectories& frames, const Clusters& clusters,
                                 const AffineMotion& motion);

// Eq. 3: per vertex, weights over a few clusters so that Σ_k w_k (AT_ik x) best predicts the vertex over
// all frames. Sparse: offsets into (cluster, weight) pairs.
struct ClusterWeights {
  std::vector<uint32_t> offset;   // W + 1
  std::vector<uint32_t> cluster;  // cluster of each pair
  std::vector<double> weight;     // weight of each pair; a vertex's weights sum to 1
};

// Candidates for a vertex are its own cluster and the clusters met within `rings` edge rings of it, at most
// `max_clusters` of them (the own cluster and the ones whose transforms alone fit it best). The weights
// solve the least-squares problem of Eq. 3 under Σ w = 1, pulled slightly towards the own cluster so that
// nearly identical candidate motions do not produce wild weights. `adjacency` is CSR (W + 1 offsets, then
// neighbours).
ClusterWeights fit_cluster_weights(const float* base, const Trajectories& frames, const Clusters& clusters,
                                   const AffineMotion& motion, const std::vector<uint32_t>& adjacency_offset,
                                   const std::vector<uint32_t>& adjacency, int rings, int max_clusters);

// One-hot weights: every vertex follows its own cluster only (the prediction of Eq. 2 without blending).
ClusterWeights own_cluster_weights(const Clusters& clusters);

// Eq. 2: predicted positions (W × 3, double) of frame `frame`.
void predict_frame(const float* base, const AffineMotion& motion, const ClusterWeights& weights, size_t frame,
                   double* out);

// predict_frame for frame after frame of one base, motion and weights (the motion must outlive it), with what does
// not depend on the frame (each pair's x − c_k) computed once. The doubles of spec/bitstream.md section 8.5, bit for
// bit, on every path: two-lane vectors (SSE2 on x86-64, or what GCC's and Clang's vector extension makes of them elsewhere),
// or, on x86 processors that have it and unless `allow_avx` is false (for tests), four-lane AVX vectors.
class FramePredictor {
 public:
  FramePredictor(const float* base, const AffineMotion& motion, const ClusterWeights& weights, bool allow_avx = true);
  void predict(size_t frame, double* out) const;

 private:
  // Two doubles operated on together (SSE2 on x86-64; GCC's and Clang's vector extension).
  typedef double Double2 __attribute__((vector_size(16)));
  struct Pair {
    Double2 x, y, z, weight;  // x − c_k by coordinate and the pair's weight, each in both lanes
  };
  struct Columns {
    Double2 rows01[4], row2[4];  // column c of [L | t]: rows 0 and 1, then row 2 and 0
  };

#if defined(__x86_64__) || defined(__i386__)
  // With AVX (checked at run time): rows 0, 1 and 2 in three lanes of one 4-lane vector, the same way.
  void predict_avx(size_t frame, double* out) const;
#endif

  const AffineMotion& motion_;
  std::vector<uint32_t> pair_offset_;  // W + 1 (ClusterWeights::offset)
  std::vector<Pair> pairs_;            // per (vertex, cluster) pair
  std::vector<uint32_t> cluster_;      // the pair's cluster
  bool avx_;
};

}  // namespace segmorph
