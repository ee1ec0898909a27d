// decode_animation: the stream's content, then frame by frame the prediction and the residual loop, each frame
// written straight into the clips' original vertex order.
#include <algorithm>
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
  return reconstruct_clips(content, base, triangles, clips);
}

Status reconstruct_clips(const StreamContent& content, const std::vector<float>& base,
                         const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips) {
  const std::vector<float> welded = welded_base(base, content);
  const AffineMotion motion = dequantized_motion(content, welded);
  const ClusterWeights weights = dequantized_weights(content);
  const ResidualTraversal traversal = residual_traversal(content, triangles);
  ResidualReconstructor reconstructor(content, traversal);

  // One frame at a time, so that what the loop reads in traversal order (predictions, symbols) and writes
  // (welded positions) stays in cache.
  const size_t vertex_count = content.vertex_count, row = size_t(content.welded_count) * 3;
  std::vector<double> predictions(row);
  std::vector<int64_t> symbols(row);
  std::vector<float> frame_out(row);
  clips.assign(content.clip_frames.size(), FrameSequence());
  size_t frame = 0;
  for (size_t c = 0; c < clips.size(); ++c) {
    FrameSequence& clip = clips[c];
    clip.vertex_count = vertex_count;
    clip.frame_count = content.clip_frames[c];
    clip.positions.resize(clip.frame_count * vertex_count * 3);
    reconstructor.start_clip();
    for (size_t f = 0; f < clip.frame_count; ++f, ++frame) {
      predict_frame(welded.data(), motion, weights, frame, predictions.data());
      std::copy_n(content.residuals.begin() + ptrdiff_t(frame * row), row, symbols.begin());
      reconstructor.frame(
          predictions.data(), [&](size_t i, double, double) { return symbols[i]; },
          [&](size_t i, float x) { frame_out[i] = x; });
      for (float x : frame_out)
        if (!std::isfinite(x))
          return Status(StatusCode::bad_data, "animation stream decodes to NaN or infinite positions");
      float* out = &clip.positions[f * vertex_count * 3];
      for (size_t v = 0; v < vertex_count; ++v) {
        const float* in = &frame_out[size_t(content.welded_index[v]) * 3];
        out[v * 3] = in[0], out[v * 3 + 1] = in[1], out[v * 3 + 2] = in[2];
      }
    }
  }
  return Status::Ok();
}

}  // namespace segmorph
