// decode_animation: the stream's content, then frame by frame the prediction and the residual loop, each frame
// written straight into the clips' original vertex order.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "codec.h"
#include "reconstruction.h"

namespace segmorph {

Status decode_animation(const uint8_t* data, size_t size, const std::vector<float>& base,
                        const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips) {
  if (base.size() % 3 != 0) return Status(StatusCode::invalid_argument, "base positions must be V × 3");
  for (uint32_t index : triangles)
    if (index >= base.size() / 3) return Status(StatusCode::invalid_argument, "a triangle names a missing vertex");
  StreamContent content;
  StreamReader reader(data, size);
  SEGMORPH_RETURN_IF_ERROR(reader.read_head(base, content));
  SEGMORPH_RETURN_IF_ERROR(reconstruct_clips(content, reader, base, triangles, clips));
  return reader.finish();
}

namespace {

// Frame `frame`'s W × 3 residual symbols into `row`.
using ResidualSource = std::function<Status(size_t frame, int64_t* row)>;

// frame_bound: how many frames the residuals can hold at most (frames_to_reserve).
Status reconstruct(const StreamContent& content, const ResidualSource& residuals, size_t frame_bound,
                   const std::vector<float>& base, const std::vector<uint32_t>& triangles,
                   std::vector<FrameSequence>& clips) {
  const std::vector<float> welded = welded_base(base, content);
  const AffineMotion motion = dequantized_motion(content, welded);
  const ClusterWeights weights = dequantized_weights(content);
  const ResidualTraversal traversal = residual_traversal(content, triangles);
  ResidualReconstructor reconstructor(content, traversal);
  const FramePredictor predictor(welded.data(), motion, weights);

  // Two frames at a time (ResidualReconstructor::two_frames), so that what the loop reads in traversal order
  // (predictions, symbols) and writes (welded positions) stays in cache.
  const size_t vertex_count = content.vertex_count, row = size_t(content.welded_count) * 3;
  std::vector<double> predictions(2 * row);
  std::vector<int64_t> symbols(2 * row);
  std::vector<float> welded_frames(2 * row);
  // Frame `frame` of the stream into slot s (0 or 1) of the buffers: prediction and symbols.
  auto prepare = [&](size_t frame, size_t s) {
    predictor.predict(frame, &predictions[s * row]);
    return residuals(frame, &symbols[s * row]);
  };
  auto symbol = [&](size_t s) {
    const int64_t* from = &symbols[s * row];
    return [from](size_t i, double, double) { return from[i]; };
  };
  auto output = [&](size_t s) {
    float* to = &welded_frames[s * row];
    return [to](size_t i, float x) { to[i] = x; };
  };
  // Slot s, reconstructed, into frame f of the clip in the original vertex order.
  auto finish = [&](size_t s, FrameSequence& clip, size_t f) {
    const float* frame = &welded_frames[s * row];
    bool finite = true;  // no early exit, so that the loop vectorizes
    for (size_t i = 0; i < row; ++i) finite &= std::fabs(frame[i]) <= std::numeric_limits<float>::max();
    if (!finite) return false;
    clip.positions.resize((f + 1) * vertex_count * 3);
    float* out = &clip.positions[f * vertex_count * 3];
    for (size_t v = 0; v < vertex_count; ++v) {
      const float* in = &frame[size_t(content.welded_index[v]) * 3];
      out[v * 3] = in[0], out[v * 3 + 1] = in[1], out[v * 3 + 2] = in[2];
    }
    return true;
  };
  clips.assign(content.clip_frames.size(), FrameSequence());
  size_t frame = 0;  // in the stream
  for (size_t c = 0; c < clips.size(); ++c) {
    FrameSequence& clip = clips[c];
    clip.vertex_count = vertex_count;
    clip.frame_count = content.clip_frames[c];
    // The frames grow as they are decoded, never sized by the counts alone: a stream of a few bytes can claim
    // format::kMaxVertexFrames positions (gigabytes), and its data runs out long before memory would.
    const size_t frame_floats = vertex_count * 3;
    clip.positions.reserve(
        frames_to_reserve(clip.frame_count, frame_bound - std::min(frame, frame_bound), frame_floats * sizeof(float)) *
        frame_floats);
    reconstructor.start_clip();
    for (size_t f = 0; f < clip.frame_count;) {
      const size_t count = std::min<size_t>(2, clip.frame_count - f);
      for (size_t s = 0; s < count; ++s) SEGMORPH_RETURN_IF_ERROR(prepare(frame + s, s));
      if (count == 2)
        reconstructor.two_frames(&predictions[0], symbol(0), output(0), &predictions[row], symbol(1), output(1));
      else
        reconstructor.frame(&predictions[0], symbol(0), output(0));
      for (size_t s = 0; s < count; ++s)
        if (!finish(s, clip, f + s))
          return Status(StatusCode::bad_data, "animation stream decodes to NaN or infinite positions");
      f += count, frame += count;
    }
  }
  return Status::Ok();
}

}  // namespace

Status reconstruct_clips(const StreamContent& content, const std::vector<float>& base,
                         const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips) {
  const size_t row = size_t(content.welded_count) * 3;
  if (content.residuals.size() != content.frame_count() * row)
    return Status(StatusCode::invalid_argument, "stream content has the wrong number of residuals");
  auto copy = [&](size_t frame, int64_t* to) {
    std::copy_n(content.residuals.begin() + ptrdiff_t(frame * row), row, to);
    return Status::Ok();
  };
  return reconstruct(content, copy, content.frame_count(), base, triangles, clips);
}

Status reconstruct_clips(const StreamContent& content, StreamReader& reader, const std::vector<float>& base,
                         const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips) {
  return reconstruct(
      content, [&](size_t, int64_t* row) { return reader.read_frame(row); }, reader.frame_bound(), base, triangles,
      clips);
}

}  // namespace segmorph
