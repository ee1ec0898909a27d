// Which vertex of one sampling of a primitive is which vertex of another (a compressed file's vertices come
// back in another order, and encoders may merge duplicates or drop unused vertices).
#pragma once

#include <cstdint>
#include <vector>

#include "common/frame_sequence.h"

namespace segmorph {

// For each vertex of `reference` (clips of one primitive), the vertex of `other` (the same clips sampled at
// the same times, any vertex order and count, at least one vertex) whose trajectory is nearest: the least
// sum of squared distances over every frame of every clip. That is the pairing under which the other's
// error is smallest, so quantization that moves vertices past their neighbours cannot mislead it (a nearest
// first frame would); of equally near vertices, the lowest. Before any search: identity when the two have the same
// vertex count and first frame (whatever duplicates the reference holds). The vertices are matched on up to
// `threads` threads (0: every hardware thread), with the same result for any number. The search holds a
// vertex-major copy of the other's first frames, at most `held_bytes` (and at least one frame).
std::vector<uint32_t> match_vertices(const std::vector<FrameSequence>& reference,
                                     const std::vector<FrameSequence>& other, size_t threads = 1,
                                     size_t held_bytes = size_t(64) << 20);

}  // namespace segmorph
