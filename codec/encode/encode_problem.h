// What encode_animation's stages share (encoder.cpp, automatic_clusters.cpp, rate_control.cpp): the primitive
// welded, its trajectories, the decoder's welded base and residual traversal, and the scales the steps start from.
#pragma once

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/reconstruction.h"
#include "common/topology.h"
#include "encode/encoder.h"
#include "encode/motion.h"

namespace segmorph {

// Motion quantizer steps relative to the mean residual step: translation β q̄, linear β q̄ / (RMS cluster radius).
constexpr double kMotionStepRatio = 0.5;

struct EncodeProblem {
  const std::vector<FrameSequence>& clips;
  const std::vector<float>& base;  // V × 3, the base positions as the decoder has them
  const CodecSettings& settings;
  size_t vertex_count = 0, welded = 0, frames_total = 0;  // V, W, F
  WeldedTopology topology;
  VertexAdjacency adjacency;
  Trajectories trajectories;           // F × W × 3, every clip end to end
  std::vector<float> base_welded;      // W × 3
  ResidualTraversal traversal;
  std::vector<uint32_t> multiplicity;  // W: original vertices per welded vertex
  double spread = 0;                   // ‖A − E(A)‖²_F (frame_spread)
  double mean_step = 0;                // the residual step the target implies (or the motion error, without one)
  double finest_step = 0;              // no lossy step is finer (encoder.cpp, kFinestStepBits)

  EncodeProblem(const std::vector<FrameSequence>& clips_, const std::vector<float>& base_, const CodecSettings& settings_)
      : clips(clips_), base(base_), settings(settings_) {}
  // The KG target as squared distortion: (E / 100)² × spread.
  double max_distortion() const { return std::pow(settings.target / 100.0, 2) * spread; }
};

// encode_animation's first stages, in order; a stage's own test sets up its problem with them.
// The welded problem: topology, the stream's header fields (in `content`), trajectories, the decoder's welded base
// and traversal.
Status set_up_problem(EncodeProblem& problem, StreamContent& content);
// The Morse segmentation of the first frame as sampled (diffusion, Morse function, levels), its E(Π)
// (report.e_pi_morse), and the concavity refinement of its levels (Eq. 6): `segmentations` receives the refined
// clusters, or with settings.choose_segmentation the Morse clusters and then the refined ones (when they differ).
Status segment_first_frame(const EncodeProblem& problem, std::vector<Clusters>& segmentations, StreamReport& report);
// The scale of the residual steps: from the target error when there is one, else from the motion error (E(Π) of
// the Morse segmentation); and the finest step any lossy quantizer may take.
void set_step_scales(EncodeProblem& problem, double e_pi_morse);

// Reports a stage of the encode and the fraction of it done (negative: not known) to the settings' progress, if any.
inline void report_progress(const CodecSettings& settings, const std::string& stage, double fraction = -1) {
  if (settings.progress) settings.progress(stage, fraction);
}

using EncodeClock = std::chrono::steady_clock;
inline double milliseconds_since(EncodeClock::time_point start) {
  return std::chrono::duration<double, std::milli>(EncodeClock::now() - start).count();
}

}  // namespace segmorph
