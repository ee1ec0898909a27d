// The glTF side of the track streams: a file's keyframe animation coded with the track stream of
// SEGMORPH_animation_compression (codec/common/track_set.h, spec/tracks.md): per animation, one stream holds its LINEAR
// and STEP samplers of node translation, rotation and scale; their accessors stay in the JSON without data, and the
// stream fills them. How finely they are quantized is the encoder's choice (converter/encoding/track_precision.h).
#pragma once

#include <cstddef>
#include <functional>

#include <tiny_gltf.h>

#include "common/track_set.h"
#include "segmorph/status.h"

namespace segmorph {

struct TrackReport {
  size_t samplers = 0, keys = 0, bytes = 0;
  size_t dropped = 0;  // samplers whose channels held the node's rest value to within their step, removed
};

// The quantization step of a track of `path` that moves `node`.
using TrackStep = std::function<double(TrackPath path, int node)>;

// Codes every LINEAR or STEP sampler of `model`'s animations that moves translations, rotations or scales
// (with increasing, finite times and finite values; others stay as they are) at the steps `step_of` gives, and lists
// the extension as required: a viewer without it would play the coded channels from accessors without data, as
// zeros. Channels that hold their node's rest value to within half their step are removed instead (as gltfpack
// removes them).
Status code_track_streams(tinygltf::Model& model, const TrackStep& step_of, TrackReport& report);

// Decodes every coded animation of `model` back into float accessors; `bytes` and `animations` (when given) receive
// the size of the streams and how many animations had one. A model without coded animations is left as it is.
Status decode_tracks_in_model(tinygltf::Model& model, size_t* bytes = nullptr, size_t* animations = nullptr);

}  // namespace segmorph
