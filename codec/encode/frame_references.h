// The encoder's choice of each frame's reference (stream version 3, kFlagFrameReferences): a frame is predicted from
// an earlier frame of its clip than the previous one where that frame predicts it much better, as in a gait or any
// motion that repeats its poses.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/reconstruction.h"
#include "common/stream.h"

namespace segmorph {

struct FrameReferences {
  uint32_t window = 1;               // the largest distance chosen
  std::vector<uint32_t> references;  // per stream frame, as StreamContent::references
  bool needed = false;               // some frame's reference is not the one versions 1 and 2 imply
};

// Per frame, the distance back (0 .. min(max_window, its index in the clip); 0: none) to the frame whose open-loop
// residuals (target minus the content's prediction) predict its own best, scored as the decoder's temporal and
// spatial predictions would use them, on a sample of the vertices: the reference the content's flags imply (the
// previous frame with temporal residuals, else none) unless another leaves at most kReferenceGain of its score.
// content: the welding, clips, flags, quantized motion and weights (its references are ignored); base_welded:
// W × 3; targets: F × W × 3. With `needed`, the stream takes temporal residuals and frame references. The frames
// are scored on up to `threads` threads (0: every core), with the same result for every count.
FrameReferences choose_frame_references(const StreamContent& content, const ResidualTraversal& traversal,
                                        const std::vector<float>& base_welded, const std::vector<float>& targets,
                                        uint32_t max_window, double step, size_t threads = 1);

// The largest window a stream of V vertices may have (format::kMaxReferenceWindowVertices), at least 1.
uint32_t largest_reference_window(size_t vertices);

}  // namespace segmorph
