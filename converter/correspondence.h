// Which vertex of one sampling of a primitive is which vertex of another (a compressed file's vertices come
// back in another order, and encoders may merge duplicates).
#pragma once

#include <cstdint>
#include <vector>

#include "frame_sequence.h"

namespace segmorph {

// For each vertex of `reference` (clips of one primitive), the vertex of `other` (the same clips, any vertex
// order and count) that is nearest in the first frame; where several are about as near (within 1e-4 of the
// bounding-box diagonal), the one whose whole trajectory is nearest. Identity when the two have the same
// vertex count and first frame.
std::vector<uint32_t> match_vertices(const std::vector<FrameSequence>& reference, const std::vector<FrameSequence>& other);

}  // namespace segmorph
