// The cluster count K and the residual prediction, chosen by estimated size (docs/codec.md, "Automatic K"): merged
// from the Morse segmentation to each candidate K, every candidate costed on a sample of the frames (the motion
// fitted and quantized, weights, the closed-loop residual rate and distortion at two steps), the cheapest kept; then
// temporal and spatial residual prediction kept where the estimate says they pay.
#pragma once

#include "encode_problem.h"
#include "stream.h"

namespace segmorph {

// The clusters to code (merged from `morse`, the refined Morse segmentation): settings.clusters when it is set, else
// the estimated best K (lossless streams: a fixed count). content.flags loses the residual predictions that do not
// pay (lossy streams).
Clusters choose_clusters(const EncodeProblem& problem, const Clusters& morse, StreamContent& content);

}  // namespace segmorph
