// The tracks of an encoded file, and the search that brings kept skins within an error target. A kept skin (the mesh
// with its joints and weights in Draco) has no codec stream: its error is its tracks' quantization and its weights'
// (bytes), measured on the decoded file as verify measures it.
#pragma once

#include <tiny_gltf.h>

#include "encode/encoder.h"
#include "pipeline.h"
#include "segmorph/status.h"

namespace segmorph {

struct TrackCoding {
  size_t bytes = 0;  // the track stream's
  // > 0 when no track precision brings the kept skins within the target: the KG % they stay at. The tracks are then
  // not coded (the caller bakes the skins instead).
  double kept_skins_floor = 0;
  // The distance the search for kept skins settled on (0 without one).
  double searched_distance = 0;
};

// Codes the translation, rotation and scale tracks of `model`, an encode of file's model. With `kept_skins` and an
// error target: at the coarsest quantization distance whose measured worst KG is within kErrorTargetMargin of the
// target (a bracket by doublings or halvings, then bisections in log distance); otherwise at a distance in
// proportion to the error target and the scene's diagonal.
// The search measures on a subsample of frames (at most 24 per clip), then checks its choice on every frame, halving
// the distance while that is above the goal; each measurement is a progress line. `settled`, when > 0: the distance
// a search for the same kept skins settled on in another encode of the file (the other variant of --targets auto),
// measured on every frame first and kept, without a search, when that is within the goal.
Status code_tracks(const SampledFile& file, const CodecSettings& codec, bool kept_skins, tinygltf::Model& model,
                   TrackCoding& coding, const Progress& progress, double settled = 0);

}  // namespace segmorph
