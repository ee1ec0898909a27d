// The segmorph animation encoder: Hachani, Ouled Zaid & Puech's segmentation-based scheme, with the
// improvements documented in docs/codec.md. Encodes the clips of one primitive against the base mesh
// positions the decoder will have (the container's Draco-decoded first frame); decode/frame_decoder.h's
// decode_animation decodes them back.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/frame_sequence.h"
#include "segmorph/encoding.h"
#include "segmorph/status.h"

namespace segmorph {

// Where encode_animation is on long work: its stage ("rate control: measuring 12 steps") and the fraction of that
// stage done, in [0, 1], or negative when the stage cannot say. Called on the encoding thread, often (once a frame in
// the passes over every frame): a caller that prints should throttle it.
using CodecProgress = std::function<void(const std::string& stage, double fraction)>;

struct CodecSettings {
  RateMode mode = RateMode::error;
  double target = 0.15;  // KG % (error) or bits per vertex per frame (bpvf)
  size_t clusters = 0;   // K; 0 chooses automatically
  // Stages of the paper that can be switched off, and additions beyond it (measured in docs/codec.md).
  // Eq. 6 (refinement.h; measured in docs/codec.md): refinement_level_curves scores the levels on ordered level
  // curves as the paper states it, else on boundary vertices. choose_segmentation: the cluster count's search is
  // run on the Morse segmentation as found too, and the one estimated cheaper is coded (automatic_clusters.h);
  // off by default: it costs 1.2x the encode time and changed few whole files.
  bool curvature_refinement = true;
  bool refinement_level_curves = false;
  bool choose_segmentation = false;
  bool motion_refinement = true;   // beyond the paper: boundary vertices follow the best-fitting motion
  bool blend_weights = true;       // Eq. 3; off: each vertex follows its own cluster only
  bool temporal_residuals = true;  // beyond the paper: residuals predicted from the previous (or reference) frame's
  bool spatial_residuals = true;   // beyond the paper: ... and from already decoded neighbours'
  // Beyond the paper: a frame's motion and residuals predicted from an earlier frame than the previous one where it
  // predicts much better (stream version 3; frame_references.h). With temporal residuals only.
  bool frame_references = true;
  // Beyond the paper: the motion's differences coded in contexts, and predicted linearly, where that takes fewer
  // bytes (stream version 3).
  bool motion_contexts = true;
  // Beyond the paper: each vertex's extra clusters coded as places among those recently blended into vertices of its
  // own cluster, its count of them in contexts, where that takes fewer bytes (stream version 3).
  bool weight_contexts = true;
  // Beyond the paper: the residuals in the table code of stream version 2 (common/table_residual_format.h), which decodes
  // faster and costs more bytes than the adaptive code. Lossy modes only.
  bool table_residuals = false;
  // Beyond the paper: the residuals as temporal bases and coefficients (stream version 4, transform_coding.h) where
  // that takes fewer bytes than the residual loop at no more KG error. Error targets (RateMode::error) only, and not
  // with table_residuals.
  bool transform_residuals = true;
  // Only a version-4 stream, whose model a GPU evaluates (docs/runtime.md, "Playing the model"): the transform-coded
  // stream is kept even where the residual loop's would be smaller; it is made at the residual loop's error as
  // without the setting (the same stream where that one is version 4), else at the error target; an encode that
  // cannot write one fails (UNSUPPORTED) rather than fall back.
  // Needs transform_residuals, an error target and no table_residuals.
  bool gpu_playable = false;
  // With transform_residuals: at most this many rows (a welded vertex's axis over all frames) of each cluster, and of
  // the whole stream, inform the bases and the choice among them (evenly spaced, each standing for the rows between);
  // the coefficients of every row are fitted, and the error is the decoder's, whatever the number. It bounds the
  // time and memory the bases take on large meshes. At least 3 (a vertex's three axes are sampled together).
  size_t transform_sample_rows = 32768;
  // Bytes of the output outside this stream (the base mesh, the container) that a bpvf target includes.
  size_t outside_bytes = 0;
  // Threads for the stages that split their work (parallel.h); 0: every hardware thread. The stream is the same
  // bytes for every number.
  size_t threads = 1;
  CodecProgress progress;  // empty: none
};

// clips: the primitive's clips (same V and triangles; frame 0 of clip 0 is the base frame). base: V × 3, the
// base positions exactly as the decoder will have them. On success `stream` holds the encoded bytes and
// `reconstruction` (if given) the frames a decoder will produce, bit for bit: for a version-4 stream the stream as
// decode_animation decodes it, for versions 1 to 3 the encoder's own closed loop (which the decoder repeats).
Status encode_animation(const std::vector<FrameSequence>& clips, const std::vector<float>& base,
                        const CodecSettings& settings, std::vector<uint8_t>& stream, StreamReport* report = nullptr,
                        std::vector<FrameSequence>* reconstruction = nullptr);

// ‖A − E(A)‖²_F: the squared distance of every position of every frame from its frame's centroid (the
// denominator of the KG error).
double frame_spread(const std::vector<FrameSequence>& clips);

// The mean residual quantizer step a KG error target implies if the whole error were uniform quantization
// noise: sqrt(12 · spread / (3 V F)) · E / 100, spread = frame_spread(clips). The encoder's first guess, and
// the scale the container chooses the base mesh's position precision by.
double expected_residual_step(const std::vector<FrameSequence>& clips, double spread, double kg_percent);

}  // namespace segmorph
