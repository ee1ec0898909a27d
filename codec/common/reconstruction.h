// How a decoder turns stream content into frames. The encoder runs the same functions on its own quantized
// values (closed loop), so its reconstruction is the decoder's, bit for bit: every sum below is evaluated in
// IEEE binary64 in the order written (no contraction; see codec/CMakeLists.txt).
#pragma once

#include <vector>

#include "common/frame_sequence.h"
#include "common/prediction.h"
#include "common/stream.h"

namespace segmorph {

// Welded base positions: base (V × 3) read at the first vertex of each welded vertex.
std::vector<float> welded_base(const std::vector<float>& base, const StreamContent& content);

// The affine motion the stream describes (centroids from the welded base and the labels).
AffineMotion dequantized_motion(const StreamContent& content, const std::vector<float>& welded);

// The same without its transforms (left empty), for a caller that keeps them in its own layout (version 4's frame
// blocks, transform_blocks.h), each made by dequantize_transform.
AffineMotion dequantized_centroids(const StreamContent& content, const std::vector<float>& welded);

// One frame and cluster's transform, row-major [L | t], from its 12 motion integers q (content.motion), the
// cluster's centroid c and the content's two steps: L = I + q × linear, t = c + q × translation (spec 8.3).
inline void dequantize_transform(const int32_t* q, const double* c, double linear, double translation,
                                 double* transform) {
  for (int r = 0; r < 3; ++r) {
    for (int j = 0; j < 3; ++j) transform[r * 4 + j] = (r == j ? 1.0 : 0.0) + double(q[r * 3 + j]) * linear;
    transform[r * 4 + 3] = c[r] + double(q[9 + r]) * translation;
  }
}

// The cluster weights the stream describes.
ClusterWeights dequantized_weights(const StreamContent& content);

// Predicted positions of every frame: F × W × 3 doubles.
std::vector<double> predicted_frames(const StreamContent& content, const std::vector<float>& welded);

// The order in which a frame's welded vertices are reconstructed, and for each vertex its neighbours that come
// before it in that order (the ones a spatial prediction may use). The order is breadth-first from the
// lowest-numbered vertex of each connected piece, neighbours in ascending index; the mesh is the base mesh's
// triangles (V indices) through the welding, triangles with two equal welded corners left out. Everything is
// indexed by position in the order, so that a loop in that order walks its arrays front to back.
struct ResidualTraversal {
  std::vector<uint32_t> order;           // W: the welded vertex at each position
  std::vector<uint32_t> position;        // W: the position of each welded vertex
  std::vector<uint32_t> earlier_offset;  // W + 1, by position
  std::vector<uint32_t> earlier;         // positions of the earlier neighbours, by ascending welded index
};
ResidualTraversal residual_traversal(const StreamContent& content, const std::vector<uint32_t>& triangles);

// Quantizer index of a residual (an encoder's choice; the decoder only reads indices): the nearest integer to
// residual × (1 / step), halves away from zero (llround's rule, inlined: this runs for every coordinate of every
// frame at every candidate step of the rate control). The encoder's residual loop and its rate control both
// use it, so that the distortion the rate control measures is the one the stream has.
inline int64_t quantizer_index(double residual_times_inverse_step) {
  const double x = residual_times_inverse_step;
  return int64_t(x + (x >= 0 ? 0.5 : -0.5));
}

// The residual loop shared by encoder and decoder, one frame at a time. For each welded vertex in traversal
// order and each axis, with p the prediction and r the predicted residual: the reconstructed residual of the same
// vertex and axis in the frame's reference when temporal residuals are on (frame_reference(): the previous frame of
// the clip, or with version 3's frame references the frame d back; 0.0 when the frame has none, and always when
// temporal residuals are off), plus, when spatial residuals are on and the vertex has n > 0 earlier neighbours,
// their mean: (Σ_j c_j) × (1 / n), the sum in the order of `earlier`, c_j the neighbour's reconstructed residual in
// this frame minus (temporal) its reference's:
//   lossy:    x = float(p + (r + k · step[axis]))          and the new r is r + k · step[axis]
//   lossless: x = from_ordered_bits(ordered_bits(float(p + r)) + k)   and the new r is x − p
class ResidualReconstructor {
 public:
  // content: its flags, residual steps and frame references; both arguments must outlive the reconstructor.
  ResidualReconstructor(const StreamContent& content, const ResidualTraversal& traversal);

  // Starts a clip: no frame of it is reconstructed yet.
  void start_clip();

  // Reconstructs the next frame of the clip, which is stream frame `frame` (its reference is the content's).
  // predictions: W × 3 (vertex v, axis a at v · 3 + a).
  // `symbol(i, p, r)` returns k for coordinate i = v · 3 + a (the encoder computes it from its target, the
  // decoder reads it); `output(i, x)` receives the reconstructed coordinate.
  template <typename Symbol, typename Output>
  void frame(size_t frame, const double* predictions, Symbol symbol, Output output);

  // The next two frames of the clip, stream frames `frame` and frame + 1: the same as frame(frame, a…) then
  // frame(frame + 1, b…), the symbols requested and the outputs given in another interleaving (each frame's own
  // order is kept), and about twice as fast: the two frames' chains of dependent operations overlap.
  template <typename SymbolA, typename OutputA, typename SymbolB, typename OutputB>
  void two_frames(size_t frame, const double* predictions_a, SymbolA symbol_a, OutputA output_a,
                  const double* predictions_b, SymbolB symbol_b, OutputB output_b);

 private:
  template <typename F>
  void with_flags(F f) const;
  template <bool kLossless, bool kTemporal, bool kSpatial, typename Symbol, typename Output>
  void vertex(size_t position, const double* predictions, Symbol& symbol, Output& output, const double* reference,
              double* current, double* change) const;
  // The residuals of frame `in_clip` of the clip (allocated when first written).
  double* slot(size_t in_clip);
  // The reference residuals of stream frame `frame`, frame `in_clip` of the clip: its reference's, or zeros.
  const double* reference(size_t frame, size_t in_clip) const;

  const StreamContent& content_;
  const ResidualTraversal& traversal_;
  bool lossless_, temporal_, spatial_;
  double steps_[3];
  // By position in the traversal (W × 3). history_: the reconstructed residuals of the last reference_window + 2
  // frames of the clip, frame j in history_[j % size] (the window, the frame being reconstructed and two_frames'
  // second). change_: what a later neighbour's spatial prediction reads of a reconstructed residual (c_j above),
  // computed once per vertex; second_change_: two_frames' second frame's.
  std::vector<std::vector<double>> history_;
  std::vector<double> zeros_, change_, second_change_;
  std::vector<double> inverse_count_;  // by position: 1 / n, n its number of earlier neighbours (0 when none)
  size_t frame_in_clip_ = 0;
};

}  // namespace segmorph

#include "common/reconstruction_inl.h"
