#include "common/prediction.h"

#include <algorithm>
#include <cstdint>

namespace segmorph {

std::vector<double> cluster_centroids(const float* base, const Clusters& clusters) {
  std::vector<double> centroid(clusters.count * 3, 0.0);
  std::vector<size_t> size(clusters.count, 0);
  for (size_t v = 0; v < clusters.label.size(); ++v) {
    const uint32_t k = clusters.label[v];
    for (int c = 0; c < 3; ++c) centroid[k * 3 + size_t(c)] += base[v * 3 + size_t(c)];
    ++size[k];
  }
  for (size_t k = 0; k < clusters.count; ++k)
    for (int c = 0; c < 3; ++c) centroid[k * 3 + size_t(c)] /= double(std::max<size_t>(size[k], 1));
  return centroid;
}

void predict_frame(const float* base, const AffineMotion& motion, const ClusterWeights& weights, size_t frame,
                   double* out) {
  FramePredictor(base, motion, weights).predict(frame, out);
}

FramePredictor::FramePredictor(const float* base, const AffineMotion& motion, const ClusterWeights& weights,
                               bool allow_avx)
    : motion_(motion), pair_offset_(weights.offset), cluster_(weights.cluster), avx_(false) {
#if defined(__x86_64__) || defined(__i386__)
  avx_ = allow_avx && __builtin_cpu_supports("avx");
#else
  (void)allow_avx;
#endif
  pairs_.reserve(weights.cluster.size());
  for (size_t v = 0; v + 1 < weights.offset.size(); ++v)
    for (uint32_t i = weights.offset[v]; i < weights.offset[v + 1]; ++i) {
      const double* c = &motion.centroid[weights.cluster[i] * 3];
      const double x = double(base[v * 3]) - c[0], y = double(base[v * 3 + 1]) - c[1],
                   z = double(base[v * 3 + 2]) - c[2], w = weights.weight[i];
      pairs_.push_back(Pair{Double2{x, x}, Double2{y, y}, Double2{z, z}, Double2{w, w}});
    }
}

#if defined(__x86_64__) || defined(__i386__)
// The same arithmetic as predict() with 4-lane vectors, compiled for AVX (without FMA, so nothing is fused): lane r
// computes row r, lane 3 a copy of row 0 that is dropped.
__attribute__((target("avx"))) void FramePredictor::predict_avx(size_t frame, double* out) const {
  typedef double Double4 __attribute__((vector_size(32), may_alias));
  const size_t vertex_count = pair_offset_.size() - 1, cluster_count = motion_.cluster_count;
  // Per cluster, column c of [L | t]: rows 0, 1, 2 and 0, at a 32-byte boundary (found in 4 doubles of slack).
  std::vector<double> storage(cluster_count * 16 + 4);
  double* aligned = reinterpret_cast<double*>((reinterpret_cast<uintptr_t>(storage.data()) + 31) & ~uintptr_t(31));
  for (size_t k = 0; k < cluster_count; ++k) {
    const double* t = motion_.transform(frame, k);
    for (size_t c = 0; c < 4; ++c) {
      double* column = aligned + k * 16 + c * 4;
      column[0] = t[c], column[1] = t[4 + c], column[2] = t[8 + c], column[3] = t[c];
    }
  }
  const Double4* columns = reinterpret_cast<const Double4*>(aligned);
  for (size_t v = 0; v < vertex_count; ++v) {
    Double4 sum = {0, 0, 0, 0};
    for (uint32_t i = pair_offset_[v]; i < pair_offset_[v + 1]; ++i) {
      const Double4* t = &columns[size_t(cluster_[i]) * 4];
      const Pair& d = pairs_[i];
      const Double4 x = {d.x[0], d.x[0], d.x[0], d.x[0]}, y = {d.y[0], d.y[0], d.y[0], d.y[0]},
                    z = {d.z[0], d.z[0], d.z[0], d.z[0]}, w = {d.weight[0], d.weight[0], d.weight[0], d.weight[0]};
      sum += w * (t[0] * x + t[1] * y + t[2] * z + t[3]);
    }
    out[v * 3] = sum[0], out[v * 3 + 1] = sum[1], out[v * 3 + 2] = sum[2];
  }
}

#endif

void FramePredictor::predict(size_t frame, double* out) const {
#if defined(__x86_64__) || defined(__i386__)
  if (avx_) return predict_avx(frame, out);
#endif
  // Term for term the expression of spec/bitstream.md section 8.5 (the order is fixed: the prediction is exact in
  // double), rows 0 and 1 in the two lanes of one vector and row 2 in another: each lane performs the same IEEE
  // operations in the same order as the scalar expression, so the result is identical, with about half the
  // instructions.
  const size_t vertex_count = pair_offset_.size() - 1, cluster_count = motion_.cluster_count;
  std::vector<Columns> columns(cluster_count);
  for (size_t k = 0; k < cluster_count; ++k) {
    const double* t = motion_.transform(frame, k);
    for (int c = 0; c < 4; ++c)
      columns[k].rows01[c] = Double2{t[c], t[4 + c]}, columns[k].row2[c] = Double2{t[8 + c], 0.0};
  }
  for (size_t v = 0; v < vertex_count; ++v) {
    Double2 sum01 = {0, 0}, sum2 = {0, 0};
    for (uint32_t i = pair_offset_[v]; i < pair_offset_[v + 1]; ++i) {
      const Columns& t = columns[cluster_[i]];
      const Pair& d = pairs_[i];
      sum01 += d.weight * (t.rows01[0] * d.x + t.rows01[1] * d.y + t.rows01[2] * d.z + t.rows01[3]);
      sum2 += d.weight * (t.row2[0] * d.x + t.row2[1] * d.y + t.row2[2] * d.z + t.row2[3]);
    }
    out[v * 3] = sum01[0], out[v * 3 + 1] = sum01[1], out[v * 3 + 2] = sum2[0];
  }
}

}  // namespace segmorph
