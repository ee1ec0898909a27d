// A file's keyframe animation coded with the track stream of SEGMORPH_animation_compression (codec/common/track_set.h,
// spec/tracks.md): per animation, one stream holds its LINEAR and STEP samplers of node translation, rotation
// and scale; their accessors stay in the JSON without data, and the stream fills them.
#pragma once

#include <cstddef>

#include <tiny_gltf.h>

#include "segmorph/status.h"

namespace segmorph {

// How finely encode quantizes the tracks: `distance` is the displacement (in model units) a quantization step may
// cause at a lever of half the scene's diagonal D. A rotation's step is distance / D (its angle error is about
// twice its components'), a scale's distance / (D / 2), a translation's distance over its parent's world scale.
struct TrackPrecision {
  double distance = 0;
  double diagonal = 0;  // D; 0: scene_diagonal of the model coded
};

// The diagonal of the bounding box of every mesh of `model` at rest (each node's mesh bounds under its static
// global transform): the scale TrackPrecision is measured against. 1 when the model has no mesh bounds.
double scene_diagonal(const tinygltf::Model& model);

struct TrackReport {
  size_t samplers = 0, keys = 0, bytes = 0;
  size_t dropped = 0;  // samplers whose channels held the node's rest value to within their step, removed
};

// Codes every LINEAR or STEP sampler of `model`'s animations that moves translations, rotations or scales
// (with increasing, finite times and finite values; others stay as they are), and lists the extension as
// required: a viewer without it would play the coded channels from accessors without data, as zeros. Channels
// that hold their node's rest value to within half their step are removed instead (as gltfpack removes them).
Status compress_tracks(tinygltf::Model& model, const TrackPrecision& precision, TrackReport& report);

// Decodes every coded animation of `model` back into float accessors; `bytes` and `animations` (when given) receive
// the size of the streams and how many animations had one. A model without coded animations is left as it is.
Status decode_tracks_in_model(tinygltf::Model& model, size_t* bytes = nullptr, size_t* animations = nullptr);

}  // namespace segmorph
