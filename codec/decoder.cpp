// decode_animation: the stream's content, the prediction, the residual loop.
#include <cmath>

#include "codec.h"
#include "reconstruction.h"

namespace segmorph {

Status decode_animation(const uint8_t* data, size_t size, const std::vector<float>& base,
                        const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips) {
  if (base.size() % 3 != 0) return Status(StatusCode::invalid_argument, "base positions must be V × 3");
  for (uint32_t index : triangles)
    if (index >= base.size() / 3) return Status(StatusCode::invalid_argument, "a triangle names a missing vertex");
  StreamContent content;
  SEGMORPH_RETURN_IF_ERROR(read_stream(data, size, base, content));
  const std::vector<float> welded = welded_base(base, content);
  const std::vector<float> frames =
      reconstruct_welded(content, residual_traversal(content, triangles), predicted_frames(content, welded));
  for (float x : frames)
    if (!std::isfinite(x)) return Status(StatusCode::bad_data, "animation stream decodes to NaN or infinite positions");

  const size_t vertex_count = content.vertex_count, row = size_t(content.welded_count) * 3;
  clips.assign(content.clip_frames.size(), FrameSequence());
  size_t frame = 0;
  for (size_t c = 0; c < clips.size(); ++c) {
    FrameSequence& clip = clips[c];
    clip.vertex_count = vertex_count;
    clip.frame_count = content.clip_frames[c];
    clip.positions.resize(clip.frame_count * vertex_count * 3);
    for (size_t f = 0; f < clip.frame_count; ++f, ++frame)
      for (size_t v = 0; v < vertex_count; ++v)
        for (int a = 0; a < 3; ++a)
          clip.positions[(f * vertex_count + v) * 3 + size_t(a)] = frames[frame * row + content.welded_index[v] * 3 + size_t(a)];
  }
  return Status::Ok();
}

}  // namespace segmorph
