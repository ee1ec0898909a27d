// What the segmorph tool prints: each command's report as text (for people) and as JSON (--json, for scripts; one
// object per line, built with nlohmann::json), and the errors. The figures come from the pipeline API's reports;
// nothing here measures or decides.
#pragma once

#include <string>

#include "segmorph/segmorph.h"

namespace segmorph {

// The stable names of the error codes --json prints.
const char* code_name(StatusCode code);

// {"error":{"code":...,"file":...,"message":...}} (file null when empty), without a newline.
std::string error_json(const std::string& code, const std::string& file, const std::string& message);

// "Fox, mesh 0 primitive 0" (the node's index when it has no name).
std::string primitive_label(const PrimitiveError& primitive);

std::string info_text(const std::string& path, const InfoReport& report);
std::string info_json(const std::string& path, const InfoReport& report);

// `bytes`: the written file's (saved_bytes).
std::string encode_text(const std::string& output, size_t bytes, const EncodeReport& report);
std::string encode_json(const std::string& input, const std::string& output, size_t bytes, const EncodeReport& report);

// The bound verify's file exceeds, in one line ("KG 0.2000 % is above --max-error 0.15 (Fox, mesh 0 primitive 0)"),
// or empty for VerifyBound::none.
std::string bound_text(VerifyBound bound, const VerifyReport& report, size_t bytes, const VerifyBounds& bounds);

// `bytes`: the compressed file's (input_bytes); `above`: bound_text's line, or empty.
std::string verify_text(const std::string& original, const std::string& compressed, size_t bytes,
                        const VerifyReport& report);
std::string verify_json(const std::string& original, const std::string& compressed, size_t bytes,
                        const VerifyReport& report, const std::string& above);

}  // namespace segmorph
