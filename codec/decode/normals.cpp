#include "decode/normals.h"

#include <cmath>

namespace segmorph {
namespace {

struct Vec3 {
  double x, y, z;
};

Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec3 operator*(Vec3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double length(Vec3 a) {
  return std::sqrt(dot(a, a));
}

Vec3 load(const float* p, size_t i) {
  return {p[i * 3], p[i * 3 + 1], p[i * 3 + 2]};
}
Vec3 load(const double* p, size_t i) {
  return {p[i * 3], p[i * 3 + 1], p[i * 3 + 2]};
}

// Rotates x by the smallest rotation taking unit vector a to unit vector b (Rodrigues' formula in the
// form R x = c x + v × x + v (v·x) / (1 + c), v = a × b, c = a·b).
Vec3 rotate_between(Vec3 a, Vec3 b, Vec3 x) {
  const Vec3 v = cross(a, b);
  const double c = dot(a, b);
  if (c < -1.0 + 1e-12) {
    // Opposite directions: any half turn about an axis perpendicular to a will do.
    Vec3 axis = cross(a, std::fabs(a.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
    axis = axis * (1.0 / length(axis));
    return axis * (2.0 * dot(axis, x)) - x;
  }
  return x * c + cross(v, x) + v * (dot(v, x) / (1.0 + c));
}

}  // namespace

std::vector<double> welded_vertex_normals(const float* positions, const WeldedTopology& topology) {
  std::vector<double> normals(topology.welded_count() * 3, 0.0);
  for (size_t t = 0; t < topology.triangles.size(); t += 3) {
    const uint32_t a = topology.triangles[t], b = topology.triangles[t + 1], c = topology.triangles[t + 2];
    const Vec3 pa = load(positions, topology.representative[a]);
    const Vec3 pb = load(positions, topology.representative[b]);
    const Vec3 pc = load(positions, topology.representative[c]);
    const Vec3 n = cross(pb - pa, pc - pa);  // twice the area times the unit normal
    for (uint32_t w : {a, b, c}) {
      normals[w * 3] += n.x;
      normals[w * 3 + 1] += n.y;
      normals[w * 3 + 2] += n.z;
    }
  }
  return normals;
}

void deform_normals(const std::vector<double>& rest_geometric, const float* rest_normals, const float* frame_positions,
                    const WeldedTopology& topology, float* out) {
  const std::vector<double> frame_geometric = welded_vertex_normals(frame_positions, topology);
  for (size_t v = 0; v < topology.welded_index.size(); ++v) {
    const uint32_t w = topology.welded_index[v];
    Vec3 n = load(rest_normals, v);
    const Vec3 a = load(rest_geometric.data(), w);
    const Vec3 b = load(frame_geometric.data(), w);
    const double la = length(a), lb = length(b);
    if (la > 0 && lb > 0 && std::isfinite(la) && std::isfinite(lb)) n = rotate_between(a * (1 / la), b * (1 / lb), n);
    const double ln = length(n);
    if (ln > 0 && std::isfinite(ln)) n = n * (1 / ln);
    out[v * 3] = float(n.x);
    out[v * 3 + 1] = float(n.y);
    out[v * 3 + 2] = float(n.z);
  }
}

void deform_normals(const float* rest_positions, const float* rest_normals, const float* frame_positions,
                    const WeldedTopology& topology, float* out) {
  deform_normals(welded_vertex_normals(rest_positions, topology), rest_normals, frame_positions, topology, out);
}

}  // namespace segmorph
