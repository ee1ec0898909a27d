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

  // welded: W × 3 (the welded base); content, residuals, motion and weights must outlive the blocks.
  TransformBlocks(const StreamContent& content, const TransformResiduals& residuals, const float* welded,
                  const AffineMotion& motion, const ClusterWeights& weights,
                  Instructions instructions = Instructions::best);

  // Welded frames `frame` .. `frame` + count − 1 (count 1 .. kMaxFrames, all < the stream's frame count) into out,
  // frame after frame (W × 3 floats each).
  void reconstruct(size_t frame, size_t count, float* out) const;

  Instructions instructions() const { return instructions_; }

  // What the kernels read (public for the kernel functions in the .cpp file).
  struct Pair {  // a vertex's cluster and weight (ClusterWeights), with the vertex's base position less the centroid
    double x, y, z, weight;
    size_t transform;  // where the cluster's transforms start in lanes
  };
  struct Vertex {
    size_t basis;        // where the cluster's basis starts in lanes
    const double* coefficients;  // the vertex's m × 3 scaled coefficients (TransformResiduals::scaled)
    uint32_t m, pairs_end;       // the basis size; the end of its pairs in pairs_
  };
  struct Data {
    const double* lanes;
    size_t stride;  // from one row of lanes to the next: the frame count plus kMaxFrames of zeros
    const Vertex* vertices;
    size_t vertex_count;
    const Pair* pairs;
  };

 private:
  // The per-frame values, vector-major so that a block's frames are side by side: each basis vector's values
  // (double(entry) × double(step), as TransformResiduals has them), each cluster's 12 transform coefficients (row-major
  // [L | t]) frame by frame, every row `stride` long.
  std::vector<double> lanes_;
  size_t stride_;
  std::vector<Vertex> vertices_;
  std::vector<Pair> pairs_;
  Instructions instructions_;
};

}  // namespace segmorph
