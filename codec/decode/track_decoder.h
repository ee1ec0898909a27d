// The decoder of the track stream (common/track_set.h says what it holds; spec/tracks.md, Appendix C).
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/track_set.h"
#include "segmorph/status.h"

namespace segmorph {

// Decodes a stream laid out as `layout` says; bad_data with a one-line message on anything else. Never allocates
// more than the layout's counts (which the caller has bounded by the file's size) or than the stream can hold.
Status decode_tracks(const uint8_t* data, size_t size, const TrackLayout& layout, TrackSet& out);

}  // namespace segmorph
