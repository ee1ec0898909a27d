// Version 4's frames a block at a time (spec/bitstream.md 8.5 and 8.7.1): the prediction and the residual sum of up
// to kMaxFrames consecutive frames in one pass over the vertices, each vector lane a frame. Every lane performs the
// operations of the spec's expressions in their order (the prediction's, then r = r + (q D) × b_i(f) for i = 0 ..
// m − 1, then float(p + r)), so each frame's floats are those of FramePredictor::predict and
// TransformResiduals::frame, bit for bit; only the order in which elements are computed changes. The coefficients,
// which a rich stream holds more of than anything else, are read once per block instead of once per frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/prediction.h"
#include "common/stream.h"
#include "decode/transform_residuals.h"

namespace segmorph {

class TransformBlocks {
 public:
  static constexpr size_t kMaxFrames = 8;

  // Which vector instructions the blocks use: the best the processor has (x86-64: AVX-512F, else AVX, else SSE2;
  // elsewhere what the compiler makes of 8-lane vectors), or, for tests, a given one (lowered to what the processor
  // has: asking for AVX-512 on a processor without it gives AVX or SSE2).
  enum class Instructions { best, avx512, avx, baseline };

  // welded: W × 3 (the welded base); centroid: K × 3 (AffineMotion::centroid). The blocks dequantize the content's
  // motion themselves (dequantize_transform, the doubles of dequantized_motion) into their own layout and read the
  // bases and coefficients where residuals keeps them: residuals must outlive the blocks.
  TransformBlocks(const StreamContent& content, const TransformResiduals& residuals, const float* welded,
                  const std::vector<double>& centroid, const ClusterWeights& weights,
                  Instructions instructions = Instructions::best);

  // Welded frames `frame` .. `frame` + count − 1 (count 1 .. kMaxFrames, all < the stream's frame count) into out,
  // frame after frame (W × 3 floats each).
  void reconstruct(size_t frame, size_t count, float* out) const;

  // Cluster k's transform in frame f (row-major [L | t], as AffineMotion::transform): coefficient j is
  // transform(k, j)[f].
  const double* transform(size_t cluster, size_t j) const { return &motion_[(cluster * 12 + j) * stride_]; }

  Instructions instructions() const { return instructions_; }

  // What the kernels read (public for the kernel functions in the .cpp file).
  struct Pair {  // a vertex's cluster and weight (ClusterWeights), with the vertex's base position less the centroid
    double x, y, z, weight;
    const double* transform;  // the cluster's 12 transform rows (motion_)
  };
  struct Vertex {
    const double* basis;         // the first of its cluster's basis rows (TransformResiduals::basis)
    const double* coefficients;  // the vertex's m × 3 scaled coefficients (TransformResiduals::scaled)
    uint32_t m, pairs_end;       // the basis size; the end of its pairs in pairs_
  };
  struct Data {
    size_t stride;  // from one row to the next (motion's and the bases'): F + TransformResiduals::kRowPadding
    const Vertex* vertices;
    size_t vertex_count;
    const Pair* pairs;
  };

 private:
  // The motion vector-major, so that a block's frames are side by side: each cluster's 12 transform coefficients
  // (row-major [L | t]), a row each, frame after frame, every row `stride_` long (the bases' rows are as long).
  std::vector<double> motion_;
  size_t stride_;
  std::vector<Vertex> vertices_;
  std::vector<Pair> pairs_;
  Instructions instructions_;
};

}  // namespace segmorph
