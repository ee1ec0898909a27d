#include "encode/stream_writer.h"

#include <algorithm>
#include <cassert>

#include "common/float_bits.h"
#include "common/range_coder.h"
#include "common/stream_format.h"
#include "common/stream_syntax.h"
#include "encode/residual_encoder.h"
#include "encode/table_residual_encoder.h"

namespace segmorph {

using namespace stream_code;

namespace {

// The walk's coder for writing (common/stream_syntax.h): codes the value it is given.
struct HeadWriter {
  static constexpr bool kReading = false;
  RangeEncoder& coder;
  void count(UnsignedModel& model, uint32_t& value) { model.encode(coder, value); }
  void bit(BitModel& model, uint32_t& value) { coder.encode_bit(model, value); }
  void tree(BitTreeModel& model, uint32_t& value) { model.encode(coder, value); }
  void integer(SignedModel& model, int32_t& value) { model.encode(coder, value); }
  void integers(SignedModel& model, int32_t* values, size_t count) {
    for (size_t i = 0; i < count; ++i) model.encode(coder, values[i]);
  }
  void float_bits(float& value) { coder.encode_direct_bits(segmorph::float_bits(value), 32); }
  template <typename T>
  void grow(std::vector<T>& values, size_t size) {
    assert(values.size() >= size);  // the writer's content is complete
    (void)values, (void)size;
  }
  bool failed() const { return false; }
  Status status() const { return Status::Ok(); }
};

}  // namespace

Status write_stream_until_invalid(const StreamContent& content, const std::vector<float>& base,
                                  std::vector<uint8_t>& out, StreamSizes* sizes) {
  const size_t start = out.size();
  out.insert(out.end(), std::begin(format::kMagic), std::end(format::kMagic));
  const bool table = content.flags & format::kFlagTableResiduals;
  [[maybe_unused]] const bool references = content.flags & format::kFlagFrameReferences;
  assert(!references || content.references.size() == content.frame_count());
  const bool version_3 = content.flags & (format::kFlagFrameReferences | format::kFlagMotionContexts |
                                          format::kFlagLinearMotion | format::kFlagWeightContexts);
  assert(!content.transform || !(content.flags & format::kResidualLoopFlags));
  out.push_back(content.transform ? format::kTransformVersion
                : version_3       ? format::kReferenceVersion
                : table           ? format::kTableVersion
                                  : format::kAdaptiveVersion);
  out.push_back(content.flags);
  const size_t length_at = out.size();
  out.insert(out.end(), 4, 0);  // body length, filled in at the end
  RangeEncoder encoder(out);
  Models models;
  HeadWriter writer{encoder};
  size_t motion_end = 0;
  // Ends the body, appends what follows it (the table code's words) and reports the sizes.
  auto end_stream = [&](const std::vector<uint8_t>& after) {
    encoder.finish();
    const uint32_t length = uint32_t(out.size() - length_at - 4);
    for (int i = 0; i < 4; ++i) out[length_at + size_t(i)] = uint8_t(length >> (8 * i));
    out.insert(out.end(), after.begin(), after.end());
    if (sizes) {
      sizes->motion = motion_end - start;
      sizes->residuals = out.size() - motion_end;
    }
  };
  // The walk takes the content by reference for the reader's sake; the writer never writes to it.
  StreamContent& fields = const_cast<StreamContent&>(content);
  Status status = code_head(writer, models, base, fields);
  motion_end = out.size();
  if (status.ok() && content.transform) status = code_transform(writer, models, fields);
  if (status.ok() && !content.transform) status = code_residual_steps(writer, fields);
  if (!status.ok() || content.transform) {
    end_stream({});
    return status;
  }

  const bool lossless = content.flags & format::kFlagLossless;
  assert(!(table && lossless));
  // The table code's tables and initial states are written even without residuals (the encoder measures such
  // streams for the size of everything but the residuals); the adaptive code writes nothing then.
  std::vector<uint8_t> symbols;  // the table code's rANS words, after the body
  const bool narrow = !content.narrow_residuals.empty();
  assert(!(narrow && (lossless || !content.residuals.empty())));
  if (table && narrow)
    encode_table_residuals(encoder, content.narrow_residuals, std::max<size_t>(content.welded_count, 1), symbols);
  else if (table)
    encode_table_residuals(encoder, content.residuals, std::max<size_t>(content.welded_count, 1), symbols);
  else if (narrow)
    encode_residuals(encoder, content.narrow_residuals, content.welded_count, lossless);
  else if (!content.residuals.empty())
    encode_residuals(encoder, content.residuals, content.welded_count, lossless);
  end_stream(symbols);
  return Status::Ok();
}

void write_stream(const StreamContent& content, const std::vector<float>& base, std::vector<uint8_t>& out,
                  StreamSizes* sizes) {
  [[maybe_unused]] const Status status = write_stream_until_invalid(content, base, out, sizes);
  assert(status.ok());
}

}  // namespace segmorph
