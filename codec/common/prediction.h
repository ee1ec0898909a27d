// The prediction of Hachani et al.'s Eq. 2, shared by encoder and decoder: clusters, their affine transforms and
// the per-vertex weights that blend them (the types), and the predicted positions of a frame. No Eigen: the runtime
// decoder links this; the fitting of the transforms and weights is motion.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace segmorph {

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

// Per vertex, weights over a few clusters (Eq. 3). Sparse: offsets into (cluster, weight) pairs.
struct ClusterWeights {
  std::vector<uint32_t> offset;   // W + 1
  std::vector<uint32_t> cluster;  // cluster of each pair
  std::vector<double> weight;     // weight of each pair; a vertex's weights sum to 1
};

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
