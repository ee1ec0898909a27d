// How a decoder turns stream content into frames. The encoder runs the same functions on its own quantized
// values (closed loop), so its reconstruction is the decoder's, bit for bit: every sum below is evaluated in
// IEEE binary64 in the order written (no contraction; see codec/CMakeLists.txt).
#pragma once

#include <vector>

#include "motion.h"
#include "stream.h"

namespace segmorph {

// Welded base positions: base (V × 3) read at the first vertex of each welded vertex.
std::vector<float> welded_base(const std::vector<float>& base, const StreamContent& content);

// The affine motion the stream describes (centroids from the welded base and the labels).
AffineMotion dequantized_motion(const StreamContent& content, const std::vector<float>& welded);

// The cluster weights the stream describes.
ClusterWeights dequantized_weights(const StreamContent& content);

// Predicted positions of every frame: F × W × 3 doubles.
std::vector<double> predicted_frames(const StreamContent& content, const std::vector<float>& welded);

// The order in which a frame's welded vertices are reconstructed, and for each vertex its neighbours that come
// before it in that order (the ones a spatial prediction may use). The order is breadth-first from the
// lowest-numbered vertex of each connected piece, neighbours in ascending index; the mesh is the base mesh's
// triangles (V indices) through the welding, triangles with two equal welded corners left out.
struct ResidualTraversal {
  std::vector<uint32_t> order;            // W
  std::vector<uint32_t> earlier_offset;   // W + 1, indexed by welded vertex
  std::vector<uint32_t> earlier;          // neighbours earlier in the order
};
ResidualTraversal residual_traversal(const StreamContent& content, const std::vector<uint32_t>& triangles);

// Quantizer index of a residual: the nearest integer, halves away from zero (llround's rule, inlined: this runs
// for every coordinate of every frame at every candidate step of the rate control).
inline int64_t quantizer_index(double residual_over_step) {
  return int64_t(residual_over_step + (residual_over_step >= 0 ? 0.5 : -0.5));
}

// The predicted residual of vertex v, coordinate `axis`, from the reconstructed residuals of the current frame
// so far and of the previous frame (arrays of W × stride values; coordinate a of vertex u at u · stride + a).
inline double predicted_residual(const ResidualTraversal& traversal, uint32_t v, size_t axis, size_t stride,
                                 const double* current, const double* previous, bool temporal, bool spatial) {
  double r = temporal ? previous[v * stride + axis] : 0.0;
  const uint32_t begin = traversal.earlier_offset[v], end = traversal.earlier_offset[v + 1];
  if (spatial && end > begin) {
    double sum = 0;
    for (uint32_t j = begin; j < end; ++j) {
      const size_t u = size_t(traversal.earlier[j]) * stride + axis;
      sum += temporal ? current[u] - previous[u] : current[u];
    }
    r += sum / double(end - begin);
  }
  return r;
}

// The residual loop shared by encoder and decoder. For each clip, frame, welded vertex and axis in that
// order (vertices in traversal order), with p the prediction and r the predicted residual: the previous
// frame's reconstructed residual of the same vertex and axis when temporal residuals are on (0 at a clip's
// first frame), plus, when spatial residuals are on, the mean over the vertex's earlier neighbours of their
// reconstructed residual in this frame minus (temporal) their previous one:
//   lossy:    x = float(p + (r + k · step[axis]))          and the new r is r + k · step[axis]
//   lossless: x = from_ordered_bits(ordered_bits(float(p + r)) + k)   and the new r is x − p
// `symbol(index, p, r)` returns k for the symbol at `index` (the encoder computes it from its target, the
// decoder reads it); `output(index, x)` receives each reconstructed coordinate.
template <typename Symbol, typename Output>
void residual_loop(const StreamContent& content, const ResidualTraversal& traversal,
                   const std::vector<double>& predictions, Symbol symbol, Output output);

// Frames (welded, F × W × 3 floats) of a complete content.
std::vector<float> reconstruct_welded(const StreamContent& content, const ResidualTraversal& traversal,
                                      const std::vector<double>& predictions);

}  // namespace segmorph

#include "reconstruction_inl.h"
