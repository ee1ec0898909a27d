// The encoder's side of version 4's residuals (transform_residuals.h is the decoder's): each cluster's residual
// trajectories over all frames in a temporal basis (nothing, the first m vectors of the stream's PCA basis, or m of
// its own), its coefficients quantized with a step of its own, chosen for the fewest estimated bytes at no more
// squared error than a budget (docs/codec.md, "Transform coding in place of the residual loop").
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "common/frame_sequence.h"
#include "common/stream.h"
#include "encode/encode_problem.h"
#include "encode/stream_writer.h"

namespace segmorph {

// From `content` (the residual loop's, taken over: its clusters, motion and weights are kept, its residual symbols
// dropped), the stream of a version-4 content whose frames have a squared error (over every vertex of every frame,
// against the problem's clips) of at most `budget`: in `stream` (`sizes`: its parts). The bases and the options
// are estimated from at most settings.transform_sample_rows rows of each cluster (whole vertices, evenly spaced); every
// row's coefficients are fitted, and the error is the decoder's frames'. Returns whether it made one: false, leaving
// the outputs undefined, when there is none (too many frames, vectors or coefficients for the format, or the budget
// not met). `prelude`, if any, is transform_prelude's of the same content.
struct TransformPrelude;
bool try_transform_stream(const EncodeProblem& problem, StreamContent content, double budget,
                          std::vector<uint8_t>& stream, StreamSizes& sizes, const TransformPrelude* prelude = nullptr);

// What try_transform_stream first finds of `content` (the residual loop's, its steps chosen), which depends on its
// motion alone, not on the budget: the residual rows (W × 3 × F floats), then the stream basis's eigenproblem, with
// `own_thread` on a thread of its own, which try_transform_stream waits for where it needs it (its clusters' own bases
// go on meanwhile); without, where it is first needed. Made while the residual loop codes its symbols (code_stream's
// `beside`), and handed to each try_transform_stream of that content: the same stream as without it. Null where no
// transform is tried (too many frames).
std::shared_ptr<const TransformPrelude> transform_prelude(const EncodeProblem& problem, StreamContent content,
                                                          bool own_thread);

}  // namespace segmorph
