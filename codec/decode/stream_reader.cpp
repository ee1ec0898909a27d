#include "decode/stream_reader.h"

#include <algorithm>
#include <cassert>
#include <cstring>

#include "common/float_bits.h"
#include "common/range_coder.h"
#include "common/stream_format.h"
#include "common/stream_syntax.h"
#include "decode/residual_decoder.h"
#include "decode/table_residual_decoder.h"

namespace segmorph {

using namespace stream_code;

namespace {

// The walk's coder for reading (common/stream_syntax.h): overwrites the value with the one it reads and checks it,
// and grows the content's arrays only as the data proves to be there.
struct HeadReader {
  static constexpr bool kReading = true;
  RangeDecoder& coder;
  void count(UnsignedModel& model, uint32_t& value) { value = model.decode(coder); }
  void bit(BitModel& model, uint32_t& value) { value = coder.decode_bit(model); }
  void tree(BitTreeModel& model, uint32_t& value) { value = model.decode(coder); }
  void integer(SignedModel& model, int32_t& value) { value = model.decode(coder); }
  void integers(SignedModel& model, int32_t* values, size_t count) { model.decode_run(coder, values, count); }
  void float_bits(float& value) { value = bits_float(coder.decode_direct_bits(32)); }
  template <typename T>
  void grow(std::vector<T>& values, size_t size) {
    values.resize(size);
  }
  bool failed() const { return coder.failed(); }
  Status status() const { return coder.finish(); }
};

}  // namespace

StreamReader::StreamReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}

StreamReader::~StreamReader() = default;

Status StreamReader::read_head(const std::vector<float>& base, StreamContent& content) {
  const uint8_t* data = data_;
  const size_t size = size_;
  content = StreamContent();
  content_ = &content;
  if (size < format::kHeaderBytes || std::memcmp(data, format::kMagic, 4) != 0)
    return Status(StatusCode::bad_data, "not a segmorph animation stream (bad magic)");
  const uint8_t version = data[4];
  if (version < format::kOldestVersion || version > format::kNewestVersion)
    return Status(StatusCode::unsupported, "animation stream version " + std::to_string(version) +
                                               " (this decoder reads versions " + std::to_string(format::kOldestVersion) +
                                               " to " + std::to_string(format::kNewestVersion) + ")");
  content.flags = data[5];
  content.transform = version == format::kTransformVersion;
  const uint8_t known = version == format::kAdaptiveVersion    ? format::kKnownFlags
                        : version == format::kTableVersion     ? format::kKnownTableVersionFlags
                        : version == format::kReferenceVersion ? format::kKnownReferenceVersionFlags
                                                               : format::kKnownTransformVersionFlags;
  if (content.transform && (content.flags & format::kResidualLoopFlags))
    return Status(StatusCode::bad_data, "animation stream: residual loop flags in a version 4 stream");
  if (content.flags & ~known) return Status(StatusCode::bad_data, "animation stream has unknown flags");
  const bool table = content.flags & format::kFlagTableResiduals;
  if (table && (content.flags & format::kFlagLossless))
    return Status(StatusCode::bad_data, "animation stream: the table residual code in a lossless stream");
  if (!content.transform && (content.flags & format::kFlagFrameReferences) &&
      !(content.flags & format::kFlagTemporalResiduals))
    return Status(StatusCode::bad_data, "animation stream: frame references without temporal residuals");
  if ((content.flags & format::kFlagLinearMotion) && !(content.flags & format::kFlagMotionContexts))
    return Status(StatusCode::bad_data, "animation stream: linear motion without motion contexts");
  const uint32_t length =
      uint32_t(data[6]) | uint32_t(data[7]) << 8 | uint32_t(data[8]) << 16 | uint32_t(data[9]) << 24;
  // With the table code the rANS words follow the body: an even number of bytes, at least the states' 8.
  const size_t available = size - format::kHeaderBytes;
  if (table ? length > available || available - length < table_code::kMinSymbolBytes || (available - length) % 2 != 0
            : length != available)
    return Status(StatusCode::bad_data, length > available ? "animation stream is truncated"
                                        : table ? "animation stream: bad length of the residual symbols after the body"
                                                : "animation stream has trailing bytes");
  body_size_ = length;
  decoder_ = std::make_unique<RangeDecoder>(data + format::kHeaderBytes, length);
  RangeDecoder& decoder = *decoder_;
  Models models;
  HeadReader reader{decoder};
  SEGMORPH_RETURN_IF_ERROR(code_head(reader, models, base, content));
  if (content.transform) {  // the whole body: the frames need nothing more from the stream
    if (uint64_t(content.welded_count) * content.frame_count() >
        (uint64_t(length) + 4) * format::kMaxVertexFramesPerByte)
      return corrupt("more vertex-frames than a version 4 stream of its length may claim");
    SEGMORPH_RETURN_IF_ERROR(code_transform(reader, models, content));
    return decoder.finish();
  }
  SEGMORPH_RETURN_IF_ERROR(code_residual_steps(reader, content));
  const bool lossless = content.flags & format::kFlagLossless;
  if (table) {
    const size_t start = format::kHeaderBytes + body_size_;
    table_residuals_ = std::make_unique<TableResidualDecoder>(content.welded_count, data + start, size - start);
    return table_residuals_->read_tables(decoder);
  }
  residuals_ = std::make_unique<ResidualDecoder>(content.welded_count, lossless);
  return Status::Ok();
}

Status StreamReader::read_frame(int64_t* row) {
  if (content_->transform) return Status::Ok();  // no residual symbols: read_head read the whole body
  assert(residuals_ || table_residuals_);
  if (table_residuals_) {
    table_residuals_->decode_frame(*decoder_, row);
    if (decoder_->failed()) return decoder_->finish();
    return table_residuals_->failed() ? table_residuals_->finish() : Status::Ok();
  }
  residuals_->decode_frame(*decoder_, row);
  // Garbage decodes as fast as a stream: stop at the first sign of it.
  if (decoder_->failed()) return decoder_->finish();
  // Lossless residuals are differences of ordered_bits values (all in [−2^31, 2^31)), so within ±(2^32 − 1); the
  // coder's escapes carry any 64-bit value, which the reconstruction would overflow adding it to a pattern.
  if (content_->flags & format::kFlagLossless)
    for (size_t i = 0; i < size_t(content_->welded_count) * 3; ++i)
      if (row[i] < -format::kMaxLosslessResidual || row[i] > format::kMaxLosslessResidual)
        return Status(StatusCode::bad_data, "animation stream: lossless residual out of range");
  return Status::Ok();
}

size_t StreamReader::frame_bound() const {
  assert(decoder_ && content_ && content_->welded_count > 0);
  // In 64 bits: a size_t of 32 bits would wrap for streams of a few megabytes.
  uint64_t vertex_frames;
  // Version 4: read_head read every symbol, and checked W × F against the body's length (kMaxVertexFramesPerByte).
  if (content_->transform) return content_->frame_count();
  if (table_residuals_) {
    vertex_frames = uint64_t(size_ - format::kHeaderBytes - body_size_) * table_code::kVertexFramesPerByte;
  } else {
    const size_t remaining = body_size_ - std::min(decoder_->position(), body_size_);
    vertex_frames = (uint64_t(remaining) + kImplicitTailBytes + 1) * 364;
  }
  return size_t(std::min<uint64_t>(vertex_frames / content_->welded_count + 1, SIZE_MAX));
}

struct StreamReader::Checkpoint {
  RangeDecoder::State range;
  std::unique_ptr<ResidualDecoder> residuals;  // a copy; or, with the table code:
  TableResidualDecoder::Position table;
  size_t bytes = 0;
};

void StreamReader::CheckpointDeleter::operator()(Checkpoint* checkpoint) const { delete checkpoint; }

StreamReader::CheckpointPointer StreamReader::checkpoint() const {
  assert(decoder_ && (residuals_ || table_residuals_ || content_->transform));
  CheckpointPointer checkpoint(new Checkpoint);
  checkpoint->range = decoder_->state();
  if (content_->transform) {  // nothing moves after the head
    checkpoint->bytes = sizeof(Checkpoint);
  } else if (table_residuals_) {
    checkpoint->table = table_residuals_->position();
    checkpoint->bytes = sizeof(Checkpoint) + checkpoint->table.history.size();
  } else {
    checkpoint->residuals = std::make_unique<ResidualDecoder>(*residuals_);
    checkpoint->bytes = sizeof(Checkpoint) + residuals_->state_bytes();
  }
  return checkpoint;
}

void StreamReader::restore(const Checkpoint& checkpoint) {
  assert(decoder_ && (residuals_ || table_residuals_ || content_->transform));
  decoder_->restore(checkpoint.range);
  if (content_->transform)
    return;
  else if (table_residuals_)
    table_residuals_->restore(checkpoint.table);
  else
    residuals_ = std::make_unique<ResidualDecoder>(*checkpoint.residuals);
}

size_t StreamReader::checkpoint_bytes(const Checkpoint& checkpoint) { return checkpoint.bytes; }

size_t frames_to_reserve(size_t frames, size_t bound, size_t frame_bytes) {
  constexpr size_t kMaxReservedBytes = size_t(64) << 20;
  return std::min({frames, bound, kMaxReservedBytes / std::max<size_t>(frame_bytes, 1)});
}

Status StreamReader::finish() const {
  assert(decoder_);
  SEGMORPH_RETURN_IF_ERROR(decoder_->finish());
  return table_residuals_ ? table_residuals_->finish() : Status::Ok();
}

Status read_stream(const uint8_t* data, size_t size, const std::vector<float>& base, StreamContent& content) {
  StreamReader reader(data, size);
  SEGMORPH_RETURN_IF_ERROR(reader.read_head(base, content));
  // The residuals grow a frame at a time as the data proves to be there (a few bytes of stream can claim
  // gigabytes of frames).
  if (content.transform) return reader.finish();
  const size_t row = size_t(content.welded_count) * 3, frames = content.frame_count();
  content.residuals.reserve(frames_to_reserve(frames, reader.frame_bound(), row * sizeof(int64_t)) * row);
  for (size_t f = 0; f < frames; ++f) {
    content.residuals.resize((f + 1) * row);
    SEGMORPH_RETURN_IF_ERROR(reader.read_frame(&content.residuals[f * row]));
  }
  return reader.finish();
}

}  // namespace segmorph
