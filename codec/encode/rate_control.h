// The rate control of encode_animation: the motion step and the residual steps that meet the target, found by
// measuring (rate_distortion.h's curves, the Lagrangian and exhaustive choices), then the residual symbols by the
// decoder's own loop and the stream. With an error target the motion step ratio is tried at a few values; with a rate
// target two passes, then the budget corrected by what the coder really produced.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "common/stream.h"
#include "encode/encode_problem.h"
#include "segmorph/status.h"

namespace segmorph {

// Codes `content` (its clusters and labels set; `fitted`: their motion, unquantized) into `stream`: quantized motion
// and weights, residual steps, residual symbols. `restored` (the clips' shape, their positions sized) receives the
// frames a decoder will produce, in the clips' vertex order; `report` the steps, sizes and stage times. `beside`, if
// any, is called with a copy of the content once its steps are chosen, while the residual symbols are coded (on
// another thread where one starts in time, else after them on this one): for work that depends on the motion alone;
// it must not report progress.
void code_stream(const EncodeProblem& problem, const Clusters& clusters, const AffineMotion& fitted,
                 StreamContent& content, StreamReport& report, std::vector<uint8_t>& stream,
                 std::vector<FrameSequence>& restored,
                 const std::function<void(const StreamContent& chosen)>& beside = {});

}  // namespace segmorph
