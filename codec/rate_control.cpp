#include "rate_control.h"

#include "stream_format.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace segmorph {
namespace {

// Estimated bits of a symbol stream coded with adaptive contexts: its conditional entropy given the context
// (the magnitude class of the same vertex's previous symbol, as the stream's coder uses), plus the cost of
// learning each context's distribution (half a bit per distinct symbol and context, roughly).
struct EntropyCounter {
  static constexpr int64_t kRange = 512;  // symbols in [−512, 512] are counted; larger ones are estimated
  std::vector<double> counts = std::vector<double>(3 * (2 * kRange + 1), 0.0);
  double total[3] = {0, 0, 0};
  double large_bits = 0;

  void add(int context, int64_t symbol) {
    if (symbol >= -kRange && symbol <= kRange) {
      counts[size_t(context * (2 * kRange + 1) + (symbol + kRange))] += 1;
      total[context] += 1;
    } else {
      // Length class and leading bits adaptive, the rest raw: about 2 log2|k| bits.
      large_bits += 2 * std::log2(double(symbol < 0 ? -symbol : symbol)) + 2;
    }
  }
  double bits() const {
    double sum = large_bits;
    for (int c = 0; c < 3; ++c) {
      if (total[c] == 0) continue;
      for (int64_t j = 0; j < 2 * kRange + 1; ++j) {
        const double count = counts[size_t(c * (2 * kRange + 1) + j)];
        if (count == 0) continue;
        sum -= count * std::log2(count / total[c]);
        sum += 0.5 * std::log2(1 + total[c]);  // learning the distribution
      }
    }
    return sum;
  }
};

}  // namespace

std::vector<double> candidate_steps(double around) {
  std::vector<double> steps;
  for (int j = -24; j <= 24; ++j) steps.push_back(around * std::exp2(j / 4.0));
  return steps;
}

SubbandCurve measure_subband(const StreamContent& content, const ResidualTraversal& traversal,
                             const std::vector<double>& predictions, const std::vector<float>& targets,
                             const std::vector<uint32_t>& multiplicity, int axis, const std::vector<double>& steps) {
  SubbandCurve curve;
  const size_t welded = multiplicity.size();
  const bool temporal = content.flags & format::kFlagTemporalResiduals;
  const bool spatial = content.flags & format::kFlagSpatialResiduals;
  std::vector<double> previous(welded), current(welded);
  std::vector<int64_t> previous_symbol(welded), current_symbol(welded);
  for (double step : steps) {
    const double q = double(float(step));  // the stream stores steps as float
    double distortion = 0;
    EntropyCounter entropy;
    size_t frame = 0;
    for (uint32_t frames : content.clip_frames) {
      std::fill(previous.begin(), previous.end(), 0.0);
      std::fill(previous_symbol.begin(), previous_symbol.end(), 0);
      for (uint32_t f = 0; f < frames; ++f, ++frame) {
        for (uint32_t v : traversal.order) {
          const size_t index = (frame * welded + v) * 3 + size_t(axis);
          const double p = predictions[index];
          const double r = predicted_residual(traversal, v, 0, 1, current.data(), previous.data(), temporal, spatial);
          const int64_t k = quantizer_index((double(targets[index]) - p - r) / q);
          current[v] = r + double(k) * q;
          const double error = double(float(p + current[v])) - double(targets[index]);
          distortion += multiplicity[v] * error * error;
          const int64_t magnitude = previous_symbol[v] < 0 ? -previous_symbol[v] : previous_symbol[v];
          entropy.add(int(std::min<int64_t>(magnitude, 2)), k);
          current_symbol[v] = k;
        }
        previous.swap(current);
        previous_symbol.swap(current_symbol);
      }
    }
    curve.step.push_back(q);
    curve.distortion.push_back(distortion);
    curve.bits.push_back(entropy.bits());
  }
  return curve;
}

StepChoice choose_steps(const SubbandCurve (&curves)[3], double lambda) {
  StepChoice choice;
  for (int axis = 0; axis < 3; ++axis) {
    const SubbandCurve& curve = curves[axis];
    size_t best = 0;
    for (size_t j = 1; j < curve.step.size(); ++j)
      if (curve.distortion[j] + lambda * curve.bits[j] < curve.distortion[best] + lambda * curve.bits[best]) best = j;
    choice.index[axis] = best;
    choice.distortion += curve.distortion[best];
    choice.bits += curve.bits[best];
  }
  return choice;
}

namespace {

// Bisection on log λ between 1e-30 and 1e30 for the largest λ whose choice is still acceptable.
template <typename Acceptable>
StepChoice bisect(const SubbandCurve (&curves)[3], Acceptable acceptable, bool want_large) {
  double low = -30, high = 30;  // log10 λ
  StepChoice best = choose_steps(curves, std::pow(10.0, want_large ? low : high));
  for (int iteration = 0; iteration < 80; ++iteration) {
    const double middle = 0.5 * (low + high);
    const StepChoice choice = choose_steps(curves, std::pow(10.0, middle));
    if (acceptable(choice)) {
      best = choice;
      (want_large ? low : high) = middle;
    } else {
      (want_large ? high : low) = middle;
    }
  }
  return best;
}

}  // namespace

// The Lagrangian choice reaches only the lower convex hull of each subband's (D, R) points, and closed-loop
// prediction makes the curves non-convex (a dead zone where everything quantizes to 0, then a jump); every
// combination of measured steps is then tried as well (a few thousand: cheap) and the best feasible one kept.
template <typename Feasible, typename Better>
StepChoice exhaustive(const SubbandCurve (&curves)[3], StepChoice best, Feasible feasible, Better better) {
  StepChoice candidate;
  for (size_t i = 0; i < curves[0].step.size(); ++i)
    for (size_t j = 0; j < curves[1].step.size(); ++j)
      for (size_t k = 0; k < curves[2].step.size(); ++k) {
        candidate.index[0] = i, candidate.index[1] = j, candidate.index[2] = k;
        candidate.distortion = curves[0].distortion[i] + curves[1].distortion[j] + curves[2].distortion[k];
        candidate.bits = curves[0].bits[i] + curves[1].bits[j] + curves[2].bits[k];
        if (feasible(candidate) && (!feasible(best) || better(candidate, best))) best = candidate;
      }
  return best;
}

StepChoice steps_for_distortion(const SubbandCurve (&curves)[3], double max_distortion) {
  // Larger λ favours rate: the largest λ whose distortion still fits.
  auto fits = [&](const StepChoice& c) { return c.distortion <= max_distortion; };
  const StepChoice lagrangian = bisect(curves, fits, true);
  return exhaustive(curves, lagrangian, fits, [](const StepChoice& a, const StepChoice& b) { return a.bits < b.bits; });
}

StepChoice steps_for_bits(const SubbandCurve (&curves)[3], double max_bits) {
  // Smaller λ favours distortion: the smallest λ whose bits still fit.
  auto fits = [&](const StepChoice& c) { return c.bits <= max_bits; };
  const StepChoice lagrangian = bisect(curves, fits, false);
  return exhaustive(curves, lagrangian, fits,
                    [](const StepChoice& a, const StepChoice& b) { return a.distortion < b.distortion; });
}

}  // namespace segmorph
