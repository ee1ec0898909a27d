// Writes the seed corpus of fuzz_track_stream: valid track streams of small synthetic animations, each behind the
// layout bytes the fuzzer reads (fuzz_track_layout.h), so that mutations start from every path of the decoder:
// regular and uneven key times, arrays of 1, 2 and 3 keys, every sampler path, both prediction orders, rotations
// with their largest component rebuilt and with all four coded (escapes), coarse and fine steps. Each stream is
// checked to decode to the encoder's values before it is written.
//
//   fuzz_track_seeds OUTPUT_DIRECTORY
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/track_set.h"
#include "decode/track_decoder.h"
#include "encode/track_encoder.h"
#include "fuzz_track_layout.h"

namespace segmorph::fuzz {
namespace {

std::vector<float> even_times(size_t count, double duration) {
  std::vector<float> times;
  for (size_t k = 0; k < count; ++k) times.push_back(float(duration * double(k) / double(count > 1 ? count - 1 : 1)));
  return times;
}

std::vector<float> uneven_times(size_t count) {
  std::vector<float> times;
  double t = 0.25;
  for (size_t k = 0; k < count; ++k, t += 0.02 + 0.05 * (k % 3)) times.push_back(float(t));
  return times;
}

// A sampler of `path` on time array `array`: smooth motion, with a jump half-way when `jumpy`.
TrackSampler sampler(TrackPath path, int components, int array, const std::vector<float>& times, bool jumpy) {
  TrackSampler s{path, components, array, {}};
  for (size_t k = 0; k < times.size(); ++k) {
    const double t = times[k] + (jumpy && k >= times.size() / 2 ? 2.0 : 0.0);
    if (path == TrackPath::rotation) {
      const double angle = 2.0 * std::sin(t), axis[3] = {0.6, 0.8 * std::cos(t), 0.8 * std::sin(t)};
      const double length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
      for (double a : axis) s.values.push_back(float(a / length * std::sin(angle / 2)));
      s.values.push_back(float(std::cos(angle / 2)));
      continue;
    }
    for (int c = 0; c < components; ++c)
      s.values.push_back(float((path == TrackPath::scale ? 1.0 : 0.0) + 0.5 * std::sin(t * (1 + c) + c)));
  }
  return s;
}

struct Seed {
  const char* name;
  TrackSet tracks;
  std::vector<double> steps;
  TrackEncoderChoices choices;
};

std::vector<Seed> seeds() {
  const std::vector<float> even = even_times(30, 1.0), uneven = uneven_times(20), three = even_times(3, 0.5);
  std::vector<Seed> list;
  TrackSet all;
  all.times = {even, uneven, {1.5f}, {0.0f, 2.0f}};
  all.samplers = {
      sampler(TrackPath::translation, 3, 0, even, false),   sampler(TrackPath::rotation, 4, 0, even, false),
      sampler(TrackPath::scale, 3, 1, uneven, false),       sampler(TrackPath::weights, 5, 1, uneven, false),
      sampler(TrackPath::translation, 3, 2, {1.5f}, false), sampler(TrackPath::rotation, 4, 3, {0.0f, 2.0f}, false)};
  const std::vector<double> all_steps = {1e-3, 1e-4, 1e-3, 1.0 / 256, 1e-2, 1e-3};
  list.push_back({"every_path", all, all_steps, {}});
  TrackEncoderChoices order1, order2, four;
  order1.order = 1;
  order2.order = 2;
  four.rotation_all_components = true;
  list.push_back({"every_path_order_1", all, all_steps, order1});
  list.push_back({"every_path_order_2", all, all_steps, order2});
  list.push_back({"every_path_four_rotation_components", all, all_steps, four});
  TrackSet jumps;
  jumps.times = {uneven, three};
  jumps.samplers = {sampler(TrackPath::rotation, 4, 0, uneven, true), sampler(TrackPath::weights, 1, 1, three, true),
                    sampler(TrackPath::translation, 3, 0, uneven, true)};
  list.push_back({"jumps_coarse", jumps, {0.05, 0.1, 0.5}, {}});
  list.push_back({"jumps_fine", jumps, {1e-6, 1e-5, 1e-6}, {}});
  TrackSet times_only;
  times_only.times = {even_times(256, 10.0), uneven_times(256), {0.0f}};
  list.push_back({"times_only", times_only, {}, {}});
  return list;
}

}  // namespace
}  // namespace segmorph::fuzz

int main(int argc, char** argv) {
  using namespace segmorph;
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_track_seeds OUTPUT_DIRECTORY\n");
    return 2;
  }
  const std::filesystem::path directory = argv[1];
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) {
    std::fprintf(stderr, "fuzz_track_seeds: %s: cannot create: %s\n", argv[1], error.message().c_str());
    return 1;
  }
  for (const fuzz::Seed& seed : fuzz::seeds()) {
    const TrackLayout layout = track_layout(seed.tracks);
    std::vector<uint8_t> stream;
    TrackSet encoded, decoded;
    Status status = fuzz::fits_track_layout_bytes(layout)
                        ? encode_tracks_with(seed.tracks, seed.steps, seed.choices, stream, encoded)
                        : Status(StatusCode::invalid_argument, "its layout does not fit the fuzzer's layout bytes");
    if (status.ok()) status = decode_tracks(stream.data(), stream.size(), layout, decoded);
    if (status.ok())
      for (size_t s = 0; s < decoded.samplers.size(); ++s)
        if (std::memcmp(decoded.samplers[s].values.data(), encoded.samplers[s].values.data(),
                        decoded.samplers[s].values.size() * sizeof(float)) != 0)
          status = Status(StatusCode::bad_data, "decodes to other values than the encoder's");
    if (!status.ok()) {
      std::fprintf(stderr, "fuzz_track_seeds: %s: %s\n", seed.name, status.message().c_str());
      return 1;
    }
    std::vector<uint8_t> bytes = fuzz::track_layout_bytes(layout);
    bytes.insert(bytes.end(), stream.begin(), stream.end());
    const std::filesystem::path path = directory / (std::string(seed.name) + ".sgmt");
    std::ofstream file(path, std::ios::binary);
    file.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    if (!file.flush()) {
      std::fprintf(stderr, "fuzz_track_seeds: %s: cannot write\n", path.c_str());
      return 1;
    }
  }
  return 0;
}
