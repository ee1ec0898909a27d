// The motion and the weights as a stream holds them (spec/bitstream.md): each cluster's affine transforms quantized
// on a linear and a translation step, and per welded vertex a few blend weights in multiples of 2^-kWeightBits. The
// encoder quantizes what it fitted; the decoder's dequantization (reconstruction.h) gives back what the prediction
// then uses, so the weights are fitted to the dequantized motion.
#pragma once

#include <cstdint>
#include <vector>

#include "common/stream.h"
#include "common/topology.h"
#include "encode/motion.h"

namespace segmorph {

// Root mean square distance of the base vertices (W × 3) from their cluster's centroid (K × 3): the lever arm that
// turns a translation step into a linear one.
double cluster_radius(const std::vector<float>& base_welded, const std::vector<double>& centroid,
                      const std::vector<uint32_t>& labels);

// content's motion (steps and F × K × 12 coefficients) and weights: the fitted motion quantized, then the weights
// fitted (Eq. 3, over `rings` 2 and 4 clusters at most) to the dequantized motion, or one-hot when `blend` is false;
// the weights on up to `threads` threads (the same for every count).
void quantize_motion_and_weights(const AffineMotion& fitted, double linear_step, double translation_step,
                                 const std::vector<float>& base_welded, const Trajectories& frames,
                                 const Clusters& clusters, const VertexAdjacency& adjacency, bool blend,
                                 StreamContent& content, size_t threads = 1);

}  // namespace segmorph
