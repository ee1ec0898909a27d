// The content of a segmorph animation stream, which the reader (decode/stream_reader.h) and the writer
// (encode/stream_writer.h) code with the range coder (range_coder.h). What the symbols mean and how the decoder turns
// them into frames is reconstruction.h; the byte layout is spec/'s appendix.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace segmorph {

struct StreamContent {
  uint8_t flags = 0;          // format::kFlag*
  uint32_t vertex_count = 0;  // V, must equal the base mesh's
  // Welding: vertices with bit-identical base positions form groups (the decoder finds them itself); a group
  // is usually one welded vertex, else its partition is coded. welded_index: V, numbered in order of first
  // vertex; welded_count: W.
  std::vector<uint32_t> welded_index;
  uint32_t welded_count = 0;
  std::vector<uint32_t> clip_frames;  // frames per clip; F = their sum
  // Version 3 (kFlagFrameReferences): per frame, how many frames back in its clip the frame its motion and
  // residuals are predicted from lies (0: none, the residuals are predicted from zero), at most reference_window
  // and the frame's index in its clip. Without the flag both are unused (frame_reference() gives the references
  // versions 1 and 2 imply).
  uint32_t reference_window = 0;
  std::vector<uint32_t> references;
  uint32_t cluster_count = 0;         // K
  std::vector<uint32_t> labels;       // W: cluster of each welded vertex
  // Motion: per frame and cluster, 12 integers: the 9 entries of L − I in units of linear_step, then the 3 of
  // t − c (c the cluster's base centroid) in units of translation_step. F × K × 12.
  float linear_step = 0, translation_step = 0;
  std::vector<int32_t> motion;
  // Weights: per welded vertex, extra clusters blended in with weights value · 2^-weight_bits; the own
  // cluster takes the rest of 1.
  int weight_bits = 0;
  std::vector<uint32_t> weight_offset;  // W + 1
  std::vector<uint32_t> weight_cluster;
  std::vector<int32_t> weight_value;
  // Residuals: F × W × 3 symbols. Lossy: quantizer indices with steps residual_step[axis]. Lossless:
  // differences of order-preserving float bit patterns.
  float residual_step[3] = {0, 0, 0};
  std::vector<int64_t> residuals;
  // The same symbols of a lossy stream in half the memory, instead of `residuals` (the encoder's: lossy indices lie
  // in (INT32_MIN, INT32_MAX]). write_stream codes whichever is not empty; read_stream fills `residuals`.
  std::vector<int32_t> narrow_residuals;

  // Version 4 (`transform`): the residuals as temporal bases and coefficients instead (spec/bitstream.md, 5.9;
  // the residual fields above are then unused). A basis's vector i has entry f = entries[i × F + f] × step[i].
  bool transform = false;
  struct Basis {
    std::vector<float> step;
    std::vector<int32_t> entries;
    size_t size() const { return step.size(); }
  };
  Basis stream_basis;
  std::vector<uint32_t> basis_source;   // K: format::kBasis*
  std::vector<uint32_t> basis_size;     // K: m, the vectors of its basis the cluster uses (0 with kBasisNone)
  std::vector<float> coefficient_step;  // K: the cluster's coefficients are multiples of it
  std::vector<Basis> own_basis;         // K: with kBasisOwn, the cluster's m vectors
  // Per cluster with a basis, per vector i < m, per axis, per welded vertex of the cluster ascending: the
  // coefficient's index minus its prediction from earlier neighbours (transform_coefficients(), transform_residuals.h).
  std::vector<int32_t> coefficient_symbols;

  size_t frame_count() const;
};

// The reference distance of stream frame `frame`, which is frame `frame_in_clip` of its clip: content.references's
// with kFlagFrameReferences, else the previous frame's (1) with temporal residuals past a clip's first frame, else 0.
uint32_t frame_reference(const StreamContent& content, size_t frame, size_t frame_in_clip);

// The largest reference distance a decoder of the content holds frames for: reference_window with
// kFlagFrameReferences, else 1.
uint32_t reference_window(const StreamContent& content);

// Groups of vertices with bit-identical base positions, in order of their first vertex; each group lists its
// vertices ascending. Singletons are included.
std::vector<std::vector<uint32_t>> identical_position_groups(const std::vector<float>& base);

// Order-preserving map between floats and integers (for lossless residuals): a < b as floats (with −0 < +0)
// exactly when ordered(a) < ordered(b).
int64_t ordered_bits(float x);
float from_ordered_bits(int64_t value);

}  // namespace segmorph
