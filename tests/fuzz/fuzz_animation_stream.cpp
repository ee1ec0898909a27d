// libFuzzer target: decode_animation on arbitrary bytes, against the fixed base mesh of fuzz_base_mesh.h (the one
// the seed streams of fuzz_seeds.cpp are encoded against). Besides the sanitizers' checks it asserts the decoder's
// promises: a refusal is one line, and a stream it accepts gives finite positions for every vertex of every frame.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "decode/frame_decoder.h"
#include "fuzz_base_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace segmorph;
  static const fuzz::BaseMesh mesh = fuzz::base_mesh();
  std::vector<FrameSequence> clips;
  const Status status = decode_animation(data, size, mesh.positions, mesh.triangles, clips);
  if (!status.ok()) {
    if (status.message().empty() || status.message().find('\n') != std::string::npos) std::abort();
    return 0;
  }
  if (clips.empty()) std::abort();
  for (const FrameSequence& clip : clips) {
    if (clip.vertex_count != mesh.vertex_count() || clip.frame_count == 0 ||
        clip.positions.size() != clip.frame_count * clip.vertex_count * 3)
      std::abort();
    for (float x : clip.positions)
      if (!std::isfinite(x)) std::abort();
  }
  return 0;
}
