// The heat-diffusion Morse function of Hachani et al. (§2.2, Eqs. 4–5).
//
// Diffusion distance d_t²(x, y) = Σ_i e^(−λ_i t) (φ_i(x) − φ_i(y))² (Laplace–Beltrami eigenpairs), integrated
// over log t on [t1, t2], is a smooth, noise-robust distance. From the two most distant points v1, v2 of a
// component, the functions f_v1, f_v2 (integrated distance to v_i) have their maxima at the shape's tips;
// the tips found by both (Tierny et al.'s extrema, neighbourhood ε) are the feature points F, and
// μ(v) = (1/area) Σ_{p∈F} d²(v, p) · area(p) grows from the tips inwards: its level sets cut limbs across.
//
// Choices where the paper is silent or ambiguous (NOTES.md):
// - the time range is t2 = 1/(2 λ_1) (the paper's scale-invariant time) down to t1 = 4 / λ_n, where the
//   highest eigenpair kept contributes e^(−4): a finer t1 lets the truncated spectrum ring, and the ripples
//   become spurious extrema (measured on a stretched sphere: feature points in the middle of the shape);
//   the integral over log t is a trapezoid rule on `time_samples` log-spaced times;
// - "two most distant points" are geodesic (edge-path lengths, double sweep of Dijkstra);
// - an extremum is a vertex whose f is largest within geodesic distance ε · sqrt(component area) of it;
//   F keeps the extrema of f_v1 that have an extremum of f_v2 within that distance;
// - μ uses the same integrated distance as the feature functions.
// Each connected component gets its own eigenpairs, feature points and μ.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/topology.h"
#include "segmorph/status.h"

namespace segmorph {

struct DiffusionSettings {
  size_t eigenpairs = 40;  // per component, the constant one included
  double epsilon = 0.074;  // extremum neighbourhood, as a fraction of sqrt(component area)
  int time_samples = 24;   // log-spaced times of the integral over [t1, t2]
  size_t threads = 1;      // for the eigenpairs (EigenSettings::threads); μ is the same for any number
  // Told each step ("eigenpairs: factorizing", "feature points", ...); empty: nothing.
  std::function<void(const std::string& step)> progress;
};

struct MorseFunction {
  std::vector<double> mu;                                // W
  std::vector<uint32_t> feature_points;                  // welded vertices, all components
  std::vector<std::array<uint32_t, 2>> farthest_points;  // per component: v1, v2
};

// μ over the welded mesh whose first-frame positions are `positions` (W × 3 doubles, row-major).
Status diffusion_morse_function(const std::vector<double>& positions, const WeldedTopology& topology,
                                const VertexAdjacency& adjacency, const DiffusionSettings& settings,
                                MorseFunction& out);

// Geodesic (edge-path) distances from `source` to every welded vertex (infinity where unreachable).
std::vector<double> edge_path_distances(const std::vector<double>& positions, const VertexAdjacency& adjacency,
                                        uint32_t source, double limit = INFINITY);

// Edge-path distances within a limit of one source after another, each in time proportional to the vertices it
// reaches (edge_path_distances, which runs one, returns a distance for every welded vertex).
class GeodesicBall {
 public:
  GeodesicBall(const std::vector<double>& positions, const VertexAdjacency& adjacency);
  // The vertices within `limit` of `source` (the source first), in the order they were reached; their distances by
  // distance(). Valid until the next call. With `stop`, the search ends at the first vertex reached for which it is
  // true (then the last one returned), and stopped() says so.
  const std::vector<uint32_t>& reach(uint32_t source, double limit,
                                     const std::function<bool(uint32_t vertex)>& stop = {});
  bool stopped() const { return stopped_; }
  double distance(uint32_t vertex) const { return distance_[vertex]; }
  // Every welded vertex's distance from the last call's source (infinity where not reached), taken from the ball.
  std::vector<double> distances() && { return std::move(distance_); }

 private:
  const std::vector<double>& positions_;
  const VertexAdjacency& adjacency_;
  std::vector<double> distance_;  // W, infinity but for the vertices reached by the last call
  std::vector<uint32_t> reached_;
  bool stopped_ = false;
};

}  // namespace segmorph
