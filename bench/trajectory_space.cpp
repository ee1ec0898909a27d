// How much a temporal basis could save on the residuals (issue lever "trajectory-space coding"): encodes one animated
// glTF file as codec_sequence does (its first animated primitive, against the stand-in base mesh), then takes the
// open-loop residuals of the stream it wrote (each welded vertex's frames minus the prediction of the stream's
// quantized motion and weights: trajectories of F values per vertex and axis, in units of the axis's residual step)
// and prices them with zeroth-order entropies (no context modelling anywhere, so the figures compare schemes, not
// coders):
//   - today's scheme: the residuals quantized closed loop against the previous frame's reconstruction, per axis;
//   - the trajectories in a temporal basis, its coefficients quantized with one step D: a DCT along time (no basis to
//     send), one PCA basis of all trajectories, or one PCA basis per cluster (the trajectories of its vertices' three
//     axes); the basis sent at B bits per entry. For each, the D and the basis size m (per cluster, for the
//     per-cluster bases) that cost least at a squared error no larger than today's scheme's; the coefficients of each
//     basis vector priced in a context of their own.
// Then each basis in front of today's scheme: its prediction (entries at B bits, coefficients with step D, m vectors)
// taken off the trajectories and today's closed loop on what is left, the cheapest (D, m) at no more squared error
// than today's (m = 0 is today's scheme); the per-cluster bases against today's scheme with histograms per cluster.
// The coder itself spends less than the zeroth-order price of today's scheme (its spatial prediction, contexts and
// frame references): the stream's residual bytes are printed beside it.
//   trajectory_space FILE [--error E] [--basis-bits B]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "residual_trajectories.h"

using namespace segmorph;
using bench::Matrix;

namespace {

// Zeroth-order entropy, in bits, of a set of integer symbols.
double entropy_bits(std::vector<int64_t> symbols) {
  std::sort(symbols.begin(), symbols.end());
  double bits = 0;
  for (size_t i = 0, j = 0; i < symbols.size(); i = j) {
    while (j < symbols.size() && symbols[j] == symbols[i]) ++j;
    bits -= double(j - i) * std::log2(double(j - i) / double(symbols.size()));
  }
  return bits;
}

struct Price {
  double bits = INFINITY, step = 0, basis_bits = 0;
  size_t size = 0;
};

// The cheapest (D, m) for the trajectories `rows` (n × F) in the orthonormal basis `basis` (rows: vectors), at a
// squared error of at most `budget` in all (the coefficients of vector i coded in context i).
Price price_in_basis(const Matrix& rows, const Matrix& basis, double budget, double bits_per_basis_entry) {
  Matrix coefficients = rows * basis.transpose();  // n × M
  const size_t vectors = size_t(basis.rows());
  std::vector<double> energy(vectors);
  for (size_t i = 0; i < vectors; ++i) energy[i] = coefficients.col(Eigen::Index(i)).squaredNorm();
  std::vector<size_t> order(vectors);
  for (size_t i = 0; i < vectors; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return energy[a] > energy[b]; });
  const double total = rows.squaredNorm();
  Price best;
  for (int d = 0; d < 40; ++d) {
    const double step = 0.3 * std::pow(20 / 0.3, d / 39.0);
    double kept = 0, quantization = 0, bits = 0;
    for (size_t m = 1; m <= vectors; ++m) {
      const Eigen::Index column = Eigen::Index(order[m - 1]);
      std::vector<int64_t> symbols(size_t(rows.rows()));
      for (Eigen::Index r = 0; r < rows.rows(); ++r) {
        const double c = coefficients(r, column);
        symbols[size_t(r)] = std::llround(c / step);
        quantization += (c - double(symbols[size_t(r)]) * step) * (c - double(symbols[size_t(r)]) * step);
      }
      kept += energy[size_t(column)];
      bits += entropy_bits(symbols);
      const double error = total - kept + quantization;
      const double basis_bits = double(m) * double(basis.cols()) * bits_per_basis_entry;
      if (error <= budget && bits + basis_bits < best.bits) best = Price{bits + basis_bits, step, basis_bits, m};
    }
  }
  return best;
}

// Today's closed loop on `rows` (per row: each value quantized to whole steps against the previous value's
// reconstruction): adds each symbol to the histogram of its row's axis, returns the squared error.
double closed_loop(const Matrix& rows, const std::vector<int>& axis_of_row,
                   std::vector<std::vector<int64_t>>& symbols) {
  double error = 0;
  for (Eigen::Index r = 0; r < rows.rows(); ++r) {
    double reconstructed = 0;
    for (Eigen::Index f = 0; f < rows.cols(); ++f) {
      const int64_t q = std::llround(rows(r, f) - reconstructed);
      reconstructed += double(q);
      error += (rows(r, f) - reconstructed) * (rows(r, f) - reconstructed);
      symbols[size_t(axis_of_row[size_t(r)])].push_back(q);
    }
  }
  return error;
}

// The basis as a decoder would have it: each vector's entries quantized to `bits` bits (signed, against the vector's
// largest magnitude, sent beside it).
Matrix quantized_basis(const Matrix& basis, double bits) {
  Matrix quantized = basis;
  if (bits <= 0) return quantized;  // a basis the decoder computes (the DCT)
  const double levels = std::pow(2.0, bits - 1) - 1;
  for (Eigen::Index i = 0; i < basis.rows(); ++i) {
    const double scale = basis.row(i).cwiseAbs().maxCoeff();
    if (scale > 0)
      for (Eigen::Index f = 0; f < basis.cols(); ++f)
        quantized(i, f) = std::round(basis(i, f) / scale * levels) / levels * scale;
  }
  return quantized;
}

// The basis added to today's scheme: the first m vectors (by energy), their entries at B bits, the trajectories'
// coefficients quantized with step D make a prediction, and today's closed loop codes what it leaves. The cheapest
// (D, m) whose squared error is at most `budget` (m = 0 is today's scheme, so there is always one).
Price price_before_closed_loop(const Matrix& rows, const std::vector<int>& axis_of_row, const Matrix& basis,
                               double budget, double bits_per_basis_entry) {
  const Matrix full = rows * basis.transpose();
  std::vector<Eigen::Index> order(size_t(basis.rows()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = Eigen::Index(i);
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index a, Eigen::Index b) { return full.col(a).squaredNorm() > full.col(b).squaredNorm(); });
  Price best;
  std::vector<size_t> sizes = {0};
  for (size_t m = 1; m <= order.size(); m = std::max(m + 1, m * 5 / 4)) sizes.push_back(m);
  for (size_t m : sizes) {
    Matrix kept(Eigen::Index(m), basis.cols());
    for (size_t i = 0; i < m; ++i) kept.row(Eigen::Index(i)) = basis.row(order[i]);
    const Matrix decoded = quantized_basis(kept, bits_per_basis_entry);
    const Matrix coefficients = rows * decoded.transpose();  // nearly orthonormal still
    const double basis_bits = double(m) * double(basis.cols()) * bits_per_basis_entry;
    for (int d = 0; d < (m == 0 ? 1 : 16); ++d) {
      const double step = 0.25 * std::pow(16 / 0.25, d / 15.0);
      Matrix quantized = coefficients;
      double bits = basis_bits;
      for (Eigen::Index i = 0; i < quantized.cols(); ++i) {
        std::vector<int64_t> symbols(size_t(quantized.rows()));
        for (Eigen::Index r = 0; r < quantized.rows(); ++r)
          quantized(r, i) = double(symbols[size_t(r)] = std::llround(coefficients(r, i) / step)) * step;
        bits += entropy_bits(symbols);
      }
      std::vector<std::vector<int64_t>> symbols(3);
      const double error = closed_loop(m == 0 ? rows : Matrix(rows - quantized * decoded), axis_of_row, symbols);
      for (const std::vector<int64_t>& axis : symbols) bits += entropy_bits(axis);
      // (m = 0 repeats today's error, summed in another order: a relative tolerance keeps it.)
      if (error <= budget * (1 + 1e-9) && bits < best.bits) best = Price{bits, m == 0 ? 0 : step, basis_bits, m};
    }
  }
  return best;
}

// Orthonormal PCA basis (right singular vectors) of the rows.
Matrix pca_basis(const Matrix& rows) {
  Eigen::BDCSVD<Eigen::MatrixXd> svd(rows, Eigen::ComputeThinV);
  return svd.matrixV().transpose();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: trajectory_space FILE [--error E] [--basis-bits B]\n");
    return 2;
  }
  CodecSettings settings;
  double basis_entry_bits = 6;
  for (int i = 2; i < argc; i += 2) {
    if (i + 1 == argc)
      return std::fprintf(stderr, "trajectory_space: %s needs a value\n", argv[i]), 2;
    else if (std::strcmp(argv[i], "--error") == 0)
      settings.target = std::atof(argv[i + 1]);
    else if (std::strcmp(argv[i], "--basis-bits") == 0)
      basis_entry_bits = std::atof(argv[i + 1]);
    else
      return std::fprintf(stderr, "trajectory_space: unknown option %s\n", argv[i]), 2;
  }
  bench::ResidualTrajectories t;
  const Status status = bench::residual_trajectories(argv[1], settings, t);
  if (!status.ok()) {
    std::fprintf(stderr, "trajectory_space: %s: %s\n", argv[1], status.message().c_str());
    return 1;
  }
  const StreamContent& content = t.content;
  const StreamReport& report = t.report;
  const Matrix& rows = t.rows;
  const size_t welded = content.welded_count, frames = content.frame_count();

  // Today's scheme, closed loop against the previous frame: the symbols per axis, the squared error per trajectory.
  double today_bits = 0, today_error = 0;
  std::vector<double> row_error(welded * 3, 0.0);
  for (size_t axis = 0; axis < 3; ++axis) {
    std::vector<int64_t> symbols;
    for (size_t w = 0; w < welded; ++w) {
      double reconstructed = 0;
      for (size_t f = 0; f < frames; ++f) {
        const double value = rows(Eigen::Index(w * 3 + axis), Eigen::Index(f));
        const int64_t q = std::llround(value - reconstructed);
        reconstructed += double(q);
        row_error[w * 3 + axis] += (value - reconstructed) * (value - reconstructed);
        symbols.push_back(q);
      }
      today_error += row_error[w * 3 + axis];
    }
    today_bits += entropy_bits(symbols);
  }
  std::printf(
      "%s --error %g: W=%zu F=%zu K=%u | stream residuals %zu B | today's scheme (closed loop on the previous "
      "frame), zeroth order: %.0f B at squared error %.4g step^2 per value\n",
      argv[1], settings.target, welded, frames, content.cluster_count, report.bytes_residuals, today_bits / 8,
      today_error / double(rows.size()));

  // DCT-II along time, orthonormal.
  Matrix dct = Matrix::Zero(Eigen::Index(frames), Eigen::Index(frames));
  for (size_t k = 0; k < frames; ++k)
    for (size_t n = 0; n < frames; ++n)
      dct(Eigen::Index(k), Eigen::Index(n)) = std::cos(M_PI * (double(n) + 0.5) * double(k) / double(frames)) *
                                              std::sqrt((k == 0 ? 1.0 : 2.0) / double(frames));
  auto print = [&](const char* name, const Price& price, const std::string& extra) {
    if (std::isinf(price.bits))
      std::printf("  %s: no step and size meet the error\n", name);
    else
      std::printf("  %s: %.0f B (basis %.0f B)%s\n", name, price.bits / 8, price.basis_bits / 8, extra.c_str());
  };
  auto step = [](const Price& price) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.3g", price.step);
    return std::string(text);
  };
  std::vector<int> axis_of_row(size_t(rows.rows()));
  for (size_t r = 0; r < axis_of_row.size(); ++r) axis_of_row[r] = int(r % 3);
  const Matrix global_basis = pca_basis(rows);
  const Price in_dct = price_in_basis(rows, dct, today_error, 0);
  print("DCT along time", in_dct,
        ", D " + step(in_dct) + " steps, " + std::to_string(in_dct.size) + " coefficients per trajectory");
  const Price global = price_in_basis(rows, global_basis, today_error, basis_entry_bits);
  print("one PCA basis", global, ", D " + step(global) + " steps, " + std::to_string(global.size) + " vectors");
  const Price dct_before = price_before_closed_loop(rows, axis_of_row, dct, today_error, 0);
  print("DCT before today's closed loop", dct_before,
        ", D " + step(dct_before) + " steps, " + std::to_string(dct_before.size) + " coefficients per trajectory");
  const Price global_before = price_before_closed_loop(rows, axis_of_row, global_basis, today_error, basis_entry_bits);
  print("one PCA basis before today's closed loop", global_before,
        ", D " + step(global_before) + " steps, " + std::to_string(global_before.size) + " vectors");

  // One basis per cluster, each cluster held to today's error on its own trajectories.
  Price clusters{0, 0, 0, 0}, clusters_before{0, 0, 0, 0};
  double today_per_cluster_bits = 0;  // today's scheme with the symbols' histograms per cluster and axis
  std::string sizes, sizes_before;
  for (uint32_t k = 0; k < content.cluster_count; ++k) {
    std::vector<Eigen::Index> members;
    for (size_t w = 0; w < welded; ++w)
      if (content.labels[w] == k)
        for (Eigen::Index axis = 0; axis < 3; ++axis) members.push_back(Eigen::Index(w * 3) + axis);
    if (members.empty()) continue;
    Matrix own(Eigen::Index(members.size()), Eigen::Index(frames));
    double own_error = 0;  // today's error on these trajectories
    for (size_t i = 0; i < members.size(); ++i) {
      own.row(Eigen::Index(i)) = rows.row(members[i]);
      own_error += row_error[size_t(members[i])];
    }
    const Matrix own_basis = pca_basis(own);
    const Price price = price_in_basis(own, own_basis, own_error, basis_entry_bits);
    clusters.bits += price.bits, clusters.basis_bits += price.basis_bits;
    if (std::isinf(price.bits)) clusters.bits = INFINITY;
    sizes += (sizes.empty() ? "" : " ") + std::to_string(price.size) + "@" + step(price);
    std::vector<int> own_axes(members.size());
    for (size_t i = 0; i < members.size(); ++i) own_axes[i] = int(members[i] % 3);
    std::vector<std::vector<int64_t>> own_symbols(3);
    closed_loop(own, own_axes, own_symbols);
    for (const std::vector<int64_t>& axis : own_symbols) today_per_cluster_bits += entropy_bits(axis);
    const Price before = price_before_closed_loop(own, own_axes, own_basis, own_error, basis_entry_bits);
    clusters_before.bits += before.bits, clusters_before.basis_bits += before.basis_bits;
    sizes_before += (sizes_before.empty() ? "" : " ") + std::to_string(before.size) + "@" + step(before);
  }
  print("a PCA basis per cluster", clusters, " (each its own D), vectors@D per cluster: " + sizes);
  print("a PCA basis per cluster before today's closed loop", clusters_before,
        " (each its own D), vectors@D per cluster: " + sizes_before + "; today's scheme with histograms per cluster: " +
            std::to_string(int64_t(today_per_cluster_bits / 8)) + " B");
  std::printf("  (bases at %g bits per entry)\n", basis_entry_bits);
  return 0;
}
