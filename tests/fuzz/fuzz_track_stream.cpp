// libFuzzer target: decode_tracks on arbitrary bytes, against a layout read from the input's first bytes
// (fuzz_track_layout.h: small, so allocations stay bounded as the converter's bound keeps them). Besides the
// sanitizers' checks it asserts the decoder's promises: a refusal is one line; an accepted stream has the layout's
// shape, times that are finite, non-negative and strictly increasing, finite values and unit rotations.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "common/track_set.h"
#include "decode/track_decoder.h"
#include "fuzz_track_layout.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void check_decoded(const segmorph::TrackLayout& layout, const segmorph::TrackSet& tracks) {
  using namespace segmorph;
  check(tracks.times.size() == layout.time_counts.size() && tracks.samplers.size() == layout.samplers.size());
  for (size_t i = 0; i < tracks.times.size(); ++i) {
    check(tracks.times[i].size() == layout.time_counts[i]);
    for (size_t k = 0; k < tracks.times[i].size(); ++k) {
      check(std::isfinite(tracks.times[i][k]) && !std::signbit(tracks.times[i][k]));
      check(k == 0 || tracks.times[i][k] > tracks.times[i][k - 1]);
    }
  }
  for (size_t s = 0; s < tracks.samplers.size(); ++s) {
    const TrackSampler& sampler = tracks.samplers[s];
    check(sampler.path == layout.samplers[s].path && sampler.components == layout.samplers[s].components &&
          sampler.times == layout.samplers[s].times);
    check(sampler.values.size() == tracks.times[size_t(sampler.times)].size() * size_t(sampler.components));
    for (float x : sampler.values) check(std::isfinite(x));
    if (sampler.path == TrackPath::rotation)
      for (size_t k = 0; k < sampler.values.size(); k += 4) {
        double norm = 0;
        for (size_t c = 0; c < 4; ++c) norm += double(sampler.values[k + c]) * sampler.values[k + c];
        check(std::fabs(norm - 1.0) < 1e-5);
      }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace segmorph;
  TrackLayout layout;
  size_t used = 0;
  if (!fuzz::read_track_layout(data, size, layout, used)) return 0;
  TrackSet tracks;
  const Status status = decode_tracks(data + used, size - used, layout, tracks);
  if (!status.ok()) {
    check(!status.message().empty() && status.message().find('\n') == std::string::npos);
    return 0;
  }
  check_decoded(layout, tracks);
  return 0;
}
