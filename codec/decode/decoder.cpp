// The decoder: FrameLoop (prediction and the residual loop, each frame written straight into the base mesh's vertex
// order), FrameDecoder (a stream frame by frame, with checkpoints at clip starts), and decode_animation and
// reconstruct_clips on top of them.
#include "decode/frame_decoder.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>

#include "common/frame_sequence.h"
#include "common/stream_format.h"
#if !defined(__wasi__)  // WebAssembly (WASI) has no threads
#include "common/parallel.h"
#endif

namespace segmorph {
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

Status not_finite() { return Status(StatusCode::bad_data, "animation stream decodes to NaN or infinite positions"); }

// Checkpoints of clip starts take at most this much memory in all (FrameDecoder::seek).
constexpr size_t kMaxCheckpointBytes = size_t(64) << 20;

}  // namespace

FrameLoop::FrameLoop(const StreamContent& content, const std::vector<float>& base,
                     const std::vector<uint32_t>& triangles)
    : content_(content),
      welded_(welded_base(base, content)),
      motion_(content.transform ? dequantized_centroids(content, welded_) : dequantized_motion(content, welded_)),
      weights_(dequantized_weights(content)),
      traversal_(residual_traversal(content, triangles)),
      row_(size_t(content.welded_count) * 3),
      to_vertices_(content.welded_index) {
  if (!content.transform) {
    predictor_ = std::make_unique<FramePredictor>(welded_.data(), motion_, weights_);
    reconstructor_ = std::make_unique<ResidualReconstructor>(content, traversal_);
    predictions_.resize(2 * row_);
    symbols_.resize(2 * row_);
    welded_frames_.resize(2 * row_);
    return;
  }
  TransformCoefficients coefficients;
  status_ = transform_coefficients(content, traversal_, coefficients);
  if (!status_.ok()) return;
  transform_ = std::make_unique<TransformResiduals>(content, std::move(coefficients));
  blocks_ = std::make_unique<TransformBlocks>(content, *transform_, welded_.data(), motion_.centroid, weights_);
  welded_frames_.resize(TransformBlocks::kMaxFrames * row_);
}

void FrameLoop::start_clip() {
  if (reconstructor_) reconstructor_->start_clip();
}

Status FrameLoop::reconstruct(size_t frame, const Residuals& residuals, size_t count) {
  assert(count >= 1 && count <= block_frames());
  if (blocks_) {  // version 4: x = float(p + r), r the frame's residual from the coefficients
    blocks_->reconstruct(frame, count, welded_frames_.data());
    return all_finite(welded_frames_.data(), count * row_) ? Status::Ok() : not_finite();
  }
  for (size_t s = 0; s < count; ++s) {
    predictor_->predict(frame + s, &predictions_[s * row_]);
    SEGMORPH_RETURN_IF_ERROR(residuals(frame + s, &symbols_[s * row_]));
  }
  auto symbol = [&](size_t s) {
    const int64_t* from = &symbols_[s * row_];
    return [from](size_t i, double, double) { return from[i]; };
  };
  auto output = [&](size_t s) {
    float* to = &welded_frames_[s * row_];
    return [to](size_t i, float x) { to[i] = x; };
  };
  if (count == 2)
    reconstructor_->two_frames(frame, &predictions_[0], symbol(0), output(0), &predictions_[row_], symbol(1),
                               output(1));
  else
    reconstructor_->frame(frame, &predictions_[0], symbol(0), output(0));
  return all_finite(welded_frames_.data(), count * row_) ? Status::Ok() : not_finite();
}

Status FrameLoop::decode_independent(size_t frame, size_t count, float* out, float* welded_frames) const {
  assert(blocks_ && count >= 1 && count <= block_frames());
  blocks_->reconstruct(frame, count, welded_frames);
  if (!all_finite(welded_frames, count * row_)) return not_finite();
  const size_t floats = to_vertices_.vertex_count() * 3;
  for (size_t s = 0; s < count; ++s) to_vertices_.gather(welded_frames + s * row_, out + s * floats);
  return Status::Ok();
}

Status FrameLoop::decode(size_t frame, const Residuals& residuals, size_t count, float* out) {
  if (blocks_) return decode_independent(frame, count, out, welded_frames_.data());
  SEGMORPH_RETURN_IF_ERROR(reconstruct(frame, residuals, count));
  const size_t floats = to_vertices_.vertex_count() * 3;
  for (size_t s = 0; s < count; ++s) to_vertices_.gather(&welded_frames_[s * row_], out + s * floats);
  return Status::Ok();
}

Status FrameLoop::decode_append(size_t frame, const Residuals& residuals, size_t count, std::vector<float>& out) {
  SEGMORPH_RETURN_IF_ERROR(reconstruct(frame, residuals, count));
  for (size_t s = 0; s < count; ++s) to_vertices_.append(&welded_frames_[s * row_], out);
  return Status::Ok();
}

FrameDecoder::FrameDecoder() = default;
FrameDecoder::~FrameDecoder() = default;

Status FrameDecoder::open(const uint8_t* data, size_t size, const std::vector<float>& base,
                          const std::vector<uint32_t>& triangles) {
  loop_.reset();
  checkpoints_.clear();
  checkpoint_bytes_ = 0;
  clip_ = frame_in_clip_ = frame_ = 0;
  version_ = 0;
  failure_ = Status::Ok();
  reader_ = std::make_unique<StreamReader>(data, size);
  const Status status = reader_->read_head(base, content_);
  if (!status.ok()) {
    reader_.reset();
    return status;
  }
  version_ = data[4];
  frame_bound_ = reader_->frame_bound();
  // A caller sizes its frames by the counts: they must be ones the data can back.
  if (content_.frame_count() > frame_bound_) {
    reader_.reset();
    return Status(StatusCode::bad_data, "animation stream claims " + std::to_string(content_.frame_count()) +
                                            " frames, more than its " + std::to_string(size) + " bytes can hold");
  }
  loop_ = std::make_unique<FrameLoop>(content_, base, triangles);
  if (!loop_->status().ok()) {
    const Status failed = loop_->status();
    loop_.reset();
    reader_.reset();
    return failed;
  }
  StreamReader* reader = reader_.get();
  residuals_ = [reader](size_t, int64_t* row) { return reader->read_frame(row); };
  if (content_.transform) {
    std::vector<int32_t>().swap(content_.coefficient_symbols);  // the loop has made the coefficients from them
  } else {
    checkpoints_.resize(content_.clip_frames.size());
    take_checkpoint();
  }
  loop_->start_clip();
  return Status::Ok();
}

size_t FrameDecoder::frames_left_in_clip() const {
  return clip_ < content_.clip_frames.size() ? content_.clip_frames[clip_] - frame_in_clip_ : 0;
}

void FrameDecoder::take_checkpoint() {
  if (checkpoints_[clip_]) return;
  StreamReader::CheckpointPointer checkpoint = reader_->checkpoint();
  const size_t bytes = StreamReader::checkpoint_bytes(*checkpoint);
  // The first clip's is always kept: it is how the decoder goes back to the start.
  if (clip_ > 0 && checkpoint_bytes_ + bytes > kMaxCheckpointBytes) return;
  checkpoint_bytes_ += bytes;
  checkpoints_[clip_] = std::move(checkpoint);
}

Status FrameDecoder::check_frames(size_t count) const {
  assert(is_open());
  if (!failure_.ok()) return failure_;
  const size_t left = frames_left_in_clip();
  if (left == 0) return Status(StatusCode::invalid_argument, "the stream has no frame left to decode");
  if (count > left)
    return Status(StatusCode::invalid_argument, std::to_string(count) + " frames asked for where the clip has " +
                                                    std::to_string(left) + " left");
  return Status::Ok();
}

Status FrameDecoder::before_decode(size_t count) {
  SEGMORPH_RETURN_IF_ERROR(check_frames(count));
  if (count == 0 || count > loop_->block_frames())
    return Status(StatusCode::invalid_argument, "frames are decoded 1 to " + std::to_string(loop_->block_frames()) +
                                                    " at a time, not " + std::to_string(count));
  return Status::Ok();
}

// Advances past `count` decoded frames; at a clip's end, to the next clip (a checkpoint of its start), and at the
// stream's end, the check that the stream ends there.
Status FrameDecoder::after_decode(Status status, size_t count) {
  if (status.ok()) {
    frame_ += count;
    frame_in_clip_ += count;
    if (frame_in_clip_ == content_.clip_frames[clip_]) {
      ++clip_;
      frame_in_clip_ = 0;
      if (clip_ < content_.clip_frames.size()) {
        if (!content_.transform) take_checkpoint();
        loop_->start_clip();
      } else {
        status = reader_->finish();
      }
    }
  }
  if (!status.ok()) failure_ = status;
  return status;
}

Status FrameDecoder::decode(size_t count, float* out) {
  SEGMORPH_RETURN_IF_ERROR(before_decode(count));
  return after_decode(loop_->decode(frame_, residuals_, count, out), count);
}

Status FrameDecoder::decode_append(size_t count, std::vector<float>& out) {
  SEGMORPH_RETURN_IF_ERROR(before_decode(count));
  return after_decode(loop_->decode_append(frame_, residuals_, count, out), count);
}

Status FrameDecoder::decode_frames(size_t count, float* out, size_t threads) {
  assert(is_open());
  const size_t block = block_frames(), floats = size_t(content_.vertex_count) * 3;
#if !defined(__wasi__)  // WebAssembly (WASI) has no threads: the loop below
  const size_t blocks = (count + block - 1) / block;
  threads = std::min(thread_count(threads), blocks);
  if (threads > 1 && content_.transform) {
    SEGMORPH_RETURN_IF_ERROR(check_frames(count));
    // Version 4: the blocks in ranges, one a thread, each with its own room for the welded frames; the first failing
    // block's status (in frame order) is the result, as one thread would report it.
    std::vector<Status> failed(blocks);
    auto decode_blocks = [&](size_t begin, size_t end) {
      std::vector<float> welded(block * size_t(content_.welded_count) * 3);
      for (size_t b = begin; b < end; ++b) {
        const size_t f = b * block, n = std::min(count - f, block);
        failed[b] = loop_->decode_independent(frame_ + f, n, out + f * floats, welded.data());
        if (!failed[b].ok()) return;
      }
    };
    parallel_ranges(blocks, threads, decode_blocks);  // (ranges without a thread run on this one)
    Status status = Status::Ok();
    for (const Status& s : failed)
      if (!s.ok()) {
        status = s;
        break;
      }
    return after_decode(status, count);
  }
#else
  (void)threads;
#endif
  for (size_t f = 0; f < count;) {
    const size_t n = std::min(count - f, block);
    SEGMORPH_RETURN_IF_ERROR(decode(n, out + f * floats));
    f += n;
  }
  return Status::Ok();
}

Status FrameDecoder::skip_frame() {
  const size_t count = std::min(frames_left_in_clip(), block_frames());
  scratch_.resize(count * content_.vertex_count * 3);
  return decode(count, scratch_.data());
}

Status FrameDecoder::seek(size_t clip) {
  assert(is_open());
  if (!failure_.ok()) return failure_;
  if (clip >= content_.clip_frames.size()) return Status(StatusCode::invalid_argument, "no such clip");
  if (clip == clip_ && frame_in_clip_ == 0) return Status::Ok();
  auto start_at = [&](size_t start) {  // the decoder at the first frame of clip `start`
    clip_ = start, frame_in_clip_ = 0, frame_ = 0;
    for (size_t c = 0; c < start; ++c) frame_ += content_.clip_frames[c];
    loop_->start_clip();
  };
  if (content_.transform) {  // version 4: no frame depends on another, nor on the reader's place (all read)
    start_at(clip);
    return Status::Ok();
  }
  // The nearest checkpoint at or before the clip, unless the decoder is already between it and the clip.
  size_t from = clip;
  while (!checkpoints_[from]) --from;  // checkpoints_[0] always exists
  if (!(clip_ >= from && clip_ < clip)) {
    reader_->restore(*checkpoints_[from]);
    start_at(from);
  }
  while (clip_ < clip) SEGMORPH_RETURN_IF_ERROR(skip_frame());
  return Status::Ok();
}

namespace {

// `clips` filled with the clips of `content`: at each clip's start begin_clip(clip, frame) returns how many floats to
// reserve, then its frames are appended `block` at a time (fewer at a clip's end) by append(frame, count, positions);
// frame counts the stream's frames.
template <typename BeginClip, typename Append>
Status collect_clips(const StreamContent& content, size_t block, BeginClip begin_clip, Append append,
                     std::vector<FrameSequence>& clips) {
  clips.assign(content.clip_frames.size(), FrameSequence());
  size_t frame = 0;
  for (size_t c = 0; c < clips.size(); ++c) {
    FrameSequence& clip = clips[c];
    clip.vertex_count = content.vertex_count;
    clip.frame_count = content.clip_frames[c];
    clip.positions.reserve(begin_clip(c, frame));
    for (size_t f = 0; f < clip.frame_count;) {
      const size_t count = std::min<size_t>(clip.frame_count - f, block);
      SEGMORPH_RETURN_IF_ERROR(append(frame, count, clip.positions));
      f += count, frame += count;
    }
  }
  return Status::Ok();
}

}  // namespace

Status reconstruct_clips(const StreamContent& content, const std::vector<float>& base,
                         const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips) {
  const size_t row = size_t(content.welded_count) * 3;
  if (!content.transform && content.residuals.size() != content.frame_count() * row)
    return Status(StatusCode::invalid_argument, "stream content has the wrong number of residuals");
  FrameLoop loop(content, base, triangles);
  SEGMORPH_RETURN_IF_ERROR(loop.status());
  const FrameLoop::Residuals copy = [&](size_t frame, int64_t* to) {
    std::copy_n(content.residuals.begin() + ptrdiff_t(frame * row), row, to);
    return Status::Ok();
  };
  auto begin_clip = [&](size_t c, size_t) {
    loop.start_clip();
    return size_t(content.clip_frames[c]) * content.vertex_count * 3;  // the residuals are in memory: so can they be
  };
  auto append = [&](size_t frame, size_t count, std::vector<float>& positions) {
    return loop.decode_append(frame, copy, count, positions);
  };
  return collect_clips(content, loop.block_frames(), begin_clip, append, clips);
}

namespace {

// FrameDecoder::open after decode_animation's checks of the base and triangles.
Status open_checked(FrameDecoder& decoder, const uint8_t* data, size_t size, const std::vector<float>& base,
                    const std::vector<uint32_t>& triangles) {
  if (base.size() % 3 != 0) return Status(StatusCode::invalid_argument, "base positions must be V × 3");
  for (uint32_t index : triangles)
    if (index >= base.size() / 3) return Status(StatusCode::invalid_argument, "a triangle names a missing vertex");
  return decoder.open(data, size, base, triangles);
}

}  // namespace

Status decode_animation_into(const uint8_t* data, size_t size, const std::vector<float>& base,
                             const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips,
                             size_t threads) {
  FrameDecoder decoder;
  SEGMORPH_RETURN_IF_ERROR(open_checked(decoder, data, size, base, triangles));
  const StreamContent& content = decoder.content();
  bool same = clips.size() == content.clip_frames.size();
  for (size_t c = 0; same && c < clips.size(); ++c)
    same = clips[c].vertex_count == content.vertex_count && clips[c].frame_count == content.clip_frames[c] &&
           clips[c].positions.size() == size_t(clips[c].frame_count) * clips[c].vertex_count * 3;
  if (!same) return Status(StatusCode::invalid_argument, "the clips are not shaped as the stream's");
  for (FrameSequence& clip : clips)
    SEGMORPH_RETURN_IF_ERROR(decoder.decode_frames(clip.frame_count, clip.positions.data(), threads));
  return Status::Ok();
}

Status decode_animation(const uint8_t* data, size_t size, const std::vector<float>& base,
                        const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips, size_t threads) {
  FrameDecoder decoder;
  SEGMORPH_RETURN_IF_ERROR(open_checked(decoder, data, size, base, triangles));
  const StreamContent& content = decoder.content();
  // The frames grow as they are decoded, never sized by the counts alone: a stream of a few bytes can claim
  // format::kMaxVertexFrames positions (gigabytes), and its data runs out long before memory would.
  const size_t frame_floats = size_t(content.vertex_count) * 3, bound = decoder.frame_bound();
  auto begin_clip = [&](size_t c, size_t frame) {  // the decoder starts each clip itself
    return frames_to_reserve(content.clip_frames[c], bound - std::min(frame, bound), frame_floats * sizeof(float)) *
           frame_floats;
  };
  // Version 4 on threads: runs of at most 64 MiB of frames (frames_to_reserve's cap, so memory still grows only as
  // far as the frames before have decoded), each run's blocks side by side (decode_frames).
  const bool threaded = content.transform && threads != 1;
  const size_t block =
      threaded ? std::max(decoder.block_frames(),
                          frames_to_reserve(content.frame_count(), bound, frame_floats * sizeof(float)))
               : decoder.block_frames();
  auto append = [&](size_t, size_t count, std::vector<float>& positions) {
    if (!threaded) return decoder.decode_append(count, positions);
    const size_t at = positions.size();
    positions.resize(at + count * frame_floats);
    return decoder.decode_frames(count, positions.data() + at, threads);
  };
  return collect_clips(content, block, begin_clip, append, clips);
}

}  // namespace segmorph
