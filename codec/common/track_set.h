// Keyframe tracks (glTF animation samplers: translation, rotation, scale, morph weights) quantized and range-coded:
// the track stream of SEGMORPH_animation_compression (spec/tracks.md, Appendix C). Self-contained: the stream
// holds every key time and value; the glTF JSON only tells the decoder what to expect (TrackLayout) so that a
// stream that disagrees with its file is refused.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace segmorph {

enum class TrackPath : uint8_t { translation = 0, rotation = 1, scale = 2, weights = 3 };

struct TrackSampler {
  TrackPath path = TrackPath::translation;
  int components = 3;         // translation and scale 3, rotation 4 (x, y, z, w), weights: the mesh's target count
  int times = -1;             // index into TrackSet::times
  std::vector<float> values;  // key count × components; key count = size of its time array
};

struct TrackSet {
  std::vector<std::vector<float>> times;  // distinct key-time arrays: each finite, >= 0, strictly increasing, >= 1 key
                                          // (+0.0, not -0.0: the stream codes times by their bit patterns)
  std::vector<TrackSampler> samplers;
};

// What the glTF JSON says about a stream, checked against it by the decoder: per time array its key count, per
// sampler its time array, path and component count.
struct TrackLayout {
  std::vector<size_t> time_counts;
  struct Sampler {
    int times = -1;
    TrackPath path = TrackPath::translation;
    int components = 0;
  };
  std::vector<Sampler> samplers;
};

// The layout of a TrackSet (what an encoder writes into the JSON).
inline TrackLayout track_layout(const TrackSet& tracks) {
  TrackLayout layout;
  for (const std::vector<float>& times : tracks.times) layout.time_counts.push_back(times.size());
  for (const TrackSampler& sampler : tracks.samplers)
    layout.samplers.push_back({sampler.times, sampler.path, sampler.components});
  return layout;
}

}  // namespace segmorph
