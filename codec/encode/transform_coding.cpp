#include "encode/transform_coding.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <future>
#include <memory>
#include <optional>
#include <system_error>
#include <unordered_map>
#include <utility>

#include "common/frame_sequence.h"
#include "common/parallel.h"
#include "common/reconstruction.h"
#include "common/stream_format.h"
#include "decode/frame_decoder.h"
#include "decode/transform_residuals.h"
#include "encode/largest_eigenvectors.h"
#include "encode/metrics.h"
#include "encode/rate_distortion.h"
#include "encode/transform_symbols.h"

namespace segmorph {
namespace {

using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// The residual trajectories, W × 3 rows of F: floats, as the frames are (half the memory of doubles on large meshes).
using Rows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Above this many frames the bases' eigenproblems (F × F) are not tried.
constexpr size_t kMaxTransformFrames = 2048;
// The coefficient steps tried: kSteps from kFinestStep to kCoarsestStep times the budget's step (the uniform
// quantizer step whose noise alone would spend the whole budget on every value).
constexpr int kSteps = 24;
constexpr double kFinestStep = 0.1, kCoarsestStep = 24;
// A basis vector's estimated price while choosing: its entries at this many bits each, and its step.
constexpr double kEstimatedBitsPerEntry = 4;
// The stream's basis is first found capped (pca_basis_of) when its eigenproblem is at least this large: choices use few
// of its vectors (at most 27 of the 377 the energy keeps on the chicken), and the uncapped basis, its projections and
// options cost a third of the encode there.
constexpr Eigen::Index kCappedBasisFrom = 64;

// Evenly spaced vertices of `rows` (their three axes' rows side by side, as members and the stream list them), at most
// `most` rows in all (all of them when there are no more): the rows that inform a basis and its options. Whole
// vertices, so that no stride can pick one axis only.
std::vector<Eigen::Index> sample(const std::vector<Eigen::Index>& rows, size_t most) {
  if (rows.size() <= most) return rows;
  const uint64_t vertices = rows.size() / 3, picked = std::max<size_t>(most / 3, 1);
  std::vector<Eigen::Index> out;
  out.reserve(size_t(picked) * 3);
  for (uint64_t j = 0; j < picked; ++j) {
    const size_t first = size_t(j * vertices / picked) * 3;
    out.insert(out.end(), rows.begin() + ptrdiff_t(first), rows.begin() + ptrdiff_t(first + 3));
  }
  return out;
}

// The rows `which` as doubles, with their weights times `scale` (how many rows each stands for).
void gather(const Rows& rows, const std::vector<double>& weight, const std::vector<Eigen::Index>& which, double scale,
            Matrix& out, std::vector<double>& out_weight) {
  out.resize(Eigen::Index(which.size()), rows.cols());
  out_weight.resize(which.size());
  for (size_t i = 0; i < which.size(); ++i) {
    out.row(Eigen::Index(i)) = rows.row(which[i]).cast<double>();
    out_weight[i] = weight[size_t(which[i])] * scale;
  }
}

// The squared error of the frames a decoder makes of a version-4 `content` against the problem's clips, none kept:
// each frame's sum (in squared_error()'s order within the frame), then the frames' in order. Version-4 frames depend
// on none before them, so ranges of them decode on threads of their own, each with a decoder of its own (8 bytes per
// coefficient): on one thread when that would take more than 256 MiB a thread. False when the content does not
// decode.
bool decoded_error(const EncodeProblem& problem, const StreamContent& content, double& error) {
  std::vector<const float*> originals;
  for (const FrameSequence& clip : problem.clips)
    for (size_t j = 0; j < clip.frame_count; ++j) originals.push_back(clip.frame(j));
  std::vector<double> frame_error(originals.size(), 0.0);
  std::vector<char> failed(originals.size(), 0);
  const size_t threads = content.coefficient_symbols.size() * sizeof(double) > (size_t(256) << 20)
                             ? 1
                             : thread_count(problem.settings.threads);
  parallel_ranges(originals.size(), threads, [&](size_t begin, size_t end) {
    FrameLoop loop(content, problem.base, problem.clips[0].triangles);
    if (!loop.status().ok()) {
      failed[begin] = 1;
      return;
    }
    const size_t frame_floats = size_t(content.vertex_count) * 3;
    std::vector<float> frames(loop.block_frames() * frame_floats);
    const FrameLoop::Residuals none;  // version 4 reads no residual symbols
    for (size_t f = begin; f < end;) {
      const size_t count = std::min(end - f, loop.block_frames());
      if (!loop.decode(f, none, count, frames.data()).ok()) {
        failed[f] = 1;
        return;
      }
      for (size_t s = 0; s < count; ++s)
        add_squared_error(originals[f + s], &frames[s * frame_floats], frame_floats, frame_error[f + s]);
      f += count;
    }
  });
  if (std::find(failed.begin(), failed.end(), 1) != failed.end()) return false;
  error = 0;
  for (double e : frame_error) error += e;
  return true;
}

// The basis sizes tried: 0, 1, 2, ... then about 25 % apart, up to the format's kMaxBasisSize.
std::vector<size_t> basis_sizes(size_t most) {
  std::vector<size_t> sizes = {0};
  most = std::min<size_t>(most, format::kMaxBasisSize);
  for (size_t m = 1; m <= most; m = std::max(m + 1, m * 5 / 4)) sizes.push_back(m);
  return sizes;
}

// The orthonormal PCA basis of the rows (each weighted), as rows, by decreasing energy: the eigenvectors of
// rowsᵀ W rows (F × F), or, with fewer rows than frames, of rows W rowsᵀ (n × n) taken back through the rows (the
// same vectors, for a smaller eigenproblem). Only the vectors before the point where the energy left (the
// eigenvalues after them) is below `negligible`, and none of no energy: the eigenvalues decide how many, and only
// those vectors are computed (LargestEigenvectors, which signs each eigenvector so that its largest entry is positive;
// in the dual form that is the n-vector's sign, before it is taken back through the rows). `capped`: at most the
// vectors LargestEigenvectors finds one by one (a quarter of the eigenproblem's size, when that is at least
// kCappedBasisFrom), and whether that cap kept fewer than the energy would into *capped; the first vectors are then
// those of an uncapped basis that also finds them one by one.
//
// pca_problem takes the rows already scaled by the square roots of their weights: the eigenproblem, which depends on
// the rows alone; pca_basis_of its vectors for a `negligible` energy (and `capped`), as often as asked.
struct PcaProblem {
  bool dual = false;
  Eigen::MatrixXd scaled;  // dual form only: the rows, to take the vectors back through
  std::unique_ptr<LargestEigenvectors> solver;
  Eigen::Index columns = 0;
};

PcaProblem pca_problem(Eigen::MatrixXd&& scaled) {
  PcaProblem out;
  out.dual = scaled.rows() < scaled.cols();
  out.columns = scaled.cols();
  // The Gram matrix's lower triangle only (the solver reads no more): half the products of a full one.
  const Eigen::Index n = out.dual ? scaled.rows() : scaled.cols();
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
  if (out.dual)
    gram.selfadjointView<Eigen::Lower>().rankUpdate(scaled);
  else
    gram.selfadjointView<Eigen::Lower>().rankUpdate(scaled.transpose());
  out.solver = std::make_unique<LargestEigenvectors>(gram);
  if (out.dual) out.scaled = std::move(scaled);
  return out;
}

Matrix pca_basis_of(const PcaProblem& problem, double negligible, bool* capped = nullptr) {
  const LargestEigenvectors& solver = *problem.solver;
  const Eigen::VectorXd& values = solver.values();  // ascending
  const Eigen::Index n = values.size();
  const double largest = std::max(values.maxCoeff(), 0.0);
  double left = std::max(values.sum(), 0.0);
  Eigen::Index kept = 0;
  for (Eigen::Index i = values.size() - 1; i >= 0 && left > negligible && values(i) > largest * 1e-12; --i, ++kept)
    left -= values(i);
  if (capped != nullptr) {
    const Eigen::Index most = n >= kCappedBasisFrom ? n / 4 : n;
    *capped = kept > most;
    kept = std::min(kept, most);
  }
  const Eigen::MatrixXd vectors = solver.vectors(kept);
  Matrix basis(kept, problem.columns);
  for (Eigen::Index j = 0; j < kept; ++j) {
    Eigen::VectorXd vector =
        problem.dual ? Eigen::VectorXd(problem.scaled.transpose() * vectors.col(j)) : Eigen::VectorXd(vectors.col(j));
    vector /= vector.norm();
    basis.row(j) = vector.transpose();
  }
  return basis;
}

Matrix pca_basis(const Matrix& rows, const std::vector<double>& weight, double negligible) {
  Eigen::MatrixXd scaled = rows;
  for (Eigen::Index r = 0; r < rows.rows(); ++r) scaled.row(r) *= std::sqrt(weight[size_t(r)]);
  return pca_basis_of(pca_problem(std::move(scaled)), negligible);
}

struct Option {
  uint32_t source = format::kBasisNone;
  size_t m = 0;
  double step = 0, bits = 0, error = 0;
};

// Zeroth-order bits of the n values `column` quantized with step `step`, and their squared quantization error (each
// weighted) into `quantization`.
double column_bits(const double* column, size_t n, double step, const std::vector<double>& weight,
                   double& quantization, std::vector<uint32_t>& counts) {
  const double inverse = 1 / step;
  double largest = 0;
  for (size_t r = 0; r < n; ++r) largest = std::max(largest, std::abs(column[r]));
  const double reach = largest * inverse;
  auto add = [&](uint32_t count) { return count ? -double(count) * std::log2(double(count) / double(n)) : 0.0; };
  double bits = 0, error = 0;
  if (reach <= 4.0 * double(n) + 64) {  // a histogram over the values' range
    const int64_t span = int64_t(reach + 0.5) + 1;
    counts.assign(size_t(2 * span + 1), 0);
    for (size_t r = 0; r < n; ++r) {
      const double c = column[r];
      const int64_t index = quantizer_index(c * inverse);
      const double q = double(index);
      ++counts[size_t(index + span)];
      error += weight[r] * (c - q * step) * (c - q * step);
    }
    for (uint32_t count : counts) bits += add(count);
    quantization = error;
    return bits;
  }
  std::unordered_map<int64_t, uint32_t> map;
  for (size_t r = 0; r < n; ++r) {
    const double c = column[r];
    const int64_t index = quantizer_index(c * inverse);
    const double q = double(index);
    ++map[index];
    error += weight[r] * (c - q * step) * (c - q * step);
  }
  for (const auto& entry : map) bits += add(entry.second);
  quantization = error;
  return bits;
}

// The options of one cluster's rows in one basis (coefficients: the rows' projections, by decreasing energy): for
// each basis size and step, the zeroth-order bits of the quantized coefficients (a histogram per vector) and the
// squared error (dropped energy plus quantization), each row weighted. Vectors past the point where what is left of
// the rows' energy is below `negligible` are not tried; `energy` receives the energy of each vector tried. The rows
// may be a sample, each standing for `scale` rows (their weights scaled alike): the bits are scaled by it.
void add_options(const Matrix& coefficients, const std::vector<double>& weight, double scale, double total,
                 uint32_t source, double unit, double bits_per_vector, double negligible, std::vector<Option>& options,
                 std::vector<double>& energy) {
  const size_t n = size_t(coefficients.rows());
  energy.clear();
  double left = total;
  for (Eigen::Index i = 0; i < coefficients.cols() && left > negligible; ++i) {
    double e = 0;
    for (size_t r = 0; r < n; ++r) e += weight[r] * coefficients(Eigen::Index(r), i) * coefficients(Eigen::Index(r), i);
    energy.push_back(e);
    left -= e;
  }
  const std::vector<size_t> sizes = basis_sizes(energy.size());
  // The vectors the sizes use, each a column of its own (the histograms read them whole, a step at a time).
  const Eigen::MatrixXd columns = coefficients.leftCols(Eigen::Index(sizes.back()));
  std::vector<uint32_t> counts;
  for (int d = 0; d < kSteps; ++d) {
    const double step = double(float(unit * kFinestStep * std::pow(kCoarsestStep / kFinestStep, d / (kSteps - 1.0))));
    double bits = 0, kept = 0, quantization = 0;
    size_t m = 0;
    for (size_t size : sizes) {
      if (size == 0) continue;
      for (; m < size; ++m) {
        double q = 0;
        bits += column_bits(columns.col(Eigen::Index(m)).data(), n, step, weight, q, counts);
        quantization += q;
        kept += energy[m];
      }
      options.push_back({source, m, step,
                         bits * scale + (source == format::kBasisOwn ? double(m) * bits_per_vector : 0) + 40,
                         std::max(total - kept, 0.0) + quantization});
    }
  }
}

struct Choice {
  std::vector<Option> per_cluster;
  size_t stream_vectors = 0;
  double bits = INFINITY, error = 0, lambda = 0;
};

// The options minimizing bits + lambda × error per cluster, lambda bisected so that the error is at most `budget`;
// the stream's basis charged once, its size the largest any cluster uses (each of `sizes` tried as the most a
// cluster may use: on up to `threads` threads, the first of the fewest bits chosen, as in order).
Choice choose(const std::vector<std::vector<Option>>& options, double budget, const std::vector<size_t>& sizes,
              double bits_per_vector, size_t threads) {
  // Each cluster's options as the searches read them: first those any size allows (none, its own basis's), then
  // those in the stream's basis by basis size (stable), so that the options a size allows are a prefix; each with
  // its place in the list, which breaks ties (the first in the list of the least bits + lambda × error is chosen).
  struct Listed {
    std::vector<double> bits, error;
    std::vector<uint32_t> place;
    std::vector<size_t> allowed;  // per size: how many of the options it allows
  };
  std::vector<Listed> listed(options.size());
  for (size_t k = 0; k < options.size(); ++k) {
    const std::vector<Option>& list = options[k];
    assert(!list.empty() && list[0].source == format::kBasisNone);  // the searches start from it
    std::vector<uint32_t> order(list.size());
    for (uint32_t i = 0; i < list.size(); ++i) order[i] = i;
    auto in_stream = [&](uint32_t i) { return list[i].source == format::kBasisStream; };
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      if (in_stream(a) != in_stream(b)) return !in_stream(a);
      return in_stream(a) && list[a].m < list[b].m;
    });
    Listed& l = listed[k];
    for (uint32_t i : order) l.bits.push_back(list[i].bits), l.error.push_back(list[i].error), l.place.push_back(i);
    for (size_t most : sizes) {
      size_t count = 0;
      for (uint32_t i : order) count += !(in_stream(i) && list[i].m > most);
      l.allowed.push_back(count);
    }
  }
  // The choice at lambda of clusters using at most sizes[j] of the stream's vectors; the options chosen only when
  // `keep` (the bisection needs the sums alone).
  auto pick = [&](double lambda, size_t j, bool keep) {
    Choice c;
    c.bits = 0;
    if (keep) c.per_cluster.reserve(options.size());
    for (size_t k = 0; k < options.size(); ++k) {
      const Listed& l = listed[k];
      size_t chosen = 0;  // the none option, first in the list
      double least = l.bits[0] + lambda * l.error[0];
      for (size_t i = 1; i < l.allowed[j]; ++i) {
        const double value = l.bits[i] + lambda * l.error[i];
        if (value < least || (value == least && l.place[i] < l.place[chosen])) least = value, chosen = i;
      }
      const Option& o = options[k][l.place[chosen]];
      if (keep) c.per_cluster.push_back(o);
      c.bits += o.bits, c.error += o.error;
      if (o.source == format::kBasisStream) c.stream_vectors = std::max(c.stream_vectors, o.m);
    }
    c.bits += double(c.stream_vectors) * bits_per_vector;
    c.lambda = lambda;
    return c;
  };
  std::vector<Choice> per_size(sizes.size());  // bits infinite where no lambda meets the budget
  parallel_items(sizes.size(), threads, [&](size_t j) {
    double low = 1e-12, high = 1e12;
    if (pick(high, j, false).error > budget) return;
    for (int i = 0; i < 80 && high > low * (1 + 1e-6); ++i) {
      const double middle = std::sqrt(low * high);
      (pick(middle, j, false).error > budget ? low : high) = middle;
    }
    per_size[j] = pick(high, j, true);
  });
  Choice best;
  for (Choice& c : per_size)
    if (c.bits < best.bits) best = std::move(c);
  return best;
}

// Whether a choice made with the stream's basis capped at `cap` vectors might have been another with more of them:
// none met the budget, or the choice uses the last basis size below the cap, or, for a cluster whose options reached
// the cap (rather than its energy criterion), its best option of the most stream vectors still costs less (bits +
// lambda × error) than its best of the size before: the vectors near the cap still pay, and those after them, of
// less energy each in the stream, might too (a heuristic: a cluster's share of them need not fall). Never when the
// cap reaches the largest basis size the format allows: the uncapped basis would offer no other size.
bool may_want_more(const Choice& choice, const std::vector<std::vector<Option>>& options,
                   const std::vector<std::vector<double>>& stream_energy, size_t cap) {
  if (cap >= basis_sizes(format::kMaxBasisSize).back()) return false;  // every size the format allows was there
  if (std::isinf(choice.bits)) return true;
  const size_t used = choice.stream_vectors;
  if (std::max(used + 1, used * 5 / 4) > cap) return true;
  const double lambda = choice.lambda;
  for (size_t k = 0; k < options.size(); ++k) {
    if (stream_energy[k].size() < cap) continue;  // its options are those it has uncapped
    // Its stream options' sizes (add_options): 0, 1, 2, ... up to its vectors tried, at least the cap's 16.
    const std::vector<size_t> sizes = basis_sizes(stream_energy[k].size());
    const size_t most = sizes.back(), before = sizes[sizes.size() - 2];
    double at_most = INFINITY, at_before = INFINITY;
    for (const Option& o : options[k]) {
      if (o.source != format::kBasisStream) continue;
      const double cost = o.bits + lambda * o.error;
      if (o.m == most) at_most = std::min(at_most, cost);
      if (o.m == before) at_before = std::min(at_before, cost);
    }
    if (at_most < at_before * (1 - 1e-9)) return true;  // less by more than rounding
  }
  return false;
}

// A basis as the stream carries it: the first m vectors, each with the step that minimizes bits + lambda × error
// for a vector whose coefficients have squared norm `energy` (an entry's error reaches the frames through them):
// F log2(1 / step) + lambda energy F step² / 12 is least at step² = 6 / (lambda ln 2 energy); at most half the
// vector's largest entry, so that no vector quantizes to zero.
StreamContent::Basis quantized_basis(const Matrix& basis, size_t m, const std::vector<double>& energy, double lambda) {
  StreamContent::Basis out;
  const size_t frames = size_t(basis.cols());
  for (size_t i = 0; i < m; ++i) {
    const Eigen::Index row = Eigen::Index(i);
    const double largest = basis.row(row).cwiseAbs().maxCoeff();
    double step = std::sqrt(6 / (lambda * std::log(2.0) * std::max(energy[i], 1e-300)));
    step = std::clamp(step, largest * 1e-6, largest / 2);
    const float stored = float(step);
    out.step.push_back(stored);
    for (size_t f = 0; f < frames; ++f)
      out.entries.push_back(int32_t(std::lround(basis(row, Eigen::Index(f)) / double(stored))));
  }
  return out;
}

// The decoder's values of a basis's first m vectors (m × F).
Matrix basis_values(const StreamContent::Basis& basis, size_t m, size_t frames) {
  Matrix values(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(frames));
  for (size_t i = 0; i < m; ++i)
    for (size_t f = 0; f < frames; ++f)
      values(Eigen::Index(i), Eigen::Index(f)) = double(basis.entries[i * frames + f]) * double(basis.step[i]);
  return values;
}

// The trajectories to code: row w × 3 + a, the frames' positions minus the prediction of the content's quantized
// motion and weights.
Rows residual_rows(const EncodeProblem& problem, const StreamContent& content) {
  const size_t welded = content.welded_count, frames = content.frame_count();
  Rows rows(Eigen::Index(welded * 3), Eigen::Index(frames));
  const FramePredictions predictions(content, problem.base_welded);
  std::vector<double> predicted(welded * 3);
  for (size_t f = 0; f < frames; ++f) {
    predictions.predict(f, predicted.data());
    const float* positions = &problem.trajectories.positions[f * welded * 3];
    for (size_t i = 0; i < welded * 3; ++i)
      rows(Eigen::Index(i), Eigen::Index(f)) = float(double(positions[i]) - predicted[i]);
  }
  return rows;
}

// `choice`'s bases, quantized, and its per-cluster sources, sizes and steps into `content`.
void with_bases(const Choice& choice, const Matrix& stream_basis, const std::vector<std::vector<double>>& stream_energy,
                const std::vector<Matrix>& own_basis, const std::vector<std::vector<double>>& own_energy,
                StreamContent& content) {
  const size_t clusters = content.cluster_count;
  std::vector<double> energy(choice.stream_vectors, 0.0);
  for (size_t k = 0; k < clusters; ++k)
    if (choice.per_cluster[k].source == format::kBasisStream)
      for (size_t i = 0; i < choice.per_cluster[k].m; ++i) energy[i] += stream_energy[k][i];
  content.stream_basis = quantized_basis(stream_basis, choice.stream_vectors, energy, choice.lambda);
  content.basis_source.assign(clusters, format::kBasisNone);
  content.basis_size.assign(clusters, 0);
  content.coefficient_step.assign(clusters, 0.0f);
  content.own_basis.assign(clusters, StreamContent::Basis());
  for (size_t k = 0; k < clusters; ++k) {
    const Option& o = choice.per_cluster[k];
    content.basis_source[k] = o.source;
    content.basis_size[k] = uint32_t(o.m);
    content.coefficient_step[k] = float(o.step);
    if (o.source == format::kBasisOwn)
      content.own_basis[k] = quantized_basis(own_basis[k], o.m, own_energy[k], choice.lambda);
  }
}

// The coefficients of every cluster's rows: least squares against its basis as the decoder has it (stream_values:
// the stream basis's), then quantized by its step. False when one lies beyond the format's limit.
bool fit_coefficients(const EncodeProblem& problem, const StreamContent& content, const Rows& rows,
                      const std::vector<std::vector<Eigen::Index>>& members, const Matrix& stream_values,
                      TransformCoefficients& coefficients) {
  const size_t frames = content.frame_count();
  coefficients = transform_layout(content);
  for (size_t k = 0; k < content.cluster_count; ++k) {
    const size_t m = content.basis_size[k];
    if (m == 0) continue;
    const Matrix values = content.basis_source[k] == format::kBasisOwn ? basis_values(content.own_basis[k], m, frames)
                                                                       : Matrix(stream_values.topRows(Eigen::Index(m)));
    const Eigen::LDLT<Eigen::MatrixXd> gram(values * values.transpose());
    const double step = double(content.coefficient_step[k]);
    std::vector<char> fits(members[k].size(), 1);  // per row: every coefficient within the format's limit
    parallel_ranges(members[k].size(), thread_count(problem.settings.threads), [&](size_t begin, size_t end) {
      for (size_t j = begin; j < end; ++j) {
        const Eigen::Index r = members[k][j];
        const Eigen::VectorXd c = gram.solve(Eigen::VectorXd(values * rows.row(r).transpose().cast<double>()));
        const size_t w = size_t(r) / 3, a = size_t(r) % 3;
        for (size_t i = 0; i < m; ++i) {
          const double q = std::round(c(Eigen::Index(i)) / step);
          if (!(std::abs(q) <= double(format::kMaxTransformValue))) fits[j] = 0;
          coefficients.values[coefficients.offset[w] + a * m + i] = fits[j] ? int32_t(q) : 0;
        }
      }
    });
    if (std::find(fits.begin(), fits.end(), 0) != fits.end()) return false;
  }
  return true;
}

// What every candidate shares: the content without the residual loop (its symbols are as large as the frames).
void as_transform_content(StreamContent& content) {
  content.flags &= uint8_t(~format::kResidualLoopFlags);
  content.transform = true;
  content.residuals = std::vector<int64_t>();
  content.narrow_residuals = std::vector<int32_t>();
  for (float& step : content.residual_step) step = 0;
}

}  // namespace

struct TransformPrelude {
  Rows rows;                   // residual_rows
  std::vector<double> weight;  // each row's: its welded vertex's multiplicity
  // The stream basis's eigenproblem, when made ahead: last, so that it is destroyed first (std::async's state waits for
  // its thread, which reads the rows).
  std::shared_future<PcaProblem> stream;

  // The rows and weights of a content as_transform_content made.
  TransformPrelude(const EncodeProblem& problem, const StreamContent& content)
      : rows(residual_rows(problem, content)), weight(size_t(content.welded_count) * 3) {
    for (size_t i = 0; i < weight.size(); ++i) weight[i] = double(problem.multiplicity[i / 3]);
  }

  // The stream basis's eigenproblem: of at most most_rows evenly spaced rows, gathered straight into their scaled
  // doubles (the same values gather() and pca_basis() make: one copy, not two).
  PcaProblem stream_problem(size_t most_rows) const {
    std::vector<Eigen::Index> all(size_t(rows.rows()));
    for (size_t i = 0; i < all.size(); ++i) all[i] = Eigen::Index(i);
    const std::vector<Eigen::Index> which = sample(all, most_rows);
    const double scale = double(all.size()) / double(which.size());
    Eigen::MatrixXd scaled(Eigen::Index(which.size()), rows.cols());
    for (size_t i = 0; i < which.size(); ++i)
      scaled.row(Eigen::Index(i)) = rows.row(which[i]).cast<double>() * std::sqrt(weight[size_t(which[i])] * scale);
    return pca_problem(std::move(scaled));
  }
};

std::shared_ptr<const TransformPrelude> transform_prelude(const EncodeProblem& problem, StreamContent content,
                                                          bool own_thread) {
  if (content.frame_count() > kMaxTransformFrames) return nullptr;
  as_transform_content(content);
  auto prelude = std::make_shared<TransformPrelude>(problem, content);
  auto make = [prelude = prelude.get(), most_rows = problem.settings.transform_sample_rows] {
    return prelude->stream_problem(most_rows);
  };
  try {
    prelude->stream = std::async(own_thread ? std::launch::async : std::launch::deferred, make).share();
  } catch (const std::system_error&) {  // no thread to start: made where it is first needed
    prelude->stream = std::async(std::launch::deferred, make).share();
  }
  return prelude;
}

bool try_transform_stream(const EncodeProblem& problem, StreamContent content, double budget,
                          std::vector<uint8_t>& stream, StreamSizes& sizes, const TransformPrelude* prelude) {
  const size_t welded = content.welded_count, frames = content.frame_count(), clusters = content.cluster_count;
  if (frames > kMaxTransformFrames || !(budget > 0)) return false;
  as_transform_content(content);
  std::shared_ptr<const TransformPrelude> own_prelude;
  if (prelude == nullptr) {
    own_prelude = std::make_shared<TransformPrelude>(problem, content);
    prelude = own_prelude.get();
  }
  const Rows& rows = prelude->rows;
  const std::vector<double>& weight = prelude->weight;
  const double unit = std::sqrt(12 * budget / (3.0 * double(content.vertex_count) * double(frames)));
  const double bits_per_vector = double(frames) * kEstimatedBitsPerEntry + 32;
  const double negligible = budget * 1e-4;  // energy a cluster may leave in vectors not tried
  const size_t most_rows = problem.settings.transform_sample_rows;

  // Each cluster's rows; the stream's basis and the cluster's own, each from at most most_rows rows; the options.
  std::vector<std::vector<Eigen::Index>> members(clusters);
  for (size_t w = 0; w < welded; ++w)
    for (Eigen::Index a = 0; a < 3; ++a) members[content.labels[w]].push_back(Eigen::Index(w * 3) + a);
  // Two rounds of items on the threads, each item's work its own: first the stream's basis (the one largest
  // eigenproblem) and each cluster's own basis and options, then each cluster's options in the stream's basis (which
  // needs it). Larger clusters first, so that no thread is left with a large one at the end. Each cluster's options
  // are then listed as they always are: none, in the stream's basis, in its own. The stream's basis is capped at
  // first (pca_basis_of); should a choice reach the cap, the stream's basis and options are found again uncapped, as
  // they are where there is no cap, and the choice made again.
  Matrix stream_basis;
  bool stream_capped = false;
  std::vector<Matrix> own_basis(clusters);
  std::vector<std::vector<double>> own_energy(clusters), stream_energy(clusters);
  std::vector<std::vector<Option>> options(clusters), own_options(clusters);
  std::vector<size_t> order(clusters);
  for (size_t k = 0; k < clusters; ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return members[a].size() > members[b].size(); });
  // The cluster's rows that inform its options (a sample of at most most_rows), each standing for `scale` rows, and
  // their weighted energy. Gathered again in the second round rather than kept from the first: kept, every cluster's
  // sample would be held at once (up to most_rows × F doubles each).
  struct Sampled {
    Matrix rows;
    std::vector<double> weight;
    double scale = 1, total = 0;
  };
  auto sampled_rows = [&](size_t k) {
    // The energy the options leave is the sample's less what they keep of it: both from the same rows, whose
    // estimate of the cluster's is then unbiased (the sample's share of the whole is not).
    const std::vector<Eigen::Index> which = sample(members[k], most_rows);
    Sampled out;
    out.scale = double(members[k].size()) / double(which.size());
    gather(rows, weight, which, out.scale, out.rows, out.weight);
    for (size_t i = 0; i < which.size(); ++i) out.total += out.weight[i] * out.rows.row(Eigen::Index(i)).squaredNorm();
    return out;
  };
  const size_t threads = thread_count(problem.settings.threads);
  // The stream basis's eigenproblem: the prelude's (waited for), else made here once (the uncapped basis reads it
  // again).
  std::optional<PcaProblem> stream_problem;
  auto find_stream_basis = [&](bool capped) {
    if (!prelude->stream.valid() && !stream_problem) stream_problem.emplace(prelude->stream_problem(most_rows));
    stream_basis = pca_basis_of(prelude->stream.valid() ? prelude->stream.get() : *stream_problem, negligible,
                                capped ? &stream_capped : nullptr);
  };
  parallel_items(clusters + 1, threads, [&](size_t item) {
    if (item == 0) {
      find_stream_basis(true);
      return;
    }
    const size_t k = order[item - 1];
    if (members[k].empty()) return;
    const Sampled own = sampled_rows(k);
    own_basis[k] = pca_basis(own.rows, own.weight, negligible);
    const Matrix in_own = own.rows * own_basis[k].transpose();
    add_options(in_own, own.weight, own.scale, own.total, format::kBasisOwn, unit, bits_per_vector, negligible,
                own_options[k], own_energy[k]);
  });
  if (!stream_capped) stream_problem.reset();  // not read again
  auto list_options = [&](size_t item) {
    const size_t k = order[item];
    options[k].clear();
    if (members[k].empty()) {
      options[k].push_back({format::kBasisNone, 0, 0, 8, 0.0});
      return;
    }
    const Sampled own = sampled_rows(k);
    options[k].push_back({format::kBasisNone, 0, 0, 8, own.total});
    const Matrix in_stream = own.rows * stream_basis.transpose();
    add_options(in_stream, own.weight, own.scale, own.total, format::kBasisStream, unit, bits_per_vector, negligible,
                options[k], stream_energy[k]);
    options[k].insert(options[k].end(), own_options[k].begin(), own_options[k].end());
  };
  parallel_items(clusters, threads, list_options);
  // Choose, then measure the decoder's frames exactly; tighten the budget until they meet it.
  const std::vector<size_t> basis_size_list = basis_sizes(frames);
  double target = budget;
  StreamContent transformed;
  for (int attempt = 0; attempt < 8; ++attempt) {
    Choice choice = choose(options, target, basis_size_list, bits_per_vector, threads);
    if (stream_capped && may_want_more(choice, options, stream_energy, size_t(stream_basis.rows()))) {
      stream_capped = false;
      find_stream_basis(false);
      stream_problem.reset();
      parallel_items(clusters, threads, list_options);
      choice = choose(options, target, basis_size_list, bits_per_vector, threads);
    }
    if (std::isinf(choice.bits)) return false;
    transformed = content;
    with_bases(choice, stream_basis, stream_energy, own_basis, own_energy, transformed);
    const Matrix stream_values = basis_values(transformed.stream_basis, choice.stream_vectors, frames);
    // The format's limits on the bases' entries and the coefficients (beyond them, the residual loop stays).
    uint64_t vectors = choice.stream_vectors, count = 0;
    for (size_t k = 0; k < clusters; ++k) {
      if (transformed.basis_source[k] == format::kBasisOwn) vectors += transformed.basis_size[k];
      count += uint64_t(transformed.basis_size[k]) * members[k].size();  // members: 3 rows per welded vertex
    }
    if (vectors * frames > format::kMaxBasisEntries || count > format::kMaxTransformCoefficients) return false;
    TransformCoefficients coefficients;
    if (!fit_coefficients(problem, transformed, rows, members, stream_values, coefficients)) return false;
    transformed.coefficient_symbols = transform_symbols(transformed, problem.traversal, coefficients);
    // The frames as the decoder makes them, and their error.
    double error = 0;
    if (!decoded_error(problem, transformed, error)) return false;
    if (error <= budget) {
      stream.clear();
      write_stream(transformed, problem.base, stream, &sizes);
      // The format's bound on the frames a stream of its length may claim (a stream of almost no residuals on
      // many vertices and frames can fall below it).
      return uint64_t(welded) * frames <=
             (uint64_t(stream.size() - format::kHeaderBytes) + 4) * format::kMaxVertexFramesPerByte;
    }
    // Tighter by the miss, and at least below the estimate of this choice scaled by it: a choice that does not
    // change would miss again (an estimate from a sample can miss by more than the first factor moves it).
    target *= std::pow(budget / error, 1.5);
    if (choice.error > 0) target = std::min(target, choice.error * (budget / error));
    target *= 0.999;
  }
  return false;
}

}  // namespace segmorph
