// What the trajectory bench tools start from: a file's first animated primitive encoded as codec_sequence
// --no-transform encodes it (against the stand-in base mesh), and the open-loop residuals of the stream it wrote:
// each welded vertex's frames minus the prediction of the stream's quantized motion and weights, one trajectory of
// F values per vertex and axis (needs segmorph_pipeline and Eigen).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "common/reconstruction.h"
#include "common/stream.h"
#include "decode/stream_reader.h"
#include "encode/encoder.h"
#include "sample_first_animated.h"
#include "stand_in_base.h"

namespace segmorph::bench {

using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct ResidualTrajectories {
  std::vector<FrameSequence> clips;
  std::vector<float> base;
  std::vector<uint8_t> stream;
  StreamReport report;
  StreamContent content;
  Matrix rows;  // W × 3 rows (welded vertex w's axis a is row w × 3 + a), F columns, in units of the axis's step
};

inline Status residual_trajectories(const char* path, const CodecSettings& settings, ResidualTrajectories& out) {
  SampledNode node;
  Status status = sample_first_animated(path, node);
  if (status.ok()) {
    out.clips = node.primitives[0].clips;
    out.base = stand_in_base(out.clips[0]);
    CodecSettings loop = settings;  // the residual loop's residuals are what the tools price (version 4 has none)
    loop.transform_residuals = false;
    status = encode_animation(out.clips, out.base, loop, out.stream, &out.report);
  }
  if (status.ok()) status = read_stream(out.stream.data(), out.stream.size(), out.base, out.content);
  if (!status.ok()) return status;
  const StreamContent& content = out.content;
  const size_t vertices = content.vertex_count, welded = content.welded_count;
  const std::vector<double> predicted = predicted_frames(content, welded_base(out.base, content));
  std::vector<uint32_t> first(welded, UINT32_MAX);
  for (uint32_t v = 0; v < vertices; ++v)
    if (first[content.welded_index[v]] == UINT32_MAX) first[content.welded_index[v]] = v;
  out.rows.resize(Eigen::Index(welded * 3), Eigen::Index(content.frame_count()));
  size_t frame = 0;
  for (const FrameSequence& clip : out.clips)
    for (size_t f = 0; f < clip.frame_count; ++f, ++frame)
      for (size_t w = 0; w < welded; ++w)
        for (size_t axis = 0; axis < 3; ++axis)
          out.rows(Eigen::Index(w * 3 + axis), Eigen::Index(frame)) =
              (double(clip.positions[(f * vertices + first[w]) * 3 + axis]) -
               predicted[(frame * welded + w) * 3 + axis]) /
              double(content.residual_step[axis]);
  return status;
}

}  // namespace segmorph::bench
