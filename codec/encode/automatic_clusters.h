// The cluster count K and the residual prediction, chosen by estimated size (docs/codec.md, "Automatic K"): merged
// from the Morse segmentation to each candidate K, every candidate costed on a sample of the frames (the motion
// fitted and quantized, weights, the closed-loop residual rate and distortion at two steps), the cheapest kept; then
// temporal and spatial residual prediction kept where the estimate says they pay. The same for each segmentation
// given (the Morse levels as found and as refined by Eq. 6): the cheapest is kept.
#pragma once

#include "common/stream.h"
#include "encode/encode_problem.h"

namespace segmorph {

// The clusters to code, merged from one of `segmentations` (the Morse segmentation, and its levels refined when the
// refinement is on): settings.clusters when it is set, else the estimated best K; the segmentation whose merged
// clusters are estimated cheapest (lossy streams; lossless streams merge the last one to a fixed count). `chosen`
// receives its index. content.flags loses the residual predictions that do not pay (lossy streams).
Clusters choose_clusters(const EncodeProblem& problem, const std::vector<Clusters>& segmentations,
                         StreamContent& content, size_t* chosen = nullptr);

}  // namespace segmorph
