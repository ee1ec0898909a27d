// Version 4's residuals (spec/bitstream.md, 5.9 and 8.7.1): each cluster's residuals over all frames as m temporal
// basis vectors and, per welded vertex and axis, m coefficients: the residual of frame f is the sum over i of
// coefficient i times entry f of vector i. The decoder's side (no Eigen): the coefficients from the stream's symbols,
// and the residuals of a frame from the coefficients; the encoder (transform_coding.h) uses the same functions, so
// that the error it measures is the decoder's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/reconstruction.h"
#include "common/stream.h"
#include "segmorph/status.h"

namespace segmorph {

// The coefficients' indices of every welded vertex: vertex w's m × 3 (m its cluster's basis size), axis by axis,
// vector by vector, at values[offset[w] ..]: coefficient i of axis a at values[offset[w] + a × m + i].
struct TransformCoefficients {
  std::vector<uint64_t> offset;  // W + 1
  std::vector<int32_t> values;
};

// The offsets alone (values sized, zero) for the content's labels and basis sizes.
TransformCoefficients transform_layout(const StreamContent& content);

// The coefficients from content.coefficient_symbols: in traversal order, each coefficient is its symbol plus the
// mean of the same coefficient of the vertex's earlier neighbours in its cluster (spec 8.7.1), rounded to the nearest
// integer, halves away from zero (0 without such a neighbour). Fails when a coefficient lies outside
// ±format::kMaxTransformValue.
Status transform_coefficients(const StreamContent& content, const ResidualTraversal& traversal,
                              TransformCoefficients& coefficients);

// The residuals of any frame, from the coefficients and the bases (the content must outlive it). It takes the
// coefficients over and keeps their offsets and their products with the steps (8 bytes each), not their indices.
class TransformResiduals {
 public:
  // Zero doubles after each basis vector's F values, so that a block of frames (transform_blocks.h) may load a
  // vector's values from any frame on, past its last.
  static constexpr size_t kRowPadding = 8;

  TransformResiduals(const StreamContent& content, TransformCoefficients coefficients);

  // Frame `frame`'s residuals, W × 3 doubles (vertex w, axis a at w × 3 + a): for each, r = 0.0, then for i = 0 ..
  // m − 1, r = r + (double(q_i) × double(D)) × b_i(f), b_i(f) = double(entry) × double(step) of the vector (both
  // products computed once, the same doubles). The reference, one frame at a time: the decoder's frame loop computes
  // the same doubles a block of frames at a time (transform_blocks.h).
  void frame(size_t frame, double* out) const;

  // What frame() reads. Vertex w's scaled coefficients are scaled()[offsets()[w] + a × m + i] (axis a, vector i).
  // The bases vector by vector, each vector's values frame after frame (the layout the blocks read): cluster k's
  // vector i in frame f is basis(k)[i × stride() + f] (the stream's basis, or its own; null without a basis), and
  // the stream's vector i is stream_basis()[i × stride() + f].
  const std::vector<uint64_t>& offsets() const { return offset_; }
  const std::vector<double>& scaled() const { return scaled_; }
  size_t stride() const { return stride_; }
  const double* stream_basis() const { return rows_.data(); }
  const double* basis(size_t cluster) const;

 private:
  const StreamContent& content_;
  std::vector<uint64_t> offset_;  // TransformCoefficients::offset
  size_t stride_;                 // F + kRowPadding
  // Every basis vector's values, a row of stride_ each: the stream's G vectors, then each own cluster's m.
  std::vector<double> rows_;
  std::vector<size_t> own_row_;  // K: the first row of a cluster's own basis
  std::vector<double> scaled_;   // double(q) × double(D) of every coefficient, laid out by offset_
};

}  // namespace segmorph
