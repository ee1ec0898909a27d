// The rate–distortion choice of the residuals' steps (Hachani et al., §2.3, Eqs. 7–12), which rate_control.h drives:
// per coordinate subband (x, y, z) a quantizer step is chosen by a Lagrangian trade-off of distortion against rate, the
// multiplier λ found by bisection so that the whole stream meets its target (a KG error, or a size).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "common/reconstruction.h"

namespace segmorph {

// Distortion and rate of one subband at each candidate step: D in squared model units summed over all its
// samples (vertex multiplicities included), R in bits (estimated from the symbols' conditional entropy).
struct SubbandCurve {
  std::vector<double> step, distortion, bits;
};

// The predicted frames of a stream content (reconstruction.h's predicted_frames), computed a frame at a time where
// they are used, as the decoder does: held for every frame they would take F × W × 3 doubles, twice the frames' own
// size, for a pass that costs less than reading them back from memory.
class FramePredictions {
 public:
  FramePredictions(const StreamContent& content, const std::vector<float>& welded)
      : motion_(dequantized_motion(content, welded)),
        weights_(dequantized_weights(content)),
        predictor_(welded.data(), motion_, weights_) {}
  FramePredictions(const FramePredictions&) = delete;  // the predictor refers to motion_
  FramePredictions& operator=(const FramePredictions&) = delete;
  // Frame `frame`'s predicted positions, W × 3.
  void predict(size_t frame, double* out) const { predictor_.predict(frame, out); }

 private:
  const AffineMotion motion_;
  const ClusterWeights weights_;
  const FramePredictor predictor_;
};

// Memory measure_subbands keeps from one call to the next: the buffers of the frames it holds for later frames'
// references, which a stream with version 3's references holds many of (each W × lanes doubles), and which would
// otherwise be allocated and faulted in again at every call. One per caller; calls must not overlap.
struct MeasureBuffers {
  std::vector<std::vector<std::vector<double>>> spare;  // per range of lanes, buffers not in use
};

// Closed-loop D(q) and R(q) of the three subbands at more candidate steps (steps[axis], any number each; the
// measurements are appended to curves[axis]): the decoder's residual loop (reconstruction.h) with the content's
// flags and clips. targets: F × W × 3; multiplicity: W (original vertices per welded vertex). The steps are measured
// on up to `threads` threads (0: every hardware thread), with the same results for any number. `progress`, if any,
// is called on the calling thread with the fraction of the frames walked, after each frame. `buffers`, if any, is
// reused. The walk uses AVX2 on x86 processors that have it, unless `allow_avx2` is false (for tests): the same
// curves either way.
void measure_subbands(const StreamContent& content, const ResidualTraversal& traversal,
                      const FramePredictions& predictions, const std::vector<float>& targets,
                      const std::vector<uint32_t>& multiplicity, const std::vector<double> (&steps)[3],
                      SubbandCurve (&curves)[3], size_t threads = 1,
                      const std::function<void(double fraction)>& progress = {}, MeasureBuffers* buffers = nullptr,
                      bool allow_avx2 = true);

struct StepChoice {
  size_t index[3] = {0, 0, 0};  // into each curve
  double distortion = 0, bits = 0;
};

// The Lagrangian choice for multiplier λ: per subband the step minimizing D + λR.
StepChoice choose_steps(const SubbandCurve (&curves)[3], double lambda);

// Bisection on λ (the paper's method), then every combination of measured steps (the curves are not convex,
// so the Lagrangian alone can miss the best feasible choice): the cheapest choice with total distortion <=
// max_distortion.
StepChoice steps_for_distortion(const SubbandCurve (&curves)[3], double max_distortion);

// The same search for the least distorted choice with residual bits <= max_bits.
StepChoice steps_for_bits(const SubbandCurve (&curves)[3], double max_bits);

}  // namespace segmorph
