// libFuzzer target: the runtime decoder's C API (include/segmorph/decoder_c.h) on arbitrary bytes. The first byte
// chooses what is driven, the rest is the input:
//   byte 0 % 4 == 0  an animation stream against fuzz_base_mesh.h's mesh, every clip whole (segmorph_decode_clip),
//                    the first clip's normals turned (segmorph_decoder_turn_normals);
//                1  the same, then clip (byte 0 / 4) % clips again frame by frame after a seek, which must give the
//                   same floats;
//                2  kept targets (segmorph_decode_targets);
//                3  a track layout (fuzz_track_layout.h) and a track stream (segmorph_decode_tracks).
// Besides the sanitizers' checks it asserts the API's promises: a refusal has a status and a one-line message, the
// bounds are what the calls fill, and what is accepted is finite.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "fuzz_base_mesh.h"
#include "fuzz_track_layout.h"
#include "segmorph/decoder_c.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

// A failure's message is one line and says something; a success's is empty.
void check_message(const segmorph_decoder* decoder, segmorph_status status) {
  const char* message = segmorph_decoder_message(decoder);
  if (status == SEGMORPH_STATUS_OK) {
    check(message[0] == '\0');
    return;
  }
  check(status == SEGMORPH_STATUS_BAD_DATA || status == SEGMORPH_STATUS_UNSUPPORTED);
  check(message[0] != '\0' && std::strchr(message, '\n') == nullptr);
}

bool all_finite(const std::vector<float>& values) {
  for (float x : values)
    if (!std::isfinite(x)) return false;
  return true;
}

void animation(segmorph_decoder* decoder, uint8_t control, const uint8_t* data, size_t size) {
  static const segmorph::fuzz::BaseMesh mesh = segmorph::fuzz::base_mesh();
  segmorph_status status = segmorph_decoder_open(decoder, data, size, mesh.positions.data(), mesh.vertex_count(),
                                                 mesh.triangles.data(), mesh.triangles.size());
  check_message(decoder, status);
  if (status != SEGMORPH_STATUS_OK) {
    check(segmorph_decoder_clip_count(decoder) == 0);
    return;
  }
  const size_t clips = segmorph_decoder_clip_count(decoder), frame_floats = mesh.vertex_count() * 3;
  check(clips > 0 && segmorph_decoder_vertex_count(decoder) == mesh.vertex_count());
  if ((control & 3) == 2) {
    std::vector<float> targets(segmorph_decode_clip_bound(decoder, 0));
    status = segmorph_decode_targets(decoder, targets.data(), targets.size());
    check_message(decoder, status);
    check(status != SEGMORPH_STATUS_OK || (clips == 1 && all_finite(targets)));
    return;
  }
  std::vector<std::vector<float>> whole(clips);
  for (size_t c = 0; c < clips; ++c) {
    const size_t frames = segmorph_decoder_frame_count(decoder, c);
    check(frames > 0 && segmorph_decode_clip_bound(decoder, c) == frames * frame_floats);
    whole[c].resize(segmorph_decode_clip_bound(decoder, c));
    status = segmorph_decode_clip(decoder, c, whole[c].data(), whole[c].size());
    check_message(decoder, status);
    if (status != SEGMORPH_STATUS_OK) return;
    check(all_finite(whole[c]));
  }
  check(segmorph_decoder_next_clip(decoder) == clips);
  if ((control & 3) == 0) {
    // The normals of the first clip's frames, on the stream's welding whatever it is: finite.
    std::vector<float> surface(frame_floats), normals(whole[0].size());
    check(segmorph_decoder_surface_normals(decoder, nullptr, surface.data(), surface.size()) == SEGMORPH_STATUS_OK);
    check(segmorph_decoder_turn_normals(decoder, surface.data(), whole[0].data(), whole[0].size() / frame_floats,
                                        normals.data(), normals.size()) == SEGMORPH_STATUS_OK);
    check(all_finite(surface) && all_finite(normals));
  }
  if ((control & 3) != 1) return;
  // A clip again, frame by frame, after a seek back to it: the same floats.
  const size_t clip = size_t(control >> 2) % clips;
  check(segmorph_decoder_seek(decoder, clip) == SEGMORPH_STATUS_OK);
  std::vector<float> frame(frame_floats);
  for (size_t f = 0; f < segmorph_decoder_frame_count(decoder, clip); ++f) {
    check(segmorph_decoder_next_clip(decoder) == clip && segmorph_decoder_next_frame(decoder) == f);
    check(segmorph_decode_frame(decoder, frame.data(), frame.size()) == SEGMORPH_STATUS_OK);
    check(std::memcmp(frame.data(), &whole[clip][f * frame_floats], frame_floats * sizeof(float)) == 0);
  }
}

void tracks(segmorph_decoder* decoder, const uint8_t* data, size_t size) {
  segmorph::TrackLayout layout;
  size_t used = 0;
  if (!segmorph::fuzz::read_track_layout(data, size, layout, used)) return;
  std::vector<segmorph_track_sampler> samplers;
  for (const segmorph::TrackLayout::Sampler& sampler : layout.samplers)
    samplers.push_back({uint32_t(sampler.times), uint32_t(sampler.path), uint32_t(sampler.components)});
  const size_t floats = segmorph_decode_tracks_bound(layout.time_counts.data(), layout.time_counts.size(),
                                                     samplers.data(), samplers.size());
  std::vector<float> out(floats);
  const segmorph_status status =
      segmorph_decode_tracks(decoder, data + used, size - used, layout.time_counts.data(), layout.time_counts.size(),
                             samplers.data(), samplers.size(), out.data(), out.size());
  if (floats == 0) {  // an invalid layout (a time array no sampler uses): refused as an argument
    check(status == SEGMORPH_STATUS_INVALID_ARGUMENT);
    return;
  }
  check_message(decoder, status);
  check(status != SEGMORPH_STATUS_OK || all_finite(out));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  segmorph_decoder* decoder = segmorph_decoder_create();
  check(decoder != nullptr);
  if ((data[0] & 3) == 3)
    tracks(decoder, data + 1, size - 1);
  else
    animation(decoder, data[0], data + 1, size - 1);
  segmorph_decoder_destroy(decoder);
  return 0;
}
