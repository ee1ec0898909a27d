#include "sampling/animation.h"

#include <algorithm>
#include <cmath>

#include "accessor.h"

namespace segmorph {
namespace {

void normalize_quaternion(double* q) {
  const double length = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (length > 0)
    for (int i = 0; i < 4; ++i) q[i] /= length;
}

// Shortest-path spherical interpolation of unit quaternions a and b at u in [0, 1].
void slerp(const float* a, const float* b, double u, double* out) {
  double d = 0;
  for (int i = 0; i < 4; ++i) d += double(a[i]) * b[i];
  const double sign = d < 0 ? -1.0 : 1.0;
  d *= sign;
  double wa, wb;
  if (d > 1.0 - 1e-9) {  // nearly equal: slerp's weights tend to the linear ones
    wa = 1 - u;
    wb = u;
  } else {
    const double angle = std::acos(d);
    const double s = std::sin(angle);
    wa = std::sin((1 - u) * angle) / s;
    wb = std::sin(u * angle) / s;
  }
  for (int i = 0; i < 4; ++i) out[i] = wa * a[i] + wb * sign * b[i];
  normalize_quaternion(out);
}

}  // namespace

void Curve::evaluate(double t, bool rotation, double* out) const {
  const size_t keys = times.size();
  const bool cubic = interpolation == Interpolation::cubic_spline;
  // Element e of key k (for CUBICSPLINE: 0 in-tangent, 1 value, 2 out-tangent).
  auto key = [&](size_t k, int e) { return values.data() + (cubic ? (k * 3 + size_t(e)) : k) * size_t(width); };
  auto copy = [&](const float* v) {
    for (int i = 0; i < width; ++i) out[i] = v[i];
    if (rotation) normalize_quaternion(out);
  };

  if (t <= times.front() || keys == 1) return copy(key(0, 1));
  if (t >= times.back()) return copy(key(keys - 1, 1));
  // k: last key with times[k] <= t, so times[k] <= t < times[k + 1].
  const size_t k = size_t(std::upper_bound(times.begin(), times.end(), float(t)) - times.begin()) - 1;
  const double t0 = times[k], t1 = times[k + 1];
  if (interpolation == Interpolation::step || t1 <= t0) return copy(key(k, 1));
  const double u = (t - t0) / (t1 - t0);

  if (interpolation == Interpolation::linear) {
    if (rotation) return slerp(key(k, 1), key(k + 1, 1), u, out);
    const float* a = key(k, 1);
    const float* b = key(k + 1, 1);
    for (int i = 0; i < width; ++i) out[i] = a[i] * (1 - u) + b[i] * u;
    return;
  }
  // Cubic Hermite spline of the glTF 2.0 specification (Appendix C), tangents scaled by the key interval.
  const double dt = t1 - t0, u2 = u * u, u3 = u2 * u;
  const double h_value0 = 2 * u3 - 3 * u2 + 1, h_tangent0 = u3 - 2 * u2 + u;
  const double h_value1 = -2 * u3 + 3 * u2, h_tangent1 = u3 - u2;
  const float* v0 = key(k, 1);
  const float* b0 = key(k, 2);
  const float* v1 = key(k + 1, 1);
  const float* a1 = key(k + 1, 0);
  for (int i = 0; i < width; ++i)
    out[i] = h_value0 * v0[i] + h_tangent0 * dt * b0[i] + h_value1 * v1[i] + h_tangent1 * dt * a1[i];
  if (rotation) normalize_quaternion(out);
}

Status load_clip(const tinygltf::Model& model, int index, Clip& clip) {
  const tinygltf::Animation& animation = model.animations[size_t(index)];
  clip = Clip();
  clip.animation = index;
  clip.name = animation.name.empty() ? "animation " + std::to_string(index) : animation.name;
  const std::string where = "animation " + std::to_string(index);
  for (size_t c = 0; c < animation.channels.size(); ++c) {
    const tinygltf::AnimationChannel& channel = animation.channels[c];
    const std::string what = where + " channel " + std::to_string(c);
    if (channel.target_node < 0) continue;  // targets defined by extensions only: nothing to evaluate
    if (size_t(channel.target_node) >= model.nodes.size())
      return Status(StatusCode::bad_data, what + " targets node " + std::to_string(channel.target_node) +
                                              ", which does not exist");
    Track track;
    track.node = channel.target_node;
    if (channel.target_path == "translation") track.path = TargetPath::translation;
    else if (channel.target_path == "rotation") track.path = TargetPath::rotation;
    else if (channel.target_path == "scale") track.path = TargetPath::scale;
    else if (channel.target_path == "weights") track.path = TargetPath::weights;
    else continue;  // "pointer" and other extension paths do not move vertices

    if (channel.sampler < 0 || size_t(channel.sampler) >= animation.samplers.size())
      return Status(StatusCode::bad_data, what + " names a sampler that does not exist");
    const tinygltf::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
    Curve& curve = track.curve;
    if (sampler.interpolation == "STEP") curve.interpolation = Interpolation::step;
    else if (sampler.interpolation == "CUBICSPLINE") curve.interpolation = Interpolation::cubic_spline;
    else if (sampler.interpolation.empty() || sampler.interpolation == "LINEAR") curve.interpolation = Interpolation::linear;
    else return Status(StatusCode::bad_data, what + ": unknown interpolation " + sampler.interpolation);

    int components = 0;
    SEGMORPH_RETURN_IF_ERROR(read_floats(model, sampler.input, what + " input", curve.times, &components));
    if (components != 1 || curve.times.empty())
      return Status(StatusCode::bad_data, what + ": key times must be a non-empty scalar accessor");
    for (size_t k = 1; k < curve.times.size(); ++k)
      if (curve.times[k] < curve.times[k - 1])
        return Status(StatusCode::bad_data, what + ": key times decrease at key " + std::to_string(k));
    if (curve.times.front() < 0) return Status(StatusCode::bad_data, what + ": key times are negative");
    SEGMORPH_RETURN_IF_ERROR(read_floats(model, sampler.output, what + " output", curve.values, &components));

    const size_t keys = curve.times.size();
    const size_t per_key = curve.interpolation == Interpolation::cubic_spline ? 3 : 1;
    const size_t elements = curve.values.size() / size_t(components);
    const int expected_components = track.path == TargetPath::rotation ? 4 : track.path == TargetPath::weights ? 1 : 3;
    if (components != expected_components)
      return Status(StatusCode::bad_data, what + ": output has the wrong type for " + channel.target_path);
    if (elements % (keys * per_key) != 0 || elements == 0)
      return Status(StatusCode::bad_data, what + ": output count does not match the key count");
    curve.width = int(elements / (keys * per_key) * size_t(components));
    clip.tracks.push_back(std::move(track));
  }
  return Status::Ok();
}

Status build_node_graph(const tinygltf::Model& model, NodeGraph& graph) {
  const size_t count = model.nodes.size();
  graph.parent.assign(count, -1);
  graph.order.clear();
  for (size_t n = 0; n < count; ++n)
    for (int child : model.nodes[n].children) {
      if (child < 0 || size_t(child) >= count)
        return Status(StatusCode::bad_data, "node " + std::to_string(n) + " has a child that does not exist");
      if (graph.parent[size_t(child)] != -1 || size_t(child) == n)
        return Status(StatusCode::bad_data, "node " + std::to_string(child) + " has more than one parent");
      graph.parent[size_t(child)] = int(n);
    }
  // Breadth-first from the roots; nodes never reached sit on a cycle.
  for (size_t n = 0; n < count; ++n)
    if (graph.parent[n] < 0) graph.order.push_back(int(n));
  for (size_t i = 0; i < graph.order.size(); ++i)
    for (int child : model.nodes[size_t(graph.order[i])].children) graph.order.push_back(child);
  if (graph.order.size() != count) return Status(StatusCode::bad_data, "the node hierarchy has a cycle");
  return Status::Ok();
}

namespace {

// A node's local TRS at some time: its own, or a clip's tracks where they animate it.
struct Trs {
  double translation[3] = {0, 0, 0};
  double rotation[4] = {0, 0, 0, 1};
  double scale[3] = {1, 1, 1};
  bool animated = false;
};

Trs rest_trs(const tinygltf::Node& node) {
  Trs local;
  if (node.translation.size() == 3) std::copy(node.translation.begin(), node.translation.end(), local.translation);
  if (node.rotation.size() == 4) std::copy(node.rotation.begin(), node.rotation.end(), local.rotation);
  if (node.scale.size() == 3) std::copy(node.scale.begin(), node.scale.end(), local.scale);
  return local;
}

void animate(const Track& track, double t, Trs& local) {
  switch (track.path) {
    case TargetPath::translation: track.curve.evaluate(t, false, local.translation); break;
    case TargetPath::rotation: track.curve.evaluate(t, true, local.rotation); break;
    case TargetPath::scale: track.curve.evaluate(t, false, local.scale); break;
    case TargetPath::weights: return;
  }
  local.animated = true;
}

Eigen::Matrix4d local_matrix(const tinygltf::Node& node, const Trs& local) {
  Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();
  // A node with a matrix is not animated by TRS channels (the specification forbids both); should a file do
  // it anyway, the animated TRS wins, as in common viewers.
  if (node.matrix.size() == 16 && !local.animated) {
    for (int i = 0; i < 16; ++i) matrix(i % 4, i / 4) = node.matrix[size_t(i)];
  } else {
    double q[4] = {local.rotation[0], local.rotation[1], local.rotation[2], local.rotation[3]};
    normalize_quaternion(q);
    const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
    matrix.block<3, 3>(0, 0) =
        rotation.toRotationMatrix() * Eigen::Vector3d(local.scale[0], local.scale[1], local.scale[2]).asDiagonal();
    matrix.block<3, 1>(0, 3) = Eigen::Vector3d(local.translation[0], local.translation[1], local.translation[2]);
  }
  return matrix;
}

}  // namespace

void evaluate_global_transforms(const tinygltf::Model& model, const NodeGraph& graph, const Clip* clip, double t,
                                std::vector<Eigen::Matrix4d>& global) {
  const size_t count = model.nodes.size();
  std::vector<Trs> trs(count);
  for (size_t n = 0; n < count; ++n) trs[n] = rest_trs(model.nodes[n]);
  if (clip)
    for (const Track& track : clip->tracks) animate(track, t, trs[size_t(track.node)]);
  global.resize(count);
  for (int n : graph.order) {
    const Eigen::Matrix4d matrix = local_matrix(model.nodes[size_t(n)], trs[size_t(n)]);
    const int parent = graph.parent[size_t(n)];
    global[size_t(n)] = parent < 0 ? matrix : Eigen::Matrix4d(global[size_t(parent)] * matrix);
  }
}

Eigen::Matrix4d evaluate_global_transform(const tinygltf::Model& model, const NodeGraph& graph, const Clip* clip,
                                          double t, int node) {
  std::vector<int> chain;  // the node, then its ancestors
  for (int n = node; n >= 0; n = graph.parent[size_t(n)]) chain.push_back(n);
  std::vector<Trs> trs(chain.size());
  for (size_t i = 0; i < chain.size(); ++i) trs[i] = rest_trs(model.nodes[size_t(chain[i])]);
  if (clip)
    for (const Track& track : clip->tracks) {
      const auto at = std::find(chain.begin(), chain.end(), track.node);
      if (at != chain.end()) animate(track, t, trs[size_t(at - chain.begin())]);
    }
  Eigen::Matrix4d global = local_matrix(model.nodes[size_t(chain.back())], trs.back());
  for (size_t i = chain.size() - 1; i-- > 0;)
    global = Eigen::Matrix4d(global * local_matrix(model.nodes[size_t(chain[i])], trs[i]));
  return global;
}

double largest_scale(const Eigen::Matrix4d& transform) {
  return std::max({transform.col(0).head<3>().norm(), transform.col(1).head<3>().norm(),
                   transform.col(2).head<3>().norm()});
}

}  // namespace segmorph
