#include "decode/transform_blocks.h"

#include <cassert>
#include <cstring>

#include "common/reconstruction.h"

namespace segmorph {
namespace {

// kMaxFrames doubles, one frame each, and their floats (GCC's and Clang's vector extension: one AVX-512 register,
// two AVX or four SSE2 ones, whatever the function is compiled for).
typedef double Lanes __attribute__((vector_size(64)));
typedef float FloatLanes __attribute__((vector_size(32)));
static_assert(sizeof(Lanes) == TransformBlocks::kMaxFrames * sizeof(double), "a lane per frame");
// The lanes of a row of TransformBlocks' values from a frame on, at any double's alignment: a memcpy, which GCC and
// Clang make one unaligned load (Clang ignores a smaller alignment on a vector typedef and loads aligned: a fault).
// Vectors by reference, never returned: a 64-byte vector's return would depend on the instruction set.
__attribute__((always_inline)) inline void load(Lanes& to, const double* from) { std::memcpy(&to, from, sizeof(to)); }

// sum = sum + weight × (t0 × x + t1 × y + t2 × z + t3), t0 .. t3 the rows at t, t + stride, ...: one row of 8.5's
// prediction for one (cluster, weight) pair, in the spec's order.
__attribute__((always_inline)) inline void add_row(Lanes& sum, const double* t, size_t stride, double x, double y,
                                                   double z, double weight) {
  Lanes t0, t1, t2, t3;
  load(t0, t), load(t1, t + stride), load(t2, t + 2 * stride), load(t3, t + 3 * stride);
  sum = sum + weight * (t0 * x + t1 * y + t2 * z + t3);
}

// The block's frames of every vertex: its prediction (spec 8.5: for each of its clusters, weight × (row · (x − c, 1)),
// summed in the clusters' order), its residuals (8.7.1), their sum as floats, each lane stored into its frame.
// Inlined into one function per instruction set below, which the compiler vectorizes for that set.
__attribute__((always_inline)) inline void reconstruct_block(const TransformBlocks::Data& d, size_t frame,
                                                             size_t count, float* out) {
  const size_t stride = d.stride, row = d.vertex_count * 3;
  const TransformBlocks::Pair* pair = d.pairs;
  for (size_t w = 0; w < d.vertex_count; ++w) {
    const TransformBlocks::Vertex& vertex = d.vertices[w];
    Lanes px = {}, py = {}, pz = {};
    for (const TransformBlocks::Pair* end = d.pairs + vertex.pairs_end; pair < end; ++pair) {
      const double* t = pair->transform + frame;
      add_row(px, t, stride, pair->x, pair->y, pair->z, pair->weight);
      add_row(py, t + 4 * stride, stride, pair->x, pair->y, pair->z, pair->weight);
      add_row(pz, t + 8 * stride, stride, pair->x, pair->y, pair->z, pair->weight);
    }
    Lanes rx = {}, ry = {}, rz = {};
    const double* c = vertex.coefficients;
    for (uint32_t i = 0, m = vertex.m; i < m; ++i) {  // (no basis, no pointer: m is 0)
      Lanes b;
      load(b, vertex.basis + (i * stride + frame));
      rx = rx + c[i] * b;
      ry = ry + c[m + i] * b;
      rz = rz + c[2 * m + i] * b;
    }
    const FloatLanes x = __builtin_convertvector(px + rx, FloatLanes), y = __builtin_convertvector(py + ry, FloatLanes),
                     z = __builtin_convertvector(pz + rz, FloatLanes);
    float* to = out + w * 3;
    if (count == TransformBlocks::kMaxFrames) {
      for (size_t f = 0; f < TransformBlocks::kMaxFrames; ++f)
        to[f * row] = x[f], to[f * row + 1] = y[f], to[f * row + 2] = z[f];
    } else {
      for (size_t f = 0; f < count; ++f) to[f * row] = x[f], to[f * row + 1] = y[f], to[f * row + 2] = z[f];
    }
  }
}

void reconstruct_baseline(const TransformBlocks::Data& d, size_t frame, size_t count, float* out) {
  reconstruct_block(d, frame, count, out);
}

#if defined(__x86_64__) || defined(__i386__)
// No FMA in either (nor does -ffp-contract=off let the compiler fuse): every product and sum rounds as written.
__attribute__((target("avx"))) void reconstruct_avx(const TransformBlocks::Data& d, size_t frame, size_t count,
                                                     float* out) {
  reconstruct_block(d, frame, count, out);
}

__attribute__((target("avx512f"))) void reconstruct_avx512(const TransformBlocks::Data& d, size_t frame,
                                                           size_t count, float* out) {
  reconstruct_block(d, frame, count, out);
}
#endif

TransformBlocks::Instructions available(TransformBlocks::Instructions wanted) {
  using Instructions = TransformBlocks::Instructions;
#if defined(__x86_64__) || defined(__i386__)
  const bool avx512 = __builtin_cpu_supports("avx512f"), avx = __builtin_cpu_supports("avx");
  if ((wanted == Instructions::best || wanted == Instructions::avx512) && avx512) return Instructions::avx512;
  if (wanted != Instructions::baseline && avx) return Instructions::avx;
#else
  (void)wanted;
#endif
  return Instructions::baseline;
}

}  // namespace

TransformBlocks::TransformBlocks(const StreamContent& content, const TransformResiduals& residuals,
                                 const float* welded, const std::vector<double>& centroid,
                                 const ClusterWeights& weights, Instructions instructions)
    : stride_(residuals.stride()), instructions_(available(instructions)) {
  static_assert(TransformResiduals::kRowPadding >= kMaxFrames - 1, "a block reads up to kMaxFrames − 1 past a row");
  const size_t frames = content.frame_count(), clusters = content.cluster_count;
  assert(stride_ == frames + TransformResiduals::kRowPadding && centroid.size() == clusters * 3);
  motion_.assign(clusters * 12 * stride_, 0.0);
  const double linear = content.linear_step, translation = content.translation_step;
  for (size_t f = 0; f < frames; ++f)
    for (size_t k = 0; k < clusters; ++k) {
      double transform[12];
      dequantize_transform(&content.motion[(f * clusters + k) * 12], &centroid[k * 3], linear, translation, transform);
      for (size_t j = 0; j < 12; ++j) motion_[(k * 12 + j) * stride_ + f] = transform[j];
    }

  const size_t vertex_count = content.welded_count;
  assert(weights.offset.size() == vertex_count + 1);
  vertices_.resize(vertex_count);
  pairs_.reserve(weights.cluster.size());
  for (size_t w = 0; w < vertex_count; ++w) {
    const uint32_t k = content.labels[w];
    for (uint32_t i = weights.offset[w]; i < weights.offset[w + 1]; ++i) {
      const uint32_t cluster = weights.cluster[i];
      const double* c = &centroid[size_t(cluster) * 3];
      pairs_.push_back(Pair{double(welded[w * 3]) - c[0], double(welded[w * 3 + 1]) - c[1],
                            double(welded[w * 3 + 2]) - c[2], weights.weight[i], transform(cluster, 0)});
    }
    vertices_[w] = Vertex{residuals.basis(k), residuals.scaled().data() + residuals.offsets()[w],
                          content.basis_size[k], uint32_t(pairs_.size())};
  }
}

void TransformBlocks::reconstruct(size_t frame, size_t count, float* out) const {
  assert(count >= 1 && count <= kMaxFrames);
  const Data data{stride_, vertices_.data(), vertices_.size(), pairs_.data()};
#if defined(__x86_64__) || defined(__i386__)
  if (instructions_ == Instructions::avx512) return reconstruct_avx512(data, frame, count, out);
  if (instructions_ == Instructions::avx) return reconstruct_avx(data, frame, count, out);
#endif
  reconstruct_baseline(data, frame, count, out);
}

}  // namespace segmorph
