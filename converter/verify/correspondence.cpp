#include "verify/correspondence.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "common/parallel.h"

namespace segmorph {
namespace {

// Each vertex's position averaged over every frame of every clip.
std::vector<double> mean_positions(const std::vector<FrameSequence>& clips) {
  const size_t count = clips[0].vertex_count;
  std::vector<double> sum(count * 3, 0.0);
  size_t frames = 0;
  for (const FrameSequence& clip : clips)
    for (size_t f = 0; f < clip.frame_count; ++f, ++frames) {
      const float* frame = clip.frame(f);
      for (size_t i = 0; i < count * 3; ++i) sum[i] += frame[i];
    }
  for (double& value : sum) value /= double(frames);
  return sum;
}


// A grid of the other's mean positions, found in a table by cell. The cells start at about the mean spacing of
// points filling the box and halve while the occupied cells hold more than two points each (a surface's points fill
// few cells) and halving still spreads them.
struct MeansGrid {
  double cell = 1.0;
  std::vector<std::pair<uint64_t, uint32_t>> cells;                    // (cell key, vertex), by key
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> table;  // cell key -> range of `cells`
  int64_t low[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, high[3] = {INT64_MIN, INT64_MIN, INT64_MIN};  // cell indices
  std::vector<double> cell_means;                                      // the means in `cells` order

  // Clamped so that far outliers cannot overflow; clamping only brings a point nearer the grid's box.
  int64_t index(double x) const { return int64_t(std::clamp(std::floor(x / cell), -1e15, 1e15)); }
  static uint64_t key(int64_t x, int64_t y, int64_t z) {  // in unsigned arithmetic, which wraps
    return (uint64_t(x) * 73856093u) ^ (uint64_t(y) * 19349663u) ^ (uint64_t(z) * 83492791u);
  }

  MeansGrid(const std::vector<double>& means, size_t count) : cells(count), cell_means(count * 3) {
    double box_low[3] = {INFINITY, INFINITY, INFINITY}, box_high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < count * 3; ++i) {
      box_low[i % 3] = std::min(box_low[i % 3], means[i]);
      box_high[i % 3] = std::max(box_high[i % 3], means[i]);
    }
    const double diagonal = std::hypot(box_high[0] - box_low[0], box_high[1] - box_low[1], box_high[2] - box_low[2]);
    cell = diagonal > 0 ? diagonal / std::max(1.0, std::cbrt(double(count))) : 1.0;
    auto place = [&] {
      for (uint32_t u = 0; u < count; ++u) {
        const double* m = &means[size_t(u) * 3];
        cells[u] = {key(index(m[0]), index(m[1]), index(m[2])), u};
      }
      std::sort(cells.begin(), cells.end());
      size_t occupied = 0;
      for (size_t i = 0; i < cells.size(); ++i) occupied += i == 0 || cells[i].first != cells[i - 1].first;
      return occupied;
    };
    for (size_t occupied = place(), halvings = 0; occupied * 2 < count && halvings < 16; ++halvings) {
      cell /= 2;
      const size_t finer = place();
      if (finer * 2 < occupied * 3) {  // the points no longer spread: keep the coarser cells
        cell *= 2;
        place();
        break;
      }
      occupied = finer;
    }
    table.reserve(count);
    for (uint32_t i = 0; i < count; ++i) {
      const double* m = &means[size_t(cells[i].second) * 3];
      for (int k = 0; k < 3; ++k) {
        cell_means[size_t(i) * 3 + size_t(k)] = m[k];
        low[k] = std::min(low[k], index(m[k]));
        high[k] = std::max(high[k], index(m[k]));
      }
      auto& range = table.try_emplace(cells[i].first, i, i).first->second;
      range.second = i + 1;
    }
  }
};

// The other's trajectories: every frame of every clip in order, the first `held` frames copied vertex by vertex (as
// far as held_bytes allows), where most candidates are decided, so that a candidate's trajectory is read contiguously.
struct Trajectories {
  std::vector<const float*> frames;
  size_t held = 0;
  std::vector<float> held_frames;

  Trajectories(const std::vector<FrameSequence>& clips, size_t frame_count, size_t held_bytes) {
    const size_t count = clips[0].vertex_count;
    for (const FrameSequence& clip : clips)
      for (size_t f = 0; f < clip.frame_count; ++f) frames.push_back(clip.frame(f));
    held = std::min(frame_count, std::max<size_t>(1, held_bytes / (count * 3 * sizeof(float))));
    held_frames.resize(count * held * 3);
    for (size_t f = 0; f < held; ++f)
      for (size_t u = 0; u < count; ++u)
        for (size_t k = 0; k < 3; ++k) held_frames[(u * held + f) * 3 + k] = frames[f][u * 3 + k];
  }

  // The trajectory distance of a vertex (its frames in `track`) and u, or a value > bound as soon as it is known to
  // exceed it.
  double distance(const float* track, uint32_t u, double bound) const {
    auto add = [](double& sum, const float* a, const float* b) {
      for (int k = 0; k < 3; ++k) sum += (double(a[k]) - b[k]) * (double(a[k]) - b[k]);
    };
    double sum = 0;
    const float* candidate = &held_frames[size_t(u) * held * 3];
    for (size_t f = 0; f < held; ++f) {
      add(sum, track + f * 3, candidate + f * 3);
      if (sum > bound) return sum;
    }
    for (size_t f = held; f < frames.size(); ++f) {
      add(sum, track + f * 3, frames[f] + size_t(u) * 3);
      if (sum > bound) return sum;
    }
    return sum;
  }
};

}  // namespace

std::vector<uint32_t> match_vertices(const std::vector<FrameSequence>& reference,
                                     const std::vector<FrameSequence>& other, size_t threads, size_t held_bytes) {
  assert(!reference.empty() && reference.size() == other.size() && other[0].vertex_count > 0);
  for (size_t c = 0; c < reference.size(); ++c)
    assert(reference[c].frame_count == other[c].frame_count && reference[c].vertex_count == reference[0].vertex_count &&
           other[c].vertex_count == other[0].vertex_count);
  const size_t count = reference[0].vertex_count, other_count = other[0].vertex_count;
  std::vector<uint32_t> match(count);
  const float* first = reference[0].frame(0);
  const float* other_first = other[0].frame(0);
  if (count == other_count && std::equal(first, first + count * 3, other_first)) {
    for (uint32_t v = 0; v < count; ++v) match[v] = v;
    return match;
  }

  // Each vertex's position averaged over every frame: by Jensen's inequality, the trajectory distance of v and u
  // (a sum over F frames of squared distances) is at least F times the squared distance of their means, a bound that
  // tightens with F where the first frame's alone would not.
  size_t frames = 0;
  for (const FrameSequence& clip : reference) frames += clip.frame_count;
  const std::vector<double> means = mean_positions(reference), other_means = mean_positions(other);

  const MeansGrid grid(other_means, other_count);

  std::vector<const float*> reference_frames;
  for (size_t c = 0; c < reference.size(); ++c)
    for (size_t f = 0; f < reference[c].frame_count; ++f) reference_frames.push_back(reference[c].frame(f));
  const Trajectories trajectories(other, frames, held_bytes);

  // The bounds are loosened so that rounding cannot skip a candidate that ties or wins: the means' by a few units in
  // the last place of the largest coordinate, the distances by a relative 1e-9.
  double largest = 0;
  for (double value : means) largest = std::max(largest, std::fabs(value));
  for (double value : other_means) largest = std::max(largest, std::fabs(value));
  const double tolerance = 8 * std::numeric_limits<double>::epsilon() * largest;
  constexpr double kSlack = 1 + 1e-9;
  const auto match_range = [&](size_t begin, size_t end) {
    std::vector<float> track(frames * 3);  // v's trajectory
    for (uint32_t v = uint32_t(begin); v < end; ++v) {
      for (size_t f = 0; f < frames; ++f)
        for (size_t k = 0; k < 3; ++k) track[f * 3 + k] = reference_frames[f][size_t(v) * 3 + k];
      const double* m = &means[size_t(v) * 3];
      const int64_t centre[3] = {grid.index(m[0]), grid.index(m[1]), grid.index(m[2])};
      // Shells of cells outwards, from the first that meets the grid's box to the last: a mean in shell r is at
      // least (r - 1) cells away, so the search ends once F times that squared exceeds the best trajectory distance
      // found. Only the part of a shell inside the box is visited. Ties go to the lowest u, whatever the order.
      int64_t near_shell = 0, far_shell = 0, from[3], to[3];
      for (int k = 0; k < 3; ++k) {
        near_shell = std::max({near_shell, grid.low[k] - centre[k], centre[k] - grid.high[k]});
        far_shell = std::max({far_shell, centre[k] - grid.low[k], grid.high[k] - centre[k]});
      }
      double best = INFINITY;
      uint32_t best_u = 0;
      auto consider = [&](uint32_t i) {  // the other's vertex cells[i]
        const double* n = &grid.cell_means[size_t(i) * 3];
        double apart = 0;
        for (int k = 0; k < 3; ++k) apart += std::pow(std::max(0.0, std::fabs(m[k] - n[k]) - tolerance), 2);
        if (double(frames) * apart > best * kSlack) return;
        const uint32_t u = grid.cells[i].second;
        const double d = trajectories.distance(track.data(), u, best);
        if (d < best || (d == best && u < best_u)) best = d, best_u = u;
      };
      auto visit = [&](int64_t dx, int64_t dy, int64_t dz) {
        const auto found = grid.table.find(MeansGrid::key(centre[0] + dx, centre[1] + dy, centre[2] + dz));
        if (found != grid.table.end())
          for (uint32_t i = found->second.first; i < found->second.second; ++i) consider(i);
      };
      // Far from any good match (files that do not correspond), shells of empty cells could outnumber the other's
      // vertices many times over (a flat or thin shape's box is mostly empty): once the cells a shell would cost
      // bring the search's to a quarter of the other's vertex count, every vertex is considered instead (a vertex
      // costs a few operations, a cell a table look-up).
      double cost = 0;
      for (int64_t radius = near_shell; radius <= far_shell; ++radius) {
        if (std::isfinite(best) &&
            (double(radius) - 1) * grid.cell - tolerance > std::sqrt(best / double(frames)) * kSlack)
          break;
        for (int k = 0; k < 3; ++k)
          from[k] = std::max(-radius, grid.low[k] - centre[k]), to[k] = std::min(radius, grid.high[k] - centre[k]);
        // The rows (dx, dy) walked and the cells looked up: all of a row on the shell's sides, its two ends (where
        // inside the box) in the rows within. In double: a far outlier's box is vast.
        auto within = [&](int k) {
          return double(std::max<int64_t>(0, std::min(to[k], radius - 1) - std::max(from[k], 1 - radius) + 1));
        };
        const double rows = double(to[0] - from[0] + 1) * double(to[1] - from[1] + 1), inner = within(0) * within(1);
        const double ends = double(from[2] == -radius) + double(to[2] == radius && radius > 0);
        cost += rows + (rows - inner) * double(to[2] - from[2] + 1) + inner * ends;
        if (cost > double(other_count) / 4) {
          for (uint32_t i = 0; i < other_count; ++i) consider(i);
          break;
        }
        for (int64_t dx = from[0]; dx <= to[0]; ++dx)
          for (int64_t dy = from[1]; dy <= to[1]; ++dy) {
            if (std::abs(dx) == radius || std::abs(dy) == radius) {
              for (int64_t dz = from[2]; dz <= to[2]; ++dz) visit(dx, dy, dz);
            } else {
              if (from[2] == -radius) visit(dx, dy, -radius);
              if (to[2] == radius) visit(dx, dy, radius);
            }
          }
      }
      match[v] = best_u;
    }
  };
  // Each vertex's search reads the grid and the frames only: the vertices are split over threads.
  parallel_ranges(count, thread_count(threads), match_range);
  return match;
}

}  // namespace segmorph
