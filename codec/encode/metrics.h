// Distortion and rate measures of a decoded animation against its original.
//
// KG error (Karni & Gotsman 2004): 100 · ‖A − Ã‖_F / ‖A − E(A)‖_F, A the 3V × F matrix of all frames,
// E(A) each frame's centroid repeated over its vertices. RMSE: per frame, the root mean square vertex
// distance; averaged over frames and divided by the first frame's bounding-box diagonal. Several clips of
// one primitive count as one sequence: their frames are pooled.
#pragma once

#include <cstddef>
#include <vector>

#include "common/frame_sequence.h"
#include "segmorph/encoding.h"  // bits_per_vertex_frame over V × F summed

namespace segmorph {

// The axis-aligned bounding box of V × 3 positions (V ≥ 1).
void bounding_box(const float* positions, size_t vertex_count, float low[3], float high[3]);

// Length of the diagonal of the axis-aligned bounding box of V × 3 positions (0 when V = 0).
double bounding_box_diagonal(const float* positions, size_t vertex_count);
// Its square, computed without the square root (E(Π) divides by it).
double bounding_box_diagonal_squared(const float* positions, size_t vertex_count);

// Adds one frame's ‖A − E(A)‖² (V × 3 positions: the squared distances from its centroid, in double, vertex by vertex
// and axis by axis) to `spread`: the KG error's denominator, summed over frames.
void add_frame_spread(const float* frame, size_t vertex_count, double& spread);

struct ErrorMetrics {
  size_t vertices = 0;            // V
  size_t frames = 0;              // F, over all clips
  double kg_percent = 0;          // KG error in %
  double rmse_over_diagonal = 0;  // mean per-frame RMSE / first frame's bounding-box diagonal
  double max_error = 0;           // largest vertex distance, model units
  double max_error_over_diagonal = 0;
};

// ‖A − Ã‖²_F over every position of every frame of `decoded` against `original` (shaped alike), in doubles, in
// clip, frame, vertex and axis order.
double squared_error(const std::vector<FrameSequence>& original, const std::vector<FrameSequence>& decoded);

// Adds (original[i] − decoded[i])² for i < count to `error`, in doubles and in order: squared_error() a part at a time.
inline void add_squared_error(const float* original, const float* decoded, size_t count, double& error) {
  for (size_t i = 0; i < count; ++i) {
    const double d = double(original[i]) - double(decoded[i]);
    error += d * d;
  }
}

// Accumulates pairs of clips (original, decoded; same V and F each) and reports the metrics over all.
// The diagonal is the first frame of the first original clip.
class ErrorAccumulator {
 public:
  void add(const FrameSequence& original, const FrameSequence& decoded);
  ErrorMetrics result() const;

 private:
  size_t vertices_ = 0, frames_ = 0;
  double diagonal_ = -1;
  double error_squared_ = 0;   // ‖A − Ã‖²_F
  double spread_squared_ = 0;  // ‖A − E(A)‖²_F
  double rmse_sum_ = 0;        // Σ over frames of that frame's RMSE
  double max_error_ = 0;
};

// Bits per vertex per frame of `bytes` for V vertices over F frames.
inline double bits_per_vertex_frame(size_t bytes, size_t vertex_count, size_t frame_count) {
  return vertex_count && frame_count ? 8.0 * double(bytes) / (double(vertex_count) * double(frame_count)) : 0.0;
}

// The same over `vertex_frames`: segmorph/encoding.h.

}  // namespace segmorph
