// The content of a segmorph animation stream, and its entropy coding (range_coder.h). What the symbols mean
// and how the decoder turns them into frames is reconstruction.h; the byte layout is spec/'s appendix.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "segmorph/status.h"

namespace segmorph {

class RangeDecoder;
class ResidualDecoder;
class TableResidualDecoder;

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

// Byte offsets of the parts of an encoded stream, for reports.
struct StreamSizes {
  size_t motion = 0;  // header, welding, labels, motion, weights
  size_t residuals = 0;
};

// Appends the encoded stream to `out`. base: V × 3, as for read_stream (the welding groups come from it).
void write_stream(const StreamContent& content, const std::vector<float>& base, std::vector<uint8_t>& out,
                  StreamSizes* sizes = nullptr);

// The same for a content that may break a rule of the format, as tests of readers need: the symbols up to and
// including the first that breaks a rule the walk checks, then the body's end; returns that rule (ok if none broke).
// write_stream asserts that none does.
Status write_stream_until_invalid(const StreamContent& content, const std::vector<float>& base,
                                  std::vector<uint8_t>& out, StreamSizes* sizes = nullptr);

// Parses a stream whose decoder-side facts are `base` (V × 3 floats): V must match, welding groups come from
// it. Every count is checked against format limits and the data before anything is sized by it.
Status read_stream(const uint8_t* data, size_t size, const std::vector<float>& base, StreamContent& content);

// How many of `frames` frames of `frame_bytes` bytes each a decoder reserves memory for before decoding them
// (growing a frame at a time copies the frames decoded so far at every reallocation): no more than `bound`, as
// many as the data can hold (StreamReader::frame_bound), and at most 64 MiB, because welding lets a short valid
// stream fill many vertices and a damaged one must not allocate gigabytes up front.
size_t frames_to_reserve(size_t frames, size_t bound, size_t frame_bytes);

// read_stream in steps, for a decoder that turns each frame's residuals into positions as they come (in cache, and
// without holding F × W × 3 symbols): read_head() parses everything before the residuals into `content` (which
// must outlive the reader; content.residuals stays empty), read_frame() the next frame's W × 3 residual symbols,
// finish() checks that the stream ends after the last. Each step fails with bad_data as soon as the data is known
// to be bad; then the reader must not be used further.
class StreamReader {
 public:
  StreamReader(const uint8_t* data, size_t size);
  ~StreamReader();
  StreamReader(const StreamReader&) = delete;
  StreamReader& operator=(const StreamReader&) = delete;

  Status read_head(const std::vector<float>& base, StreamContent& content);
  Status read_frame(int64_t* row);
  Status finish() const;

  // After read_head(): the most frames the stream's remaining bytes can hold. Every welded vertex-frame costs
  // at least one binary decision of probability at most 2017/2048 (0.022 bits), so a byte holds at most 364; in
  // the table code a symbol of frequency at most 4032/4096 (table_code::kVertexFramesPerByte per byte).
  // frames_to_reserve() turns it into memory reserved up front.
  size_t frame_bound() const;

  // The reader between two frames, after read_head(): the coders' states, the adaptive models and the residual
  // history, enough to read on from that frame later (restore()). About 3 bytes per welded vertex (1 with the table
  // code) and a few kilobytes.
  struct Checkpoint;
  struct CheckpointDeleter {
    void operator()(Checkpoint* checkpoint) const;
  };
  using CheckpointPointer = std::unique_ptr<Checkpoint, CheckpointDeleter>;
  CheckpointPointer checkpoint() const;
  void restore(const Checkpoint& checkpoint);
  static size_t checkpoint_bytes(const Checkpoint& checkpoint);

 private:
  const uint8_t* data_;
  size_t size_;
  const StreamContent* content_ = nullptr;
  std::unique_ptr<RangeDecoder> decoder_;
  std::unique_ptr<ResidualDecoder> residuals_;
  std::unique_ptr<TableResidualDecoder> table_residuals_;  // instead of residuals_, with kFlagTableResiduals
  size_t body_size_ = 0;                                   // the range-coded body's bytes
};

// Groups of vertices with bit-identical base positions, in order of their first vertex; each group lists its
// vertices ascending. Singletons are included.
std::vector<std::vector<uint32_t>> identical_position_groups(const std::vector<float>& base);

// Order-preserving map between floats and integers (for lossless residuals): a < b as floats (with −0 < +0)
// exactly when ordered(a) < ordered(b).
int64_t ordered_bits(float x);
float from_ordered_bits(int64_t value);

}  // namespace segmorph
