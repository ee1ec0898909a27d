#include "encode/segmentation/refinement.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "common/parallel.h"

namespace segmorph {
namespace {

// The concavity of a candidate level τ in one component, scored on vertices: the boundary is the set of vertices
// with μ >= τ next to one below it, unordered; κ_min is averaged `smoothing` times over the boundary's own
// neighbours (a stand-in for G_σ), and the score is the least of it. INFINITY when no vertex is on the boundary.
double boundary_vertex_concavity(double level, const std::vector<uint32_t>& vertices, const std::vector<double>& mu,
                                 const std::vector<double>& curvature, const VertexAdjacency& adjacency, int smoothing,
                                 std::vector<int>& slot, std::vector<uint32_t>& boundary,
                                 std::vector<double>& profile) {
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

// One crossing of a level: the point where μ reaches the level on the welded edge (a, b), a < b.
struct Crossing {
  uint64_t edge;
  double point[3];
  double curvature;  // κ_min interpolated along the edge as μ is
};

// Eq. 6's E_concave as the paper states it, for one candidate level in one component: the level set of μ as ordered
// curves (the segments where triangles cross the level, chained through their shared edges), each parameterized by its
// normalized arc length t, its κ_min profile convolved with a Gaussian of width σ in t (circularly on a closed
// curve), and the minimum over all the curves. INFINITY when the level crosses no triangle.
class LevelCurves {
 public:
  LevelCurves(const std::vector<double>& positions, const std::vector<double>& mu, const std::vector<double>& curvature,
              const RefinementSettings& settings)
      : positions_(positions), mu_(mu), curvature_(curvature), settings_(settings) {}

  double concavity(double level, const std::vector<uint32_t>& triangles) {
    crossings_.clear();
    segments_.clear();
    for (size_t t = 0; t < triangles.size(); t += 3) {
      uint32_t found[2];
      int count = 0;
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = triangles[t + size_t(e)], b = triangles[t + size_t(e + 1) % 3];
        if ((mu_[a] >= level) != (mu_[b] >= level)) found[count++ & 1] = cross(level, a, b);
      }
      if (count == 2) segments_.push_back({found[0], found[1]});
    }
    if (segments_.empty()) return INFINITY;
    join_shared_edges();
    return curves_minimum();
  }

 private:
  uint32_t cross(double level, uint32_t a, uint32_t b) {
    if (a > b) std::swap(a, b);
    const double s = (level - mu_[a]) / (mu_[b] - mu_[a]);
    Crossing c;
    c.edge = uint64_t(a) << 32 | b;
    for (int i = 0; i < 3; ++i)
      c.point[i] = positions_[a * 3 + size_t(i)] * (1 - s) + positions_[b * 3 + size_t(i)] * s;
    c.curvature = curvature_[a] * (1 - s) + curvature_[b] * s;
    crossings_.push_back(c);
    return uint32_t(crossings_.size() - 1);
  }

  // Each edge's crossing was made once per triangle on it: number the distinct edges (nodes), rewrite the segments.
  void join_shared_edges() {
    order_.resize(crossings_.size());
    for (uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
    std::sort(order_.begin(), order_.end(),
              [&](uint32_t x, uint32_t y) { return crossings_[x].edge < crossings_[y].edge; });
    node_of_.resize(crossings_.size());
    nodes_.clear();
    for (size_t i = 0; i < order_.size(); ++i) {
      if (i == 0 || crossings_[order_[i]].edge != crossings_[order_[i - 1]].edge) nodes_.push_back(order_[i]);
      node_of_[order_[i]] = uint32_t(nodes_.size() - 1);
    }
    for (auto& s : segments_) s = {node_of_[s[0]], node_of_[s[1]]};
    // Segments at each node, compressed rows.
    offset_.assign(nodes_.size() + 1, 0);
    for (const auto& s : segments_) ++offset_[s[0] + 1], ++offset_[s[1] + 1];
    for (size_t n = 0; n < nodes_.size(); ++n) offset_[n + 1] += offset_[n];
    at_node_.resize(segments_.size() * 2);
    fill_.assign(offset_.begin(), offset_.end() - 1);
    for (uint32_t i = 0; i < segments_.size(); ++i)
      at_node_[fill_[segments_[i][0]]++] = i, at_node_[fill_[segments_[i][1]]++] = i;
  }

  // Walks the curves (open ones from their ends first, then the closed ones) and returns the least smoothed κ_min.
  double curves_minimum() {
    used_.assign(segments_.size(), 0);
    double minimum = INFINITY;
    auto walk = [&](uint32_t node) {
      curve_.assign(1, node);
      for (bool extended = true; extended;) {
        extended = false;
        for (uint32_t i = offset_[node]; i < offset_[node + 1]; ++i) {
          const uint32_t s = at_node_[i];
          if (used_[s]) continue;
          used_[s] = 1;
          node = segments_[s][0] == node ? segments_[s][1] : segments_[s][0];
          curve_.push_back(node);
          extended = true;
          break;
        }
      }
      if (curve_.size() > 1) minimum = std::min(minimum, smoothed_minimum());
    };
    for (uint32_t n = 0; n < nodes_.size(); ++n)
      if ((offset_[n + 1] - offset_[n]) % 2 == 1) walk(n);
    for (uint32_t s = 0; s < segments_.size(); ++s)
      if (!used_[s]) walk(segments_[s][0]);
    return minimum;
  }

  // The curve's κ_min sampled at uniform normalized arc length, convolved with G_σ; its minimum.
  double smoothed_minimum() {
    const size_t n = curve_.size();
    const bool closed = n > 2 && curve_.front() == curve_.back();
    arc_.assign(1, 0.0);
    for (size_t i = 1; i < n; ++i) {
      const double* p = crossings_[nodes_[curve_[i - 1]]].point;
      const double* q = crossings_[nodes_[curve_[i]]].point;
      arc_.push_back(arc_.back() + std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                             (p[2] - q[2]) * (p[2] - q[2])));
    }
    const double length = arc_.back();
    auto curvature_at = [&](size_t i) { return crossings_[nodes_[curve_[i]]].curvature; };
    if (!(length > 0)) {
      double m = INFINITY;
      for (size_t i = 0; i < n; ++i) m = std::min(m, curvature_at(i));
      return m;
    }
    const int samples = settings_.samples;
    profile_.resize(size_t(samples));
    size_t i = 0;
    for (int k = 0; k < samples; ++k) {
      // Closed: samples centred in equal pieces of the loop; open: from one end to the other.
      const double t = closed ? (k + 0.5) / samples : double(k) / std::max(samples - 1, 1);
      const double s = t * length;
      while (i + 2 < n && arc_[i + 1] < s) ++i;
      const double piece = arc_[i + 1] - arc_[i];
      const double u = piece > 0 ? std::clamp((s - arc_[i]) / piece, 0.0, 1.0) : 0.0;
      profile_[size_t(k)] = curvature_at(i) * (1 - u) + curvature_at(i + 1) * u;
    }
    const double sigma = settings_.sigma * (closed ? samples : std::max(samples - 1, 1));  // in samples
    const int radius = int(std::ceil(3 * sigma));
    kernel_.resize(size_t(radius) + 1);
    for (int d = 0; d <= radius; ++d) kernel_[size_t(d)] = std::exp(-0.5 * d * d / (sigma * sigma));
    double minimum = INFINITY;
    for (int k = 0; k < samples; ++k) {
      double sum = 0, weight = 0;
      for (int d = -radius; d <= radius; ++d) {
        int j = k + d;
        if (closed)
          j = ((j % samples) + samples) % samples;
        else if (j < 0 || j >= samples)
          continue;  // an open curve's ends: the kernel renormalized
        sum += kernel_[size_t(std::abs(d))] * profile_[size_t(j)];
        weight += kernel_[size_t(std::abs(d))];
      }
      minimum = std::min(minimum, sum / weight);
    }
    return minimum;
  }

  const std::vector<double>& positions_;
  const std::vector<double>& mu_;
  const std::vector<double>& curvature_;
  const RefinementSettings& settings_;
  std::vector<Crossing> crossings_;
  std::vector<std::array<uint32_t, 2>> segments_;
  std::vector<uint32_t> order_, node_of_, nodes_, offset_, at_node_, fill_, curve_;
  std::vector<uint8_t> used_;
  std::vector<double> arc_, profile_, kernel_;
};

}  // namespace

MorseBands refine_levels(const std::vector<double>& positions, const std::vector<double>& mu,
                         const std::vector<double>& curvature, const WeldedTopology& topology,
                         const VertexAdjacency& adjacency, const MorseBands& bands, const RefinementSettings& settings,
                         int* iterations_out) {
  MorseBands refined = bands;
  std::vector<std::vector<uint32_t>> members(topology.component_count);
  for (size_t w = 0; w < topology.welded_count(); ++w) members[topology.component[w]].push_back(uint32_t(w));
  std::vector<int> slot(topology.welded_count(), -1);
  std::vector<uint32_t> boundary;
  std::vector<double> profile;
  std::vector<std::vector<uint32_t>> triangles(topology.component_count);
  for (size_t t = 0; t < topology.triangles.size(); t += 3) {
    std::vector<uint32_t>& own = triangles[topology.component[topology.triangles[t]]];
    own.insert(own.end(), topology.triangles.begin() + ptrdiff_t(t), topology.triangles.begin() + ptrdiff_t(t + 3));
  }
  std::vector<double> low(topology.component_count, INFINITY), high(topology.component_count, -INFINITY);
  for (size_t w = 0; w < topology.welded_count(); ++w) {
    low[topology.component[w]] = std::min(low[topology.component[w]], mu[w]);
    high[topology.component[w]] = std::max(high[topology.component[w]], mu[w]);
  }
  LevelCurves curves(positions, mu, curvature, settings);
  // Each vertex's lowest neighbouring μ: a vertex is on the boundary of a level τ when μ ≥ τ and that is below τ, so
  // the candidates of one window look only at the vertices that are for some τ in it (`band`, in the component's
  // order: the same boundaries, in the same order, as from every vertex of the component).
  std::vector<double> lowest_neighbour(
      settings.profile == ConcavityProfile::level_curves ? 0 : topology.welded_count(), INFINITY);
  for (size_t w = 0; w < lowest_neighbour.size(); ++w)
    for (uint32_t i = adjacency.offset[w]; i < adjacency.offset[w + 1]; ++i)
      if (mu[adjacency.neighbour[i]] < lowest_neighbour[w]) lowest_neighbour[w] = mu[adjacency.neighbour[i]];
  std::vector<uint32_t> band;
  auto concavity = [&](double level, size_t c) {
    if (settings.profile == ConcavityProfile::level_curves) return curves.concavity(level, triangles[c]);
    return boundary_vertex_concavity(level, band, mu, curvature, adjacency, settings.smoothing, slot, boundary,
                                     profile);
  };
  std::vector<double> candidates(size_t(std::max(settings.candidates, 0)));
  int iterations = 0;
  for (bool moved = true; moved && iterations < settings.max_iterations; ++iterations) {
    moved = false;
    for (size_t c = 0; c < topology.component_count; ++c) {
      std::vector<double>& levels = refined.levels[c];
      for (size_t j = 0; j < levels.size(); ++j) {
        const double below = j > 0 ? levels[j - 1] : low[c], above = j + 1 < levels.size() ? levels[j + 1] : high[c];
        const double from = levels[j] - settings.window * (levels[j] - below);
        const double to = levels[j] + settings.window * (above - levels[j]);
        double best = levels[j], lo = best, hi = best;
        for (int k = 0; k < settings.candidates; ++k) {
          candidates[size_t(k)] = from + (to - from) * k / std::max(settings.candidates - 1, 1);
          lo = std::min(lo, candidates[size_t(k)]), hi = std::max(hi, candidates[size_t(k)]);
        }
        band.clear();
        if (settings.profile != ConcavityProfile::level_curves)
          for (uint32_t v : members[c])
            if (!(mu[v] < lo) && lowest_neighbour[v] < hi) band.push_back(v);
        double best_score = concavity(best, c);
        for (double candidate : candidates) {
          const double score = concavity(candidate, c);
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
                          const VertexAdjacency& adjacency, int max_iterations, int* iterations_out, size_t threads,
                          AffineMotion* motion_out) {
  Clusters refined = clusters;
  const size_t vertex_count = frames.vertex_count;
  int iterations = 0;
  AffineMotion motion;
  bool have_fit = false;
  Clusters fitted;  // the clusters `motion` is the fit of
  for (; iterations < max_iterations; ++iterations) {
    // Each round moves few vertices: the clusters it left alone keep their fit.
    motion = have_fit ? refit_affine_motion(base, frames, refined, fitted, motion, threads)
                      : fit_affine_motion(base, frames, refined, threads);
    fitted = refined, have_fit = true;
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
  if (motion_out)
    *motion_out = !have_fit                        ? fit_affine_motion(base, frames, refined, threads)
                  : refined.label == fitted.label && refined.count == fitted.count ? std::move(motion)
                                                  : refit_affine_motion(base, frames, refined, fitted, motion, threads);
  return refined;
}

}  // namespace segmorph
