// Rate control of the residuals (Hachani et al., §2.3, Eqs. 7–12): per coordinate subband (x, y, z) a
// quantizer step is chosen by a Lagrangian trade-off of distortion against rate, the multiplier λ found by
// bisection so that the whole stream meets its target (a KG error, or a size).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "reconstruction.h"

namespace segmorph {

// Distortion and rate of one subband at each candidate step: D in squared model units summed over all its
// samples (vertex multiplicities included), R in bits (estimated from the symbols' conditional entropy).
struct SubbandCurve {
  std::vector<double> step, distortion, bits;
};

// Closed-loop D(q) and R(q) of the three subbands at more candidate steps (steps[axis], any number each; the
// measurements are appended to curves[axis]): the decoder's residual loop (reconstruction.h) with the content's
// flags and clips. predictions, targets: F × W × 3; multiplicity: W (original vertices per welded vertex). The
// steps are measured on up to `threads` threads (0: every hardware thread), with the same results for any number.
void measure_subbands(const StreamContent& content, const ResidualTraversal& traversal,
                      const std::vector<double>& predictions, const std::vector<float>& targets,
                      const std::vector<uint32_t>& multiplicity, const std::vector<double> (&steps)[3],
                      SubbandCurve (&curves)[3], size_t threads = 1);

// reconstruction.h's predicted_frames, the frames split over up to `threads` threads (0: every hardware thread): the
// same predictions, F × W × 3.
std::vector<double> predicted_frames(const StreamContent& content, const std::vector<float>& welded, size_t threads);

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
