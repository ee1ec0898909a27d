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
    : content_(content), offset_(std::move(coefficients.offset)), stride_(content.frame_count() + kRowPadding) {
  const size_t frames = content.frame_count(), clusters = content.cluster_count;
  size_t rows = content.stream_basis.size();
  own_row_.assign(clusters, 0);
  for (size_t k = 0; k < clusters; ++k)
    if (content.basis_source[k] == format::kBasisOwn) own_row_[k] = rows, rows += content.basis_size[k];
  rows_.assign(rows * stride_, 0.0);
  auto put = [&](const StreamContent::Basis& basis, size_t vectors, size_t first_row) {
    for (size_t i = 0; i < vectors; ++i) {
      double* row = &rows_[(first_row + i) * stride_];
      const double step = double(basis.step[i]);
      for (size_t f = 0; f < frames; ++f) row[f] = double(basis.entries[i * frames + f]) * step;
    }
  };
  put(content.stream_basis, content.stream_basis.size(), 0);
  for (size_t k = 0; k < clusters; ++k)
    if (content.basis_source[k] == format::kBasisOwn) put(content.own_basis[k], content.basis_size[k], own_row_[k]);
  scaled_.resize(coefficients.values.size());
  for (size_t w = 0; w < content.welded_count; ++w) {
    const double step = double(content.coefficient_step[content.labels[w]]);
    for (uint64_t i = offset_[w]; i < offset_[w + 1]; ++i) scaled_[i] = double(coefficients.values[i]) * step;
  }
}

const double* TransformResiduals::basis(size_t cluster) const {
  switch (content_.basis_source[cluster]) {
    case format::kBasisOwn: return rows_.data() + own_row_[cluster] * stride_;
    case format::kBasisStream: return rows_.data();
    default: return nullptr;
  }
}

void TransformResiduals::frame(size_t frame, double* out) const {
  for (size_t w = 0; w < content_.welded_count; ++w) {
    const uint32_t k = content_.labels[w], m = content_.basis_size[k];
    if (m == 0) {  // no basis: the residuals are zero (and the vectors below may be empty)
      out[w * 3] = out[w * 3 + 1] = out[w * 3 + 2] = 0.0;
      continue;
    }
    const double* basis = this->basis(k) + frame;
    const double* c = scaled_.data() + offset_[w];
    // The three axes' sums side by side (each in its own order), so that their additions overlap.
    double x = 0.0, y = 0.0, z = 0.0;
    for (uint32_t i = 0; i < m; ++i) {
      const double b = basis[i * stride_];
      x = x + c[i] * b;
      y = y + c[m + i] * b;
      z = z + c[2 * m + i] * b;
    }
    out[w * 3] = x, out[w * 3 + 1] = y, out[w * 3 + 2] = z;
  }
}

}  // namespace segmorph
