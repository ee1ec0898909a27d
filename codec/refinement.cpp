#include "refinement.h"

#include <algorithm>
#include <cmath>

#include "parallel.h"

namespace segmorph {
namespace {

// Score of a candidate level τ in one component: the minimum of the smoothed κ_min along the crossing.
double concavity(double level, const std::vector<uint32_t>& vertices, const std::vector<double>& mu,
                 const std::vector<double>& curvature, const VertexAdjacency& adjacency, int smoothing,
                 std::vector<int>& slot, std::vector<uint32_t>& boundary, std::vector<double>& profile) {
  boundary.clear();
  for (uint32_t v : vertices) {
    if (mu[v] < level) continue;
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i)
      if (mu[adjacency.neighbour[i]] < level) {
        boundary.push_back(v);
        break;
      }
  }
  if (boundary.empty()) return INFINITY;
  profile.resize(boundary.size());
  for (size_t b = 0; b < boundary.size(); ++b) {
    slot[boundary[b]] = int(b);
    profile[b] = curvature[boundary[b]];
  }
  std::vector<double> next(profile.size());
  for (int pass = 0; pass < smoothing; ++pass) {
    for (size_t b = 0; b < boundary.size(); ++b) {
      double sum = profile[b];
      int count = 1;
      for (uint32_t i = adjacency.offset[boundary[b]]; i < adjacency.offset[boundary[b] + 1]; ++i) {
        const int s = slot[adjacency.neighbour[i]];
        if (s >= 0) sum += profile[size_t(s)], ++count;
      }
      next[b] = sum / count;
    }
    profile.swap(next);
  }
  for (uint32_t v : boundary) slot[v] = -1;
  return *std::min_element(profile.begin(), profile.end());
}

}  // namespace

MorseBands refine_levels(const std::vector<double>& mu, const std::vector<double>& curvature,
                         const WeldedTopology& topology, const VertexAdjacency& adjacency, const MorseBands& bands,
                         const RefinementSettings& settings, int* iterations_out) {
  MorseBands refined = bands;
  std::vector<std::vector<uint32_t>> members(topology.component_count);
  for (size_t w = 0; w < topology.welded_count(); ++w) members[topology.component[w]].push_back(uint32_t(w));
  std::vector<int> slot(topology.welded_count(), -1);
  std::vector<uint32_t> boundary;
  std::vector<double> profile;
  int iterations = 0;
  for (bool moved = true; moved && iterations < settings.max_iterations; ++iterations) {
    moved = false;
    for (size_t c = 0; c < topology.component_count; ++c) {
      std::vector<double>& levels = refined.levels[c];
      if (levels.empty()) continue;
      double low = INFINITY, high = -INFINITY;
      for (uint32_t v : members[c]) low = std::min(low, mu[v]), high = std::max(high, mu[v]);
      for (size_t j = 0; j < levels.size(); ++j) {
        const double below = j > 0 ? levels[j - 1] : low, above = j + 1 < levels.size() ? levels[j + 1] : high;
        const double from = levels[j] - settings.window * (levels[j] - below);
        const double to = levels[j] + settings.window * (above - levels[j]);
        double best = levels[j];
        double best_score =
            concavity(best, members[c], mu, curvature, adjacency, settings.smoothing, slot, boundary, profile);
        for (int k = 0; k < settings.candidates; ++k) {
          const double candidate = from + (to - from) * k / std::max(settings.candidates - 1, 1);
          const double score =
              concavity(candidate, members[c], mu, curvature, adjacency, settings.smoothing, slot, boundary, profile);
          if (score < best_score - 1e-12 * std::fabs(best_score)) best = candidate, best_score = score;
        }
        if (best != levels[j]) {
          levels[j] = best;
          moved = true;
        }
      }
    }
  }
  if (iterations_out) *iterations_out = iterations;
  return refined;
}

Clusters refine_by_motion(const Clusters& clusters, const float* base, const Trajectories& frames,
                          const VertexAdjacency& adjacency, int max_iterations, int* iterations_out, size_t threads) {
  Clusters refined = clusters;
  const size_t vertex_count = frames.vertex_count;
  int iterations = 0;
  for (; iterations < max_iterations; ++iterations) {
    const AffineMotion motion = fit_affine_motion(base, frames, refined, threads);
    std::vector<uint32_t> label = refined.label;
    // Each vertex's move depends on the previous labels only: the vertices are split over threads.
    parallel_ranges(vertex_count, thread_count(threads), [&](size_t begin, size_t end) {
      std::vector<uint32_t> candidates;
      for (size_t v = begin; v < end; ++v) {
        candidates.assign(1, refined.label[v]);
        for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
          const uint32_t k = refined.label[adjacency.neighbour[i]];
          if (std::find(candidates.begin(), candidates.end(), k) == candidates.end()) candidates.push_back(k);
        }
        if (candidates.size() == 1) continue;
        // Squared prediction error of vertex v under cluster k's transforms, over all frames (stops past limit).
        auto error_of = [&](uint32_t k, double limit) {
          double error = 0;
          const double* c = &motion.centroid[k * 3];
          const double d[3] = {base[v * 3] - c[0], base[v * 3 + 1] - c[1], base[v * 3 + 2] - c[2]};
          for (size_t f = 0; f < frames.frame_count && error < limit; ++f) {
            const double* t = motion.transform(f, k);
            for (int r = 0; r < 3; ++r) {
              const double e = t[r * 4] * d[0] + t[r * 4 + 1] * d[1] + t[r * 4 + 2] * d[2] + t[r * 4 + 3] -
                               frames.frame(f)[v * 3 + size_t(r)];
              error += e * e;
            }
          }
          return error;
        };
        // A vertex moves only for a gain of more than 0.1 %, so the iteration settles.
        const double own = error_of(candidates[0], INFINITY);
        double best_error = 0.999 * own;
        for (size_t j = 1; j < candidates.size(); ++j) {
          const double error = error_of(candidates[j], best_error);
          if (error < best_error) best_error = error, label[v] = candidates[j];
        }
      }
    });
    const bool moved = label != refined.label;
    // Clusters emptied by the moves disappear; labels are renumbered in order of first appearance.
    refined = compact(label);
    if (!moved) break;
  }
  if (iterations_out) *iterations_out = iterations;
  return refined;
}

}  // namespace segmorph
