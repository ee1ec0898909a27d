// The encoder's words that its settings and reports share with the pipeline API (segmorph.h): how a rate target is
// read, and what the codec tells of each stream it made. The runtime decoder (decoder.h) needs none of it.
#pragma once

#include <cstddef>

namespace segmorph {

enum class RateMode {
  error,     // target: KG error in percent
  bpvf,      // target: bits per vertex per frame of the whole output
  lossless,  // restore the input floats bit for bit
};

// Bits per vertex per frame of `bytes` over `vertex_frames`, V × F summed over the primitives and clips coded (0 when
// there are none): the rate every report and target of segmorph is in.
inline double bits_per_vertex_frame(size_t bytes, double vertex_frames) {
  return vertex_frames > 0 ? 8.0 * double(bytes) / vertex_frames : 0.0;
}

// One animation stream of a primitive coded as frames or kept targets, as the codec made it.
struct StreamReport {
  int mesh = -1, primitive = -1;  // the primitive of the encoded file it animates
  size_t clusters = 0;      // K
  double e_pi_morse = 0;    // E(Π) of the Morse segmentation before merging to K and refinement (paper, Table 2)
  double e_pi = 0;          // E(Π) of the final clusters
  int curvature_refinement_passes = 0;   // passes of the concavity refinement of the Morse levels (Eq. 6)
  bool curvature_refined = false;        // the clusters were merged from the refined levels (Eq. 6)
  int motion_refinement_iterations = 0;  // rounds of moving boundary vertices to the clusters that predict them best
  double residual_steps[3] = {0, 0, 0};
  double kg_percent = 0;  // of the encoder's own reconstruction (of the animation it plays, for kept targets)
  size_t bytes_motion = 0, bytes_residuals = 0, bytes_total = 0;
  // Milliseconds per stage.
  double ms_segmentation = 0, ms_motion = 0, ms_prediction = 0, ms_rate_control = 0, ms_entropy = 0;
};

}  // namespace segmorph
