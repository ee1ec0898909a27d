// Transform coding in place of the residual loop, coded (issue lever "trajectory-space coding"; docs/codec.md): the
// open-loop residual trajectories of the stream segmorph writes for a file (residual_trajectories.h) coded as a
// temporal basis and coefficients, with the stream's range coder, at no more squared error than the stream's own
// decoded frames have. Per cluster: none, the first m vectors of the stream's one PCA basis, or the first m of a PCA
// basis of the cluster's own trajectories; its coefficients quantized with a step D of its own. The (source, m, D)
// of every cluster come from one Lagrangian choice (estimated bytes + lambda x squared error, lambda bisected to the
// error budget, estimated with the unquantized bases), then the exact error with the bases quantized to B bits per
// entry is measured and the budget tightened until it holds. Printed: the bytes of the parts as the range coder
// codes them, the coefficients in three ways (a model per vector; and in the context of the previous vertex's
// magnitude; and predicted from the decoded earlier neighbours, as the residual loop predicts, in a model per vector:
// in the context of the prediction's magnitude too, they took 0.4-3 % more), the bases in two
// (B bits each; differences along time in an adaptive model), against the stream's residual bytes. With
// --basis-bits 0 (the default) each basis vector's entries get a step of their own, from lambda and the energy of
// the coefficients that use the vector. A welded vertex's error counts once per vertex of its group (as if they moved
// together; the sequences measured have one group of two vertices at most).
//   transform_prototype FILE [--error E] [--basis-bits B]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/range_coder.h"
#include "decode/frame_decoder.h"
#include "residual_trajectories.h"

using namespace segmorph;
using bench::Matrix;

namespace {

// Zeroth-order entropy, in bits, of the quantized column `column` of `coefficients` (step `step`) over `rows`.
double entropy_bits(const Matrix& coefficients, Eigen::Index column, const std::vector<Eigen::Index>& rows, double step,
                    double& quantization, const std::vector<double>& weight) {
  std::unordered_map<int64_t, uint32_t> counts;
  quantization = 0;
  for (Eigen::Index r : rows) {
    const double c = coefficients(r, column);
    const int64_t q = std::llround(c / step);
    ++counts[q];
    quantization += weight[size_t(r)] * (c - double(q) * step) * (c - double(q) * step);
  }
  double bits = 0;
  for (const auto& [symbol, count] : counts) bits -= double(count) * std::log2(double(count) / double(rows.size()));
  return bits;
}

// Orthonormal PCA basis (right singular vectors, by decreasing singular value) of the rows.
Matrix pca_basis(const Matrix& rows) {
  Eigen::BDCSVD<Eigen::MatrixXd> svd(rows, Eigen::ComputeThinV);
  return svd.matrixV().transpose();
}

// A basis as a decoder has it: each vector's entries as integers of `bits` bits (signed, against the vector's largest
// magnitude, a float sent beside it).
struct QuantizedBasis {
  Matrix vectors;                      // the decoder's values
  std::vector<std::vector<int>> ints;  // per vector, F integers
};
QuantizedBasis quantize_basis(const Matrix& basis, size_t m, int bits, const std::vector<double>& steps) {
  QuantizedBasis out;
  out.vectors = basis.topRows(Eigen::Index(m));
  out.ints.resize(m);
  const double levels = std::pow(2.0, bits - 1) - 1;
  for (size_t i = 0; i < m; ++i) {
    const Eigen::Index row = Eigen::Index(i);
    const double scale = float(bits > 0 ? basis.row(row).cwiseAbs().maxCoeff() / levels : steps[i]);
    for (Eigen::Index f = 0; f < basis.cols(); ++f) {
      const int q = int(std::lround(basis(row, f) / scale));
      out.ints[i].push_back(q);
      out.vectors(row, f) = double(q) * scale;
    }
  }
  return out;
}

// With --basis-bits 0, each vector's entries get a step of their own: the one that minimizes bits + lambda × squared
// error for a vector whose coefficients have squared norm `energy` (an entry's error reaches the frames through
// them): F log2(1/step) + lambda energy F step² / 12 is least at step² = 6 / (lambda ln 2 energy).
std::vector<double> basis_steps(const std::vector<double>& energy, double lambda) {
  std::vector<double> steps;
  for (double e : energy)
    steps.push_back(std::clamp(std::sqrt(6 / (lambda * std::log(2.0) * std::max(e, 1e-30))), 1e-5, 0.5));
  return steps;
}

struct Option {
  int source = 0;  // 0 none, 1 the stream's basis, 2 the cluster's own
  size_t m = 0;
  double step = 0, bits = 0, error = 0;
};

// The options of one cluster in one basis (orthonormal, rows by decreasing energy): for each m of `sizes` (up to the
// basis's size) and each step, the zeroth-order bits of the coefficients (a histogram per vector) and the squared
// error (dropped energy plus quantization), weighted per row.
void add_options(const Matrix& coefficients, const std::vector<Eigen::Index>& rows, const std::vector<double>& weight,
                 double total, int source, const std::vector<size_t>& sizes, double bits_per_vector,
                 std::vector<Option>& options) {
  const size_t vectors = size_t(coefficients.cols());
  for (int d = 0; d < 24; ++d) {
    const double step = 0.3 * std::pow(12 / 0.3, d / 23.0);
    double bits = 0, kept = 0, quantization = 0;
    size_t m = 0;
    for (size_t size : sizes) {
      if (size > vectors) break;
      for (; m < size; ++m) {
        double q = 0;
        bits += entropy_bits(coefficients, Eigen::Index(m), rows, step, q, weight);
        quantization += q;
        for (Eigen::Index r : rows)
          kept += weight[size_t(r)] * coefficients(r, Eigen::Index(m)) * coefficients(r, Eigen::Index(m));
      }
      options.push_back(
          {source, m, step, bits + (source == 2 ? double(m) * bits_per_vector : 0), total - kept + quantization});
    }
  }
}

struct Choice {
  std::vector<Option> per_cluster;
  size_t global_vectors = 0;
  double bits = 0, error = 0, lambda = 0;
};

// The options minimizing bits + lambda × error per cluster, lambda bisected so that the error is at most `budget`;
// the stream's basis charged `bits_per_vector` per vector once, its size the largest any cluster uses (tried at each
// of `sizes`: a cluster may use it only up to that size).
Choice choose(const std::vector<std::vector<Option>>& options, double budget, const std::vector<size_t>& sizes,
              double bits_per_vector, bool allow_global, bool allow_own) {
  Choice best;
  best.bits = INFINITY;
  for (size_t global : sizes) {
    if (!allow_global && global > 0) break;
    auto pick = [&](double lambda) {
      Choice c;
      c.global_vectors = 0;
      for (const std::vector<Option>& list : options) {
        const Option* chosen = nullptr;
        for (const Option& o : list) {
          if ((o.source == 1 && (o.m > global || !allow_global)) || (o.source == 2 && !allow_own)) continue;
          if (!chosen || o.bits + lambda * o.error < chosen->bits + lambda * chosen->error) chosen = &o;
        }
        c.per_cluster.push_back(*chosen);
        c.bits += chosen->bits, c.error += chosen->error;
        if (chosen->source == 1) c.global_vectors = std::max(c.global_vectors, chosen->m);
      }
      c.bits += double(c.global_vectors) * bits_per_vector;
      return c;
    };
    double low = 1e-6, high = 1e6;
    if (pick(high).error > budget) continue;
    for (int i = 0; i < 60; ++i) {
      const double mid = std::sqrt(low * high);
      (pick(mid).error > budget ? low : high) = mid;
    }
    Choice c = pick(high);
    c.lambda = high;
    if (c.bits < best.bits) best = c;
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: transform_prototype FILE [--error E] [--basis-bits B]\n");
    return 2;
  }
  CodecSettings settings;
  int basis_bits = 0;
  for (int i = 2; i < argc; i += 2) {
    if (i + 1 == argc)
      return std::fprintf(stderr, "transform_coding: %s needs a value\n", argv[i]), 2;
    else if (std::strcmp(argv[i], "--error") == 0)
      settings.target = std::atof(argv[i + 1]);
    else if (std::strcmp(argv[i], "--basis-bits") == 0)
      basis_bits = std::atoi(argv[i + 1]);
    else
      return std::fprintf(stderr, "transform_coding: unknown option %s\n", argv[i]), 2;
  }
  if (basis_bits != 0 && (basis_bits < 2 || basis_bits > 16))
    return std::fprintf(stderr, "transform_coding: --basis-bits 0 or 2..16\n"), 2;
  bench::ResidualTrajectories t;
  Status status = bench::residual_trajectories(argv[1], settings, t);
  if (!status.ok()) {
    std::fprintf(stderr, "transform_coding: %s: %s\n", argv[1], status.message().c_str());
    return 1;
  }
  const StreamContent& content = t.content;
  const size_t welded = content.welded_count, frames = content.frame_count(), vertices = content.vertex_count;
  const double steps[3] = {content.residual_step[0], content.residual_step[1], content.residual_step[2]};
  const double unit = (steps[0] + steps[1] + steps[2]) / 3;

  // Rows in units of the mean step; each welded vertex's errors count once per vertex of its group (KG counts all).
  Matrix rows = t.rows;
  std::vector<double> weight(welded * 3, 0.0);
  std::vector<uint32_t> first(welded, UINT32_MAX);
  for (uint32_t v = 0; v < vertices; ++v) {
    const uint32_t w = content.welded_index[v];
    if (first[w] == UINT32_MAX) first[w] = v;
    for (int axis = 0; axis < 3; ++axis) weight[w * 3 + axis] += 1;
  }
  for (Eigen::Index r = 0; r < rows.rows(); ++r) rows.row(r) *= steps[r % 3] / unit;

  // The budget: the squared error of the stream's own decoded frames, in unit².
  std::vector<FrameSequence> decoded;
  status = reconstruct_clips(content, t.base, t.clips[0].triangles, decoded);
  if (!status.ok()) return std::fprintf(stderr, "transform_coding: %s\n", status.message().c_str()), 1;
  double budget = 0;
  for (size_t c = 0; c < decoded.size(); ++c)
    for (size_t i = 0; i < decoded[c].positions.size(); ++i) {
      const double e = (double(decoded[c].positions[i]) - double(t.clips[c].positions[i])) / unit;
      budget += e * e;
    }
  const auto start = std::chrono::steady_clock::now();

  // Clusters' rows; the stream's basis and each cluster's own.
  const size_t clusters = content.cluster_count;
  std::vector<std::vector<Eigen::Index>> members(clusters);
  for (size_t w = 0; w < welded; ++w)
    for (Eigen::Index axis = 0; axis < 3; ++axis) members[content.labels[w]].push_back(Eigen::Index(w * 3) + axis);
  std::vector<size_t> sizes = {0};
  for (size_t m = 1; m <= frames; m = std::max(m + 1, m * 5 / 4)) sizes.push_back(m);
  const double bits_per_vector =
      double(frames) * (basis_bits ? basis_bits : 6) + 32;  // the estimate: entries at B bits, a scale
  const Matrix global_basis = pca_basis(rows);
  const Matrix global_coefficients = rows * global_basis.transpose();
  std::vector<Matrix> own_basis(clusters);
  std::vector<std::vector<double>> own_energy(clusters);
  std::vector<std::vector<Option>> options(clusters);
  for (size_t k = 0; k < clusters; ++k) {
    if (members[k].empty()) {
      options[k].push_back({});
      continue;
    }
    Matrix own(Eigen::Index(members[k].size()), Eigen::Index(frames));
    double total = 0;
    for (size_t i = 0; i < members[k].size(); ++i) {
      own.row(Eigen::Index(i)) = rows.row(members[k][i]);
      total += weight[size_t(members[k][i])] * rows.row(members[k][i]).squaredNorm();
    }
    options[k].push_back({0, 0, 0, 0, total});
    own_basis[k] = pca_basis(own);
    add_options(global_coefficients, members[k], weight, total, 1, sizes, bits_per_vector, options[k]);
    Matrix own_coefficients = Matrix::Zero(rows.rows(), own_basis[k].rows());
    for (size_t i = 0; i < members[k].size(); ++i)
      own_coefficients.row(members[k][i]) = own.row(Eigen::Index(i)) * own_basis[k].transpose();
    for (Eigen::Index i = 0; i < own_basis[k].rows(); ++i) {
      double e = 0;
      for (Eigen::Index r : members[k]) e += weight[size_t(r)] * own_coefficients(r, i) * own_coefficients(r, i);
      own_energy[k].push_back(e);
    }
    add_options(own_coefficients, members[k], weight, total, 2, sizes, bits_per_vector, options[k]);
  }
  double energy = 0;
  for (Eigen::Index r = 0; r < rows.rows(); ++r) energy += weight[size_t(r)] * rows.row(r).squaredNorm();
  const double seconds_options = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "%s --error %g: W=%zu F=%zu K=%zu | stream residual bytes %zu, stream %zu B | residual energy %.4g unit^2, error "
      "budget %.4g "
      "unit^2 (%.4g per value; unit = mean residual step %.4g, steps %.4g %.4g %.4g) | options %.1f s\n",
      argv[1], settings.target, welded, frames, clusters, t.report.bytes_residuals, t.stream.size(), energy, budget,
      budget / double(vertices * 3 * frames), unit, steps[0], steps[1], steps[2], seconds_options);

  // The three schemes: the stream's basis, the clusters' own, either per cluster.
  const char* names[3] = {"the stream's basis", "own bases", "either per cluster"};
  for (int scheme = 0; scheme < 3; ++scheme) {
    const bool allow_global = scheme != 1, allow_own = scheme != 0;
    double target = budget;
    Choice choice;
    double exact = 0;
    Matrix coefficients_q;  // per row, the quantized coefficients of its cluster's chosen vectors
    std::vector<QuantizedBasis> bases(clusters);
    QuantizedBasis global_q;
    for (int attempt = 0; attempt < 16; ++attempt) {
      choice = choose(options, target, sizes, bits_per_vector, allow_global, allow_own);
      if (std::isinf(choice.bits)) break;
      std::vector<double> global_energy(choice.global_vectors, 0.0);
      for (size_t k = 0; k < clusters; ++k)
        if (choice.per_cluster[k].source == 1)
          for (size_t i = 0; i < choice.per_cluster[k].m; ++i)
            for (Eigen::Index r : members[k])
              global_energy[i] +=
                  weight[size_t(r)] * global_coefficients(r, Eigen::Index(i)) * global_coefficients(r, Eigen::Index(i));
      global_q =
          quantize_basis(global_basis, choice.global_vectors, basis_bits, basis_steps(global_energy, choice.lambda));
      exact = 0;
      coefficients_q = Matrix::Zero(rows.rows(), Eigen::Index(frames));
      for (size_t k = 0; k < clusters; ++k) {
        const Option& o = choice.per_cluster[k];
        if (o.source == 2)
          bases[k] = quantize_basis(own_basis[k], o.m, basis_bits, basis_steps(own_energy[k], choice.lambda));
        const Matrix& b = o.source == 1 ? global_q.vectors : bases[k].vectors;
        const Matrix used = o.source == 0 ? Matrix() : Matrix(b.topRows(Eigen::Index(o.m)));
        Eigen::LDLT<Eigen::MatrixXd> gram;
        if (o.m > 0) gram.compute(used * used.transpose());
        for (Eigen::Index r : members[k]) {
          Eigen::RowVectorXd reconstructed = Eigen::RowVectorXd::Zero(Eigen::Index(frames));
          if (o.m > 0) {
            const Eigen::VectorXd c = gram.solve(Eigen::VectorXd(used * rows.row(r).transpose()));
            for (Eigen::Index i = 0; i < c.size(); ++i) coefficients_q(r, i) = double(std::llround(c(i) / o.step));
            reconstructed = coefficients_q.row(r).head(c.size()) * o.step * used;
          }
          exact += weight[size_t(r)] * (rows.row(r) - reconstructed).squaredNorm();
        }
      }
      if (exact <= budget) break;
      target *= std::pow(budget / exact, 1.5) * 0.999;
    }
    if (std::isinf(choice.bits) || exact > budget) {
      std::printf("  %s: no choice meets the budget\n", names[scheme]);
      continue;
    }

    // Coded: the side information, the bases two ways, the coefficients three ways.
    std::vector<uint8_t> side_bytes, basis_direct, basis_delta, coefficient_bytes[3];
    {
      RangeEncoder side(side_bytes);
      BitTreeModel source(2);
      UnsignedModel size;
      for (const Option& o : choice.per_cluster) {
        source.encode(side, uint32_t(o.source));
        if (o.source != 0) {
          size.encode(side, uint32_t(o.m));
          side.encode_direct_bits(uint32_t(std::lround(std::log2(o.step) * 16) & 0xFF), 8);  // a step in 1/16 octaves
        }
      }
      side.finish();
    }
    std::vector<const QuantizedBasis*> sent;
    if (choice.global_vectors > 0) sent.push_back(&global_q);
    for (size_t k = 0; k < clusters; ++k)
      if (choice.per_cluster[k].source == 2) sent.push_back(&bases[k]);
    {
      RangeEncoder direct(basis_direct), delta(basis_delta);
      SignedModel difference;
      for (const QuantizedBasis* b : sent)
        for (const std::vector<int>& entries : b->ints) {
          direct.encode_direct_bits(0, 32), delta.encode_direct_bits(0, 32);  // the scale
          int previous = 0;
          for (int e : entries) {
            if (basis_bits > 0) direct.encode_direct_bits(uint32_t(e) & ((1u << basis_bits) - 1), basis_bits);
            difference.encode(delta, e - previous);
            previous = e;
          }
        }
      direct.finish(), delta.finish();
    }
    // The coefficients in the residual loop's traversal order (breadth first over the base mesh), cluster by
    // cluster, vector by vector, axis by axis.
    const ResidualTraversal traversal = residual_traversal(content, t.clips[0].triangles);
    size_t coefficient_count = 0;
    for (int way = 0; way < 3; ++way) {
      RangeEncoder encoder(coefficient_bytes[way]);
      std::vector<SignedModel> models(64 * 4);
      for (size_t k = 0; k < clusters; ++k) {
        const Option& o = choice.per_cluster[k];
        for (size_t i = 0; i < o.m; ++i)
          for (size_t axis = 0; axis < 3; ++axis) {
            int64_t previous = 0;
            for (size_t p = 0; p < welded; ++p) {
              const uint32_t w = traversal.order[p];
              if (content.labels[w] != k) continue;
              const int64_t q = int64_t(coefficients_q(Eigen::Index(w * 3 + axis), Eigen::Index(i)));
              const size_t vector_context = std::min<size_t>(i, 63) * 4;
              if (way == 0) {
                models[vector_context].encode(encoder, int32_t(q));
              } else if (way == 1) {
                models[vector_context + size_t(std::min<int64_t>(std::llabs(previous), 3))].encode(encoder, int32_t(q));
              } else {
                double sum = 0;
                int count = 0;
                for (uint32_t j = traversal.earlier_offset[p]; j < traversal.earlier_offset[p + 1]; ++j) {
                  const uint32_t neighbour = traversal.order[traversal.earlier[j]];
                  if (content.labels[neighbour] != k) continue;
                  sum += coefficients_q(Eigen::Index(neighbour * 3 + axis), Eigen::Index(i));
                  ++count;
                }
                const int64_t predicted = count ? std::llround(sum / count) : 0;
                models[vector_context].encode(encoder, int32_t(q - predicted));
              }
              previous = q;
              if (way == 0) ++coefficient_count;
            }
          }
      }
      encoder.finish();
    }
    std::string used;
    size_t own_count = 0, global_count = 0, none = 0, own_vectors = 0, largest = 0;
    for (const Option& o : choice.per_cluster) {
      if (o.source == 0) ++none;
      if (o.source == 1) ++global_count;
      if (o.source == 2) ++own_count, own_vectors += o.m;
      largest = std::max(largest, o.m);
    }
    const size_t best_coefficients =
        std::min({coefficient_bytes[0].size(), coefficient_bytes[1].size(), coefficient_bytes[2].size()});
    const size_t basis_bytes = basis_bits > 0 ? std::min(basis_direct.size(), basis_delta.size()) : basis_delta.size();
    const size_t total = side_bytes.size() + basis_bytes + best_coefficients;
    std::printf(
        "  %s: %zu B (%.1f %% of the stream's residuals) | estimate %.0f B | side %zu B | bases %zu B at "
        "%d bits, %zu B as differences (stream basis %zu vectors, own %zu vectors in %zu clusters; %zu "
        "clusters on the stream's, %zu none; m at most %zu) | coefficients %zu: %zu B per vector, %zu B in the "
        "previous's "
        "context, %zu B predicted from earlier neighbours | error %.4g (budget %.4g)\n",
        names[scheme], total, 100.0 * double(total) / double(t.report.bytes_residuals), choice.bits / 8,
        side_bytes.size(), basis_direct.size(), basis_bits, basis_delta.size(), choice.global_vectors, own_vectors,
        own_count, global_count, none, largest, coefficient_count, coefficient_bytes[0].size(),
        coefficient_bytes[1].size(), coefficient_bytes[2].size(), exact, budget);
  }
  return 0;
}
