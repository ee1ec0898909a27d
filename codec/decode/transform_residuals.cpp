#include "decode/transform_residuals.h"

#include <cassert>
#include <utility>

#include "common/stream_format.h"
#include "decode/transform_walk.h"

namespace segmorph {

using transform_code::walk;

TransformCoefficients transform_layout(const StreamContent& content) {
  TransformCoefficients coefficients;
  coefficients.offset.resize(size_t(content.welded_count) + 1);
  coefficients.offset[0] = 0;
  for (size_t w = 0; w < content.welded_count; ++w)
    coefficients.offset[w + 1] = coefficients.offset[w] + uint64_t(content.basis_size[content.labels[w]]) * 3;
  coefficients.values.assign(size_t(coefficients.offset.back()), 0);
  return coefficients;
}

Status transform_coefficients(const StreamContent& content, const ResidualTraversal& traversal,
                              TransformCoefficients& coefficients) {
  coefficients = transform_layout(content);
  assert(coefficients.values.size() == content.coefficient_symbols.size());
  const bool ok = walk(content, traversal, coefficients, [&](uint64_t index, int64_t prediction, uint64_t symbol) {
    const int64_t q = prediction + content.coefficient_symbols[size_t(symbol)];
    if (q < -format::kMaxTransformValue || q > format::kMaxTransformValue) return false;
    coefficients.values[size_t(index)] = int32_t(q);
    return true;
  });
  return ok ? Status::Ok() : Status(StatusCode::bad_data, "animation stream: coefficient out of range");
}

TransformResiduals::TransformResiduals(const StreamContent& content, TransformCoefficients coefficients)
    : content_(content), offset_(std::move(coefficients.offset)), frames_(content.frame_count()) {
  auto frame_major = [&](const StreamContent::Basis& basis, size_t vectors) {
    std::vector<double> values(frames_ * vectors);
    for (size_t i = 0; i < vectors; ++i)
      for (size_t f = 0; f < frames_; ++f)
        values[f * vectors + i] = double(basis.entries[i * frames_ + f]) * double(basis.step[i]);
    return values;
  };
  stream_ = frame_major(content.stream_basis, content.stream_basis.size());
  scaled_.resize(coefficients.values.size());
  for (size_t w = 0; w < content.welded_count; ++w) {
    const double step = double(content.coefficient_step[content.labels[w]]);
    for (uint64_t i = offset_[w]; i < offset_[w + 1]; ++i) scaled_[i] = double(coefficients.values[i]) * step;
  }
  own_.resize(content.cluster_count);
  for (size_t k = 0; k < content.cluster_count; ++k)
    if (content.basis_source[k] == format::kBasisOwn)
      own_[k] = frame_major(content.own_basis[k], content.basis_size[k]);
}

void TransformResiduals::frame(size_t frame, double* out) const {
  const size_t stream_vectors = content_.stream_basis.size();
  for (size_t w = 0; w < content_.welded_count; ++w) {
    const uint32_t k = content_.labels[w], m = content_.basis_size[k];
    if (m == 0) {  // no basis: the residuals are zero (and the vectors below may be empty)
      out[w * 3] = out[w * 3 + 1] = out[w * 3 + 2] = 0.0;
      continue;
    }
    const double* basis = content_.basis_source[k] == format::kBasisOwn ? own_[k].data() + frame * m
                                                                        : stream_.data() + frame * stream_vectors;
    const double* c = scaled_.data() + offset_[w];
    // The three axes' sums side by side (each in its own order), so that their additions overlap.
    double x = 0.0, y = 0.0, z = 0.0;
    for (uint32_t i = 0; i < m; ++i) {
      const double b = basis[i];
      x = x + c[i] * b;
      y = y + c[m + i] * b;
      z = z + c[2 * m + i] * b;
    }
    out[w * 3] = x, out[w * 3 + 1] = y, out[w * 3 + 2] = z;
  }
}

}  // namespace segmorph
