// decode_animation: the stream's content, then frame by frame the prediction and the residual loop, each frame
// written straight into the clips' original vertex order.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>

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

// Whether no float of x[0 .. count) is infinite or NaN (exponent bits all ones), four at a time (GCC's and Clang's
// vector extension: GCC 12 left the scalar loop with its float comparisons unvectorized, at the Release build's -O3).
bool all_finite(const float* x, size_t count) {
  typedef uint32_t Uint4 __attribute__((vector_size(16)));
  constexpr uint32_t kExponent = 0x7f800000u;
  Uint4 infinite = {0, 0, 0, 0};
  size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    Uint4 bits;
    std::memcpy(&bits, x + i, sizeof(bits));
    infinite |= (bits & kExponent) == kExponent;  // all ones in a lane that is
  }
  bool finite = (infinite[0] | infinite[1] | infinite[2] | infinite[3]) == 0;
  for (; i < count; ++i) finite = finite && std::isfinite(x[i]);
  return finite;
}

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
  // Slot s, reconstructed, appended to its clip in the original vertex order: run by run, a run being vertices
  // v, v + 1, ... whose welded vertices are w, w + 1, ... (usually few and long), so that the frame is copied
  // without a gather or a zero-filling resize.
  struct Run {
    size_t welded, count;
  };
  std::vector<Run> runs;
  bool long_runs = true;  // else vertex by vertex
  for (size_t v = 0; v < vertex_count && long_runs; ++v) {
    const size_t w = content.welded_index[v];
    if (!runs.empty() && runs.back().welded + runs.back().count == w)
      ++runs.back().count;
    else
      runs.push_back({w, 1});
    long_runs = runs.size() * 8 <= vertex_count;
  }
  if (!long_runs) runs.clear();
  auto finish = [&](size_t s, FrameSequence& clip) {
    const float* frame = &welded_frames[s * row];
    if (!all_finite(frame, row)) return false;
    if (long_runs) {
      for (const Run& run : runs)
        clip.positions.insert(clip.positions.end(), frame + run.welded * 3, frame + (run.welded + run.count) * 3);
      return true;
    }
    const size_t at = clip.positions.size();
    clip.positions.resize(at + vertex_count * 3);
    for (size_t v = 0; v < vertex_count; ++v) {
      const float* in = &frame[size_t(content.welded_index[v]) * 3];
      float* out = &clip.positions[at + v * 3];
      out[0] = in[0], out[1] = in[1], out[2] = in[2];
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
        if (!finish(s, clip))
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
