// A rate target and its tolerances, in one place. The user's target (RateMode::error: KG % of the whole file as verify
// measures it; bpvf: bits per vertex per frame of the whole file) passes down the layers of an encode; each layer
// aims a little inside what it is given, by the factors below, so that the file as a whole meets the target:
//
//   whole file (converter/encoding/           bpvf: a result within kBpvfTolerance of the target meets it;
//               encode_file.cpp, kept_skins)  error: kept skins' tracks searched until KG <= kErrorTargetMargin × E;
//                                            meshes that move rigidly: Draco takes kMovingMeshErrorShare of E
//   primitive (converter/encoding/           error: the codec is given kErrorTargetMargin × E; kept targets search
//              baked_primitives, kept_targets) until the animation's KG is in [kCloseEnough, 1] × that
//   stream (codec/encode/rate_control.cpp)   bpvf: the coded size lands in [kBpvfLandingLow, 1] × its budget
#pragma once

#include "encode/encoder.h"

namespace segmorph {

// The codec's error target relative to the file's: verify measures the decoded file against the original, where
// vertices Draco merged count once each and the morph-target form adds its rounding (measured: up to 0.3 % above the
// codec's own figure on the samples).
constexpr double kErrorTargetMargin = 0.99;

// A search over settings that measures the error (kept morph targets) stops once it is at least this fraction of its
// goal: closer costs encodes for a few bytes.
constexpr double kCloseEnough = 0.93;

// The codec's bpvf rate control stops once the stream's size is within this fraction below its budget.
constexpr double kBpvfLandingLow = 0.97;

// A whole file's bpvf within this factor of the target meets it (larger is said: the rest of the file, JSON and
// images, is measured on a first encode and may move a little on the second).
constexpr double kBpvfTolerance = 1.05;

// Draco's share of the KG error target in the meshes that move rigidly (compress_moving_meshes).
constexpr double kMovingMeshErrorShare = 0.6;

// The KG error target (%) of parts that have no rate of their own (Draco's moving meshes, tracks): the error target
// when there is one, else the default one.
inline double error_target(const CodecSettings& settings) {
  return settings.mode == RateMode::error ? settings.target : CodecSettings().target;
}

}  // namespace segmorph
