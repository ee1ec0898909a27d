// The decoder's one frame loop: a stream's frames reconstructed a few at a time (two in versions 1 to 3, up to
// TransformBlocks::kMaxFrames in version 4) and written in the base mesh's vertex order. decode_animation, reconstruct_clips and the runtime API (include/segmorph/decoder.h) all decode
// through it, so that every way of decoding gives the same floats.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "common/prediction.h"
#include "common/reconstruction.h"
#include "common/stream.h"
#include "common/vertex_gather.h"
#include "decode/stream_reader.h"
#include "decode/transform_blocks.h"
#include "decode/transform_residuals.h"
#include "segmorph/status.h"

namespace segmorph {

// What reconstructs frames from their residual symbols, given a stream's content (read_head's, or read_stream's):
// the welded base, the dequantized motion and weights, the traversal and the residual loop.
class FrameLoop {
 public:
  // Frame `frame` (in the stream, all clips end to end)'s W × 3 residual symbols into `row`.
  using Residuals = std::function<Status(size_t frame, int64_t* row)>;

  // content must outlive the loop; base (V × 3) and triangles (T × 3 indices into V) are read by the constructor.
  // Check status() before decoding: version 4's coefficients are made from the traversal here, and can be bad.
  FrameLoop(const StreamContent& content, const std::vector<float>& base, const std::vector<uint32_t>& triangles);
  FrameLoop(const FrameLoop&) = delete;
  FrameLoop& operator=(const FrameLoop&) = delete;

  const Status& status() const { return status_; }

  // What the loop reconstructs from (the playback model, playback_model.h, reads them): the welded base (W × 3), the
  // dequantized motion and weights, and in version 4 the residuals' coefficients and bases and the blocks (null in
  // versions 1-3). Version 4's motion has its centroids only: its transforms are the blocks' (blocks()->transform).
  const std::vector<float>& welded() const { return welded_; }
  const AffineMotion& motion() const { return motion_; }
  const ClusterWeights& weights() const { return weights_; }
  const TransformResiduals* transform() const { return transform_.get(); }
  const TransformBlocks* blocks() const { return blocks_.get(); }

  // Starts a clip: its first frame has no reference.
  void start_clip();

  // How many frames one call decodes at most: 2 in versions 1 to 3, TransformBlocks::kMaxFrames in version 4.
  size_t block_frames() const { return blocks_ ? TransformBlocks::kMaxFrames : 2; }

  // Reconstructs stream frames `frame` .. `frame` + count − 1 (count 1 .. block_frames(); in versions 1 to 3 all in
  // one clip, in version 4 any, its frames depending on no other) into out,
  // frame after frame (V × 3 floats each). Fails on bad symbols and on a position that decodes to NaN or infinity.
  Status decode(size_t frame, const Residuals& residuals, size_t count, float* out);

  // The same, appending the frames' floats to `out` (which grows without being zero-filled first).
  Status decode_append(size_t frame, const Residuals& residuals, size_t count, std::vector<float>& out);

  // Version 4 only (transform() not null): decode() of `count` frames (1 .. block_frames()) with the caller's room
  // for the welded frames (block_frames() × W × 3 floats) instead of the loop's, so that several threads may
  // decode frames of one loop at once.
  Status decode_independent(size_t frame, size_t count, float* out, float* welded_frames) const;

 private:
  Status reconstruct(size_t frame, const Residuals& residuals, size_t count);

  const StreamContent& content_;
  std::vector<float> welded_;
  AffineMotion motion_;
  ClusterWeights weights_;
  ResidualTraversal traversal_;
  std::unique_ptr<FramePredictor> predictor_;              // versions 1 to 3 (null in version 4)
  std::unique_ptr<ResidualReconstructor> reconstructor_;  // versions 1 to 3 (null in version 4)
  size_t row_;  // W × 3
  // Versions 1 to 3 reconstruct two frames at a time (ResidualReconstructor::two_frames), so that what the loop reads
  // in traversal order (predictions, symbols) and writes (welded positions) stays in cache: slot 0 and slot 1.
  std::vector<double> predictions_;
  std::vector<int64_t> symbols_;
  std::vector<float> welded_frames_;  // block_frames() slots of W × 3
  VertexGather to_vertices_;  // welded frames into the base mesh's vertex order
  // Version 4: the residuals from the coefficients instead of the residual loop (no symbols are read), the frames
  // a block at a time.
  std::unique_ptr<TransformResiduals> transform_;
  std::unique_ptr<TransformBlocks> blocks_;
  Status status_;
};

// A stream decoded frame by frame in stream order (clip after clip), with the frames written where the caller says:
// parse the head with open(), then decode(); seek() goes back (or forward) to the first frame of a clip. Bad data is
// sticky: after a failure every call returns it until the next open().
class FrameDecoder {
 public:
  FrameDecoder();
  ~FrameDecoder();
  FrameDecoder(const FrameDecoder&) = delete;
  FrameDecoder& operator=(const FrameDecoder&) = delete;

  // Parses the stream's head against the base mesh (base: V × 3 positions; triangles: T × 3 indices into V, checked
  // by the caller). Keeps a pointer to data, which must outlive the decoder or stay until the next open(). Refuses a
  // stream that claims more frames than its bytes can hold (frame_bound()), so that frame counts can size memory.
  Status open(const uint8_t* data, size_t size, const std::vector<float>& base, const std::vector<uint32_t>& triangles);

  bool is_open() const { return loop_ != nullptr; }
  const FrameLoop& loop() const { return *loop_; }
  const StreamContent& content() const { return content_; }
  int version() const { return version_; }

  // The next frame to decode: clip and frame within it (next_clip() == the clip count after the last frame).
  size_t next_clip() const { return clip_; }
  size_t next_frame() const { return frame_in_clip_; }
  size_t frames_left_in_clip() const;

  // How many frames one call decodes at most (FrameLoop::block_frames()).
  size_t block_frames() const { return loop_->block_frames(); }

  // Decodes the next `count` frames (1 .. block_frames(), within the clip) into out, frame after frame (V × 3 floats
  // each); advances. The last frame of the stream also checks that the stream ends there.
  Status decode(size_t count, float* out);
  // The same, appending to `out`.
  Status decode_append(size_t count, std::vector<float>& out);
  // The next `count` frames (any number within the clip) into out, frame after frame, a block at a time; a version-4
  // stream's blocks on up to `threads` threads (0: every hardware thread; a WebAssembly build has none and uses the
  // calling one). The same floats for every thread count.
  Status decode_frames(size_t count, float* out, size_t threads);

  // Positions the decoder at the first frame of `clip` (< the clip count). Versions 1 to 3: a clip start the decoder
  // has passed is restored from a checkpoint (about 3 bytes per welded vertex, kept while they take at most 64 MiB
  // in all); one it has not is reached by decoding the frames before it. Version 4 goes there directly (its frames
  // depend on none before them), without checking the frames it skips.
  Status seek(size_t clip);

  // How many frames of the stream its bytes can hold (StreamReader::frame_bound() after the head).
  size_t frame_bound() const { return frame_bound_; }

 private:
  // The sticky failure, or invalid_argument unless `count` frames are left in the clip (any count: the caller checks
  // the block size where it applies).
  Status check_frames(size_t count) const;
  Status before_decode(size_t count);
  Status after_decode(Status status, size_t count);
  void take_checkpoint();
  Status skip_frame();

  StreamContent content_;
  std::unique_ptr<StreamReader> reader_;
  std::unique_ptr<FrameLoop> loop_;
  FrameLoop::Residuals residuals_;
  int version_ = 0;
  size_t frame_bound_ = 0;
  size_t clip_ = 0, frame_in_clip_ = 0, frame_ = 0;  // frame_: in the stream
  Status failure_;
  // checkpoints_[c]: the reader at the first frame of clip c, once passed (null before, and beyond the memory cap).
  std::vector<StreamReader::CheckpointPointer> checkpoints_;
  size_t checkpoint_bytes_ = 0;
  std::vector<float> scratch_;  // skip_frame's output
};

// The clips (original vertex order) of a content read by read_stream against `base`, with the base mesh's
// triangles (the decoder's stage after entropy decoding; frame_decoder.h's FrameLoop). Fails when a position decodes
// to NaN or infinity.
Status reconstruct_clips(const StreamContent& content, const std::vector<float>& base,
                         const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips);

// Decodes a stream against the base mesh: positions (V × 3) and triangles (T × 3 indices into V, as the
// encoder's clips had them). The clips come back with their positions (frame times are the container's
// business and are left empty). Never reads outside [data, data + size). A version-4 stream's frames on up to
// `threads` threads (0: every hardware thread; FrameDecoder::decode_frames): the same floats for every count.
Status decode_animation(const uint8_t* data, size_t size, const std::vector<float>& base,
                        const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips,
                        size_t threads = 1);

// decode_animation into clips the caller has shaped (the encoder, decoding a stream it has just written): as many as
// the stream has, each with the stream's vertex and frame counts and its positions sized to them. The frames are
// decoded where they will stay, with no growing and copying. invalid_argument when the shapes differ.
Status decode_animation_into(const uint8_t* data, size_t size, const std::vector<float>& base,
                             const std::vector<uint32_t>& triangles, std::vector<FrameSequence>& clips,
                             size_t threads = 1);

}  // namespace segmorph
