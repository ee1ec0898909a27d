#include "kept_skins.h"

#include <cmath>

#include "comparison.h"
#include "compressed.h"
#include "rate_target.h"
#include "sample.h"
#include "tracks.h"

namespace segmorph {
namespace {

// The tracks' quantization distance where nothing measured depends on it: this fraction of the error target times
// the scene's diagonal, about what the search settles on for kept skins.
constexpr double kTrackDistanceRatio = 0.25;
// The search: a bracket in at most kBracketRounds doublings or halvings, then kHalvings bisections of it.
constexpr int kBracketRounds = 8, kHalvings = 4;

// The worst KG error (%) of `encoded` against the file it was encoded from, as verify measures it.
Status measured_kg(const SampledFile& file, tinygltf::Model encoded, double& kg) {
  SEGMORPH_RETURN_IF_ERROR(decode_compressed_model(encoded));
  Scene scene;
  SEGMORPH_RETURN_IF_ERROR(analyze_scene(encoded, scene));
  AnimationComparison comparison;
  SEGMORPH_RETURN_IF_ERROR(compare_animation(file.model, file.scene, file.sampled, encoded, scene, comparison));
  kg = comparison.worst.kg_percent;
  return Status::Ok();
}

}  // namespace

Status code_tracks(const SampledFile& file, const CodecSettings& codec, bool kept_skins, tinygltf::Model& model,
                   TrackCoding& coding) {
  coding = TrackCoding();
  const double first = kTrackDistanceRatio * error_target(codec) / 100 * scene_diagonal(model);
  auto encode = [&](double distance, tinygltf::Model& result) {  // in place
    TrackReport report;
    SEGMORPH_RETURN_IF_ERROR(compress_tracks(result, TrackPrecision{distance}, report));
    coding.bytes = report.bytes;
    return Status::Ok();
  };
  if (!kept_skins || codec.mode != RateMode::error) return encode(first, model);

  const double goal = kErrorTargetMargin * codec.target;
  tinygltf::Model candidate;
  double kg = 0, within = 0, beyond = 0;  // distances known within and beyond the goal (0: none yet)
  auto within_goal = [&](double distance, bool& ok) {
    candidate = model;
    SEGMORPH_RETURN_IF_ERROR(encode(distance, candidate));
    SEGMORPH_RETURN_IF_ERROR(measured_kg(file, candidate, kg));
    ok = kg <= goal;
    return Status::Ok();
  };
  bool ok = false;
  double distance = first;
  for (int round = 0; round < kBracketRounds; ++round) {
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance, ok));
    (ok ? within : beyond) = distance;
    if (within > 0 && beyond > 0) break;
    distance = ok ? distance * 2 : distance / 2;
  }
  if (within == 0) {  // the error is not the tracks' (a kept skin's weights are bytes)
    coding = TrackCoding();
    coding.kept_skins_floor = kg;
    return Status::Ok();
  }
  for (int round = 0; beyond > 0 && round < kHalvings; ++round) {
    distance = std::sqrt(within * beyond);
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance, ok));
    (ok ? within : beyond) = distance;
  }
  return encode(within, model);
}

}  // namespace segmorph
