// Choices encode_tracks makes by itself, open to tests and measurements (tests/track_coding_test.cpp measures
// what each is worth). Every combination writes a valid stream; decode_tracks needs no option.
#pragma once

#include <cstdint>
#include <vector>

#include "segmorph/status.h"
#include "track_coding.h"

namespace segmorph {

struct TrackEncoderChoices {
  int order = 0;                         // prediction order of every sampler: 1 or 2; 0 = the cheaper per sampler
  bool rotation_all_components = false;  // code all four components of every rotation key (an escape each)
};

// encode_tracks with the choices made as `choices` says.
Status encode_tracks_with(const TrackSet& tracks, const std::vector<double>& steps, const TrackEncoderChoices& choices,
                          std::vector<uint8_t>& bytes, TrackSet& decoded);

}  // namespace segmorph
