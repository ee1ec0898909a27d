// The encoder of the track stream (common/track_set.h says what it holds; spec/tracks.md, Appendix C).
#pragma once

#include <cstdint>
#include <vector>

#include "common/track_set.h"
#include "segmorph/status.h"

namespace segmorph {

// Encodes `tracks`, sampler s quantized with steps[s] (> 0, in the value's units; rotations in quaternion units).
// The encoder may round each step down to the stream's grid of representable steps. `decoded` receives exactly what
// decode_tracks returns for the bytes. Fails (invalid_argument) on input the stream cannot hold.
Status encode_tracks(const TrackSet& tracks, const std::vector<double>& steps, std::vector<uint8_t>& bytes,
                     TrackSet& decoded);

// Choices encode_tracks makes by itself, open to tests and measurements (tests/track_coding_test.cpp measures
// what each is worth). Every combination writes a valid stream; decode_tracks needs no option.

struct TrackEncoderChoices {
  int order = 0;                         // prediction order of every sampler: 1 or 2; 0 = the cheaper per sampler
  bool rotation_all_components = false;  // code all four components of every rotation key (an escape each)
};

// encode_tracks with the choices made as `choices` says.
Status encode_tracks_with(const TrackSet& tracks, const std::vector<double>& steps, const TrackEncoderChoices& choices,
                          std::vector<uint8_t>& bytes, TrackSet& decoded);

}  // namespace segmorph
