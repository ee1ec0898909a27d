// How finely encode quantizes a file's node tracks (the track streams, extensions/track_streams.h): the steps that
// keep the displacement they cause within a distance at the scale of the scene.
#pragma once

#include <tiny_gltf.h>

#include "segmorph/status.h"
#include "track_streams.h"

namespace segmorph {

// `distance` is the displacement (in model units) a quantization step may cause at a lever of half the scene's
// diagonal D. A rotation's step is distance / D (its angle error is about twice its components'), a scale's
// distance / (D / 2), a translation's distance over its parent's world scale.
struct TrackPrecision {
  double distance = 0;
  double diagonal = 0;  // D; 0: scene_diagonal of the model coded
};

// The diagonal of the bounding box of every mesh of `model` at rest (each node's mesh bounds under its static
// global transform): the scale TrackPrecision is measured against. 1 when the model has no mesh bounds.
double scene_diagonal(const tinygltf::Model& model);

// Codes `model`'s tracks (code_track_streams) at the steps `precision` gives.
Status compress_tracks(tinygltf::Model& model, const TrackPrecision& precision, TrackReport& report);

}  // namespace segmorph
