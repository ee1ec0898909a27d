#include "encode/rate_distortion.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/parallel.h"
#include "common/prediction.h"
#include "common/stream_format.h"

namespace segmorph {
namespace {

// Estimated bits of a symbol stream coded with adaptive contexts: its conditional entropy given the context
// (the magnitude class of the same vertex's previous symbol, as the stream's coder uses), plus the cost of
// learning each context's distribution (half a bit per distinct symbol and context, roughly).
struct EntropyCounter {
  static constexpr int64_t kRange = 512;  // symbols in [−512, 512] are counted; larger ones are estimated
  std::vector<uint32_t> counts = std::vector<uint32_t>(3 * (2 * kRange + 1), 0);
  double large_bits = 0;

  void add(int context, int64_t symbol) {
    if (symbol >= -kRange && symbol <= kRange) {
      counts[size_t(context * (2 * kRange + 1) + (symbol + kRange))] += 1;
    } else {
      // Length class and leading bits adaptive, the rest raw: about 2 log2|k| bits.
      large_bits += 2 * std::log2(double(symbol < 0 ? -symbol : symbol)) + 2;
    }
  }
  double bits() const {
    double sum = large_bits;
    double total[3] = {0, 0, 0};  // symbols counted per context (exact: far below 2^53)
    for (int c = 0; c < 3; ++c) {
      uint64_t symbols = 0;
      for (int64_t j = 0; j < 2 * kRange + 1; ++j) symbols += counts[size_t(c * (2 * kRange + 1) + j)];
      total[c] = double(symbols);
    }
    for (int c = 0; c < 3; ++c) {
      if (total[c] == 0) continue;
      for (int64_t j = 0; j < 2 * kRange + 1; ++j) {
        const double count = double(counts[size_t(c * (2 * kRange + 1) + j)]);
        if (count == 0) continue;
        sum -= count * std::log2(count / total[c]);
        sum += 0.5 * std::log2(1 + total[c]);  // learning the distribution
      }
    }
    return sum;
  }
};

constexpr double kIndexLimit = 1 << 30;

// One vertex at `count` lanes (an axis and a step each): the residual quantized as the encoder does
// (quantizer_index, in a form the compiler vectorizes without trapping math, codec/CMakeLists.txt: indices are clamped
// to ±2^30, which only a step far too small to ever be chosen reaches), the reconstructed residual, its change from `last` and the distortion of
// the reconstructed position.
__attribute__((always_inline)) inline void quantize_lanes(size_t count, double weight, const double* __restrict p,
                                                          const double* __restrict target, const double* __restrict r,
                                                          const double* __restrict q,
                                                          const double* __restrict inverse_q,
                                                          const double* __restrict last, double* __restrict current,
                                                          double* __restrict change, int32_t* __restrict symbol,
                                                          double* __restrict distortion) {
  for (size_t s = 0; s < count; ++s) {
    double x = (target[s] - p[s] - r[s]) * inverse_q[s];
    x = std::min(std::max(x + std::copysign(0.5, x), -kIndexLimit), kIndexLimit);
    const int32_t k = int32_t(x);
    const double reconstructed = r[s] + double(k) * q[s];
    current[s] = reconstructed;
    change[s] = reconstructed - last[s];
    const double error = double(float(p[s] + reconstructed)) - target[s];
    distortion[s] += weight * error * error;
    symbol[s] = k;
  }
}

// One frame of a walk: every array by position in the traversal, lane s of position i at i · lanes + s.
struct FrameWalk {
  const ResidualTraversal* traversal = nullptr;
  size_t welded = 0, lanes = 0;
  bool spatial = false;
  const size_t* lane_axis = nullptr;
  const double *q = nullptr, *inverse_q = nullptr;
  const double *prediction = nullptr, *target = nullptr, *weight = nullptr;  // per position (× 3 by axis)
  const double* reference = nullptr;  // the reference frame's reconstructed residuals, or zeros of `lanes` per position
  bool zero_reference = false;        // reference holds `lanes` zeros only, for every position
  const int32_t* previous_symbol = nullptr;
  double *current = nullptr, *change = nullptr, *distortion = nullptr;
  int32_t* current_symbol = nullptr;
  EntropyCounter* entropy = nullptr;
};

// The walk of one frame at kLanes lanes (0: w.lanes, not known when compiled). A known lane count lets every
// per-lane loop be unrolled: the arithmetic per lane is the same, in the same order.
template <size_t kLanes>
__attribute__((always_inline)) inline void walk_frame(const FrameWalk& w) {
  const size_t count = kLanes ? kLanes : w.lanes;
  double local[4 * (kLanes ? kLanes : 1)];       // a known count's per-lane values
  std::vector<double> heap(kLanes ? 0 : 4 * count);  // any other's
  double* const values = kLanes ? local : heap.data();
  double *p = values, *target = values + count, *r = values + 2 * count, *sum = values + 3 * count;
  const uint32_t* earlier_offset = w.traversal->earlier_offset.data();
  const uint32_t* earlier = w.traversal->earlier.data();
  for (size_t position = 0; position < w.welded; ++position) {
    const uint32_t begin = earlier_offset[position], end = earlier_offset[position + 1];
    const size_t at = position * count;
    for (size_t s = 0; s < count; ++s) {
      p[s] = w.prediction[position * 3 + w.lane_axis[s]];
      target[s] = w.target[position * 3 + w.lane_axis[s]];
    }
    const double* last = w.zero_reference ? w.reference : &w.reference[at];
    for (size_t s = 0; s < count; ++s) r[s] = last[s];
    if (w.spatial && end > begin) {
      for (size_t s = 0; s < count; ++s) sum[s] = 0.0;
      for (uint32_t j = begin; j < end; ++j) {
        const double* c = &w.change[size_t(earlier[j]) * count];
        for (size_t s = 0; s < count; ++s) sum[s] += c[s];
      }
      const double inverse_n = 1.0 / double(end - begin);
      for (size_t s = 0; s < count; ++s) r[s] += sum[s] * inverse_n;
    }
    quantize_lanes(count, w.weight[position], p, target, r, w.q, w.inverse_q, last, &w.current[at], &w.change[at],
                   &w.current_symbol[at], w.distortion);
    for (size_t s = 0; s < count; ++s) {
      const int32_t before = w.previous_symbol[at + s], magnitude = before < 0 ? -before : before;
      w.entropy[s].add(std::min(magnitude, 2), w.current_symbol[at + s]);
    }
  }
}

// walk_frame at w.lanes, unrolled for the lane counts the rate control measures (up to 16), compiled for the baseline
// instructions and for AVX2 (the same operations on each lane, in the same order: the same doubles; -ffp-contract=off
// keeps multiplies and adds apart, and no FMA is enabled).
__attribute__((always_inline)) inline void walk_frame_at(const FrameWalk& w) {
  switch (w.lanes) {
    case 1: return walk_frame<1>(w);
    case 2: return walk_frame<2>(w);
    case 3: return walk_frame<3>(w);
    case 4: return walk_frame<4>(w);
    case 5: return walk_frame<5>(w);
    case 6: return walk_frame<6>(w);
    case 7: return walk_frame<7>(w);
    case 8: return walk_frame<8>(w);
    case 9: return walk_frame<9>(w);
    case 10: return walk_frame<10>(w);
    case 11: return walk_frame<11>(w);
    case 12: return walk_frame<12>(w);
    case 13: return walk_frame<13>(w);
    case 14: return walk_frame<14>(w);
    case 15: return walk_frame<15>(w);
    case 16: return walk_frame<16>(w);
    default: return walk_frame<0>(w);
  }
}

void walk_frame_baseline(const FrameWalk& w) { walk_frame_at(w); }

#if defined(__x86_64__)
__attribute__((target("avx2"))) void walk_frame_avx2(const FrameWalk& w) { walk_frame_at(w); }
#endif

// AVX2 where the processor has it, unless not allowed (tests compare the two); x86-64 only (a 32-bit x86 build's
// baseline could compute in x87's extended precision).
using WalkFrame = void (*)(const FrameWalk&);
WalkFrame frame_walker(bool allow_avx2) {
#if defined(__x86_64__)
  if (allow_avx2 && __builtin_cpu_supports("avx2")) return walk_frame_avx2;
#endif
  (void)allow_avx2;
  return walk_frame_baseline;
}

// The subbands and steps are measured together, in one walk over the frames: every array below holds, per
// welded vertex, one value per lane (an axis and a candidate step) side by side (position i, lane s at
// i · S + s). The lanes' loops are independent, so the processor overlaps them instead of waiting on one
// vertex's chain of dependent operations at a time; each lane still sees exactly the arithmetic of the
// decoder's loop, in the same order. Arrays are by position in the traversal, so the walk reads them front to
// back and a vertex's earlier neighbours are mostly close behind.
void measure_lanes(const StreamContent& content, const ResidualTraversal& traversal,
                   const FramePredictions& predictions, const std::vector<float>& targets,
                   const std::vector<uint32_t>& multiplicity, const std::vector<double> (&steps)[3],
                   SubbandCurve (&curves)[3], const std::function<void(double)>& progress,
                   std::vector<std::vector<double>>& spare, WalkFrame walk_one) {
  const size_t welded = multiplicity.size();
  const bool temporal = content.flags & format::kFlagTemporalResiduals;
  const bool spatial = content.flags & format::kFlagSpatialResiduals;
  std::vector<size_t> lane_axis;
  std::vector<double> q, inverse_q;
  for (int axis = 0; axis < 3; ++axis)
    for (double step : steps[axis]) {
      lane_axis.push_back(size_t(axis));
      q.push_back(double(float(step)));  // the stream stores steps as float
      inverse_q.push_back(1.0 / q.back());
    }
  const size_t count = q.size();
  if (count == 0) return;
  std::vector<double> distortion(count, 0.0), zeros(count, 0.0);
  std::vector<double> change(welded * count, 0.0);
  std::vector<int32_t> previous_symbol(welded * count), current_symbol(welded * count);
  std::vector<EntropyCounter> entropy(count);
  std::vector<double> predicted(welded * 3);  // in welded order
  std::vector<double> frame_prediction(welded * 3), frame_target(welded * 3), frame_weight(welded);
  for (size_t v = 0; v < welded; ++v) frame_weight[traversal.position[v]] = multiplicity[v];
  // Each frame's lanes' residuals are held while a later frame may use them as its reference: the next frame of the
  // clip, or a later one that references it from further back (until the last). Frames without a reference read
  // zeros (as without temporal residuals: the same doubles). The buffers are reused.
  const size_t frame_count = content.frame_count();
  std::vector<size_t> last_use(frame_count, 0);
  for (size_t c = 0, first = 0; c < content.clip_frames.size(); first += content.clip_frames[c++])
    for (size_t f = 0; f < content.clip_frames[c]; ++f) {
      const size_t back = frame_reference(content, first + f, f);
      if (back > 0) last_use[first + f - back] = std::max(last_use[first + f - back], first + f);
    }
  std::vector<std::pair<size_t, std::vector<double>>> held;  // (frame, its lanes' residuals)
  FrameWalk walk;
  walk.traversal = &traversal, walk.welded = welded, walk.lanes = count, walk.spatial = spatial;
  walk.lane_axis = lane_axis.data(), walk.q = q.data(), walk.inverse_q = inverse_q.data();
  walk.weight = frame_weight.data(), walk.change = change.data(), walk.distortion = distortion.data();
  walk.entropy = entropy.data();
  size_t frame = 0;
  for (uint32_t frames : content.clip_frames) {
    std::fill(previous_symbol.begin(), previous_symbol.end(), 0);
    for (uint32_t f = 0; f < frames; ++f, ++frame) {
      // This frame's predictions and targets, by position in the traversal.
      predictions.predict(frame, predicted.data());
      for (size_t v = 0; v < welded; ++v)
        for (size_t axis = 0; axis < 3; ++axis) {
          frame_prediction[traversal.position[v] * 3 + axis] = predicted[v * 3 + axis];
          frame_target[traversal.position[v] * 3 + axis] = double(targets[(frame * welded + v) * 3 + axis]);
        }
      // The reference's residuals (the temporal prediction), and this frame's.
      const size_t back = frame_reference(content, frame, f);
      const double* reference = nullptr;  // none: zeros
      for (const auto& entry : held)
        if (back > 0 && entry.first == frame - back) reference = entry.second.data();
      std::vector<double> current;
      if (!spare.empty()) current = std::move(spare.back()), spare.pop_back();
      current.resize(welded * count);
      walk.prediction = frame_prediction.data(), walk.target = frame_target.data();
      walk.zero_reference = !(temporal && reference);
      walk.reference = walk.zero_reference ? zeros.data() : reference;
      walk.current = current.data();
      walk.previous_symbol = previous_symbol.data(), walk.current_symbol = current_symbol.data();
      walk_one(walk);
      // Let go of the frames nothing after this one uses; hold this one if something does.
      for (size_t i = 0; i < held.size();)
        if (last_use[held[i].first] <= frame) {
          spare.push_back(std::move(held[i].second));
          held.erase(held.begin() + std::ptrdiff_t(i));
        } else {
          ++i;
        }
      if (last_use[frame] > frame)
        held.emplace_back(frame, std::move(current));
      else
        spare.push_back(std::move(current));
      previous_symbol.swap(current_symbol);
      if (progress) progress(double(frame + 1) / double(frame_count));
    }
  }
  for (auto& entry : held) spare.push_back(std::move(entry.second));
  for (size_t s = 0; s < count; ++s) {
    SubbandCurve& curve = curves[lane_axis[s]];
    curve.step.push_back(q[s]);
    curve.distortion.push_back(distortion[s]);
    curve.bits.push_back(entropy[s].bits());
  }
}

}  // namespace

// The lanes split into contiguous ranges, one walk over the frames per thread (a lane's arithmetic does not depend
// on the others'), the ranges' measurements appended in lane order: the same curves for every thread count.
void measure_subbands(const StreamContent& content, const ResidualTraversal& traversal,
                      const FramePredictions& predictions, const std::vector<float>& targets,
                      const std::vector<uint32_t>& multiplicity, const std::vector<double> (&steps)[3],
                      SubbandCurve (&curves)[3], size_t threads, const std::function<void(double)>& progress,
                      MeasureBuffers* buffers, bool allow_avx2) {
  const WalkFrame walk_one = frame_walker(allow_avx2);
  const size_t lanes = steps[0].size() + steps[1].size() + steps[2].size();
  // Each range predicts and walks every frame: at least two lanes a thread make that worth it.
  const size_t ranges = std::min(thread_count(threads), std::max<size_t>(lanes / 2, 1));
  struct Curves {
    SubbandCurve axis[3];
  };
  std::vector<Curves> measured(ranges);
  MeasureBuffers local;
  MeasureBuffers& reused = buffers ? *buffers : local;
  if (reused.spare.size() < ranges) reused.spare.resize(ranges);
  std::vector<size_t> range_begin(ranges + 1);
  for (size_t r = 0; r <= ranges; ++r) range_begin[r] = lanes * r / ranges;
  parallel_ranges(ranges, ranges, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      // The range's lanes, axis by axis (lanes are numbered axis after axis).
      std::vector<double> subset[3];
      size_t lane = 0;
      for (int axis = 0; axis < 3; ++axis)
        for (double step : steps[axis]) {
          if (lane >= range_begin[r] && lane < range_begin[r + 1]) subset[axis].push_back(step);
          ++lane;
        }
      // The first range runs on the calling thread: it reports.
      measure_lanes(content, traversal, predictions, targets, multiplicity, subset, measured[r].axis,
                    r == 0 ? progress : std::function<void(double)>(), reused.spare[r], walk_one);
    }
  });
  for (size_t r = 0; r < ranges; ++r)
    for (int axis = 0; axis < 3; ++axis) {
      const SubbandCurve& from = measured[r].axis[axis];
      SubbandCurve& to = curves[axis];
      to.step.insert(to.step.end(), from.step.begin(), from.step.end());
      to.distortion.insert(to.distortion.end(), from.distortion.begin(), from.distortion.end());
      to.bits.insert(to.bits.end(), from.bits.begin(), from.bits.end());
    }
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
