// Fixtures shared by the sampling tests (sampling_*_test.cpp): tiny in-memory models whose sampled positions
// are worked out by hand from the glTF 2.0 specification.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iterator>
#include <ostream>
#include <string>
#include <vector>

#include "gltf_builder.h"
#include "sampling/sample.h"

namespace segmorph {

// Failed EXPECT_EQs on status codes print the name instead of the enum's bytes (found by argument-dependent lookup).
inline void PrintTo(StatusCode code, std::ostream* os) {
  static const char* const kNames[] = {"ok",          "invalid_argument", "io_error", "bad_data",
                                       "unsupported", "nothing_to_do",    "numerical"};  // status.h's order
  const size_t i = size_t(code);
  *os << (i < std::size(kNames) ? kNames[i] : "unknown StatusCode");
}

namespace {

using test::GltfBuilder;

// Positions are floats of order 1 to 10: 1e-5 model units is about 80 float ulps at 1 and 10 at 10, yet far below
// every difference a wrong formula makes in these fixtures (the smallest, slerp against nlerp, is 0.015).
constexpr double kTolerance = 1e-5;  // model units

// 1/√2 and the sines and cosines of the angles the rotation tests reach, to 8 decimals.
constexpr double kHalfSqrt2 = 0.70710678;  // cos 45° = sin 45°
constexpr double kCos22_5 = 0.92387953;
constexpr double kSin22_5 = 0.38268343;

inline testing::AssertionResult IsOk(const Status& status) {
  if (status.ok()) return testing::AssertionSuccess();
  return testing::AssertionFailure() << testing::PrintToString(status.code()) << ": " << status.message();
}

// Vertex v of frame f is within kTolerance model units of `expected` in every coordinate.
inline testing::AssertionResult VertexNear(const FrameSequence& frames, size_t f, size_t v,
                                    const std::array<double, 3>& expected) {
  if (f >= frames.frame_count || v >= frames.vertex_count)
    return testing::AssertionFailure() << "there is no frame " << f << " vertex " << v;
  const float* p = frames.frame(f) + v * 3;
  for (int c = 0; c < 3; ++c)
    if (!(std::fabs(double(p[c]) - expected[size_t(c)]) <= kTolerance))
      return testing::AssertionFailure() << "frame " << f << " (t = " << frames.times[f] << " s) vertex " << v
                                         << " is (" << p[0] << ", " << p[1] << ", " << p[2] << "), expected ("
                                         << expected[0] << ", " << expected[1] << ", " << expected[2] << ")";
  return testing::AssertionSuccess();
}

// Vertex v of frame f is `expected`, bit for bit.
inline testing::AssertionResult VertexEq(const FrameSequence& frames, size_t f, size_t v,
                                  const std::array<float, 3>& expected) {
  if (f >= frames.frame_count || v >= frames.vertex_count)
    return testing::AssertionFailure() << "there is no frame " << f << " vertex " << v;
  const float* p = frames.frame(f) + v * 3;
  if (p[0] == expected[0] && p[1] == expected[1] && p[2] == expected[2]) return testing::AssertionSuccess();
  return testing::AssertionFailure() << testing::PrintToString(std::vector<float>(p, p + 3)) << " != "
                                     << testing::PrintToString(std::vector<float>(expected.begin(), expected.end()))
                                     << " at frame " << f << " vertex " << v;
}

// Analyzes `model` and samples its animated node `index`. `out.node` points into `scene`.
inline Status analyze_and_sample(const tinygltf::Model& model, const SampleSettings& settings, Scene& scene, SampledNode& out,
                          size_t index = 0) {
  SEGMORPH_RETURN_IF_ERROR(analyze_scene(model, scene));
  if (index >= scene.animated.size())
    return Status(StatusCode::invalid_argument, "only " + std::to_string(scene.animated.size()) + " animated nodes");
  return sample_node(model, scene, scene.animated[index], settings, out);
}

inline SampleSettings at_fps(double fps) {
  SampleSettings settings;
  settings.fps = fps;
  return settings;
}

// The morph triangle: three vertices, two morph targets (POSITION deltas).
//   base      v0 (0.1, 0, 0)   v1 (1, 0, 0)    v2 (0, 1, 0)
//   target 0  v0 (0.2, 0, 1)   v1 (0, 0, 2)    v2 (1, 0, 0)
//   target 1  v0 (0, 2, 0)     v1 (-1, 0, 0)   v2 (0, 0, 4)
// With weights (w0, w1):  v0 = (0.1 + 0.2 w0, 2 w1, w0)   v1 = (1 - w1, 0, 2 w0)   v2 = (w0, 1, 4 w1).
inline int add_morph_mesh(GltfBuilder& gltf) {
  const int mesh =
      gltf.add_mesh(gltf.add_vec3({0.1f, 0, 0, 1, 0, 0, 0, 1, 0}),
                    gltf.add_uints({0, 1, 2}, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
  gltf.add_target(mesh, {{"POSITION", gltf.add_vec3({0.2f, 0, 1, 0, 0, 2, 1, 0, 0})}});
  gltf.add_target(mesh, {{"POSITION", gltf.add_vec3({0, 2, 0, -1, 0, 0, 0, 0, 4})}});
  return mesh;
}

// A node instantiating a new morph triangle; returns the node.
inline int add_morph_node(GltfBuilder& gltf) {
  const int node = gltf.add_mesh_node(add_morph_mesh(gltf));
  gltf.add_root(node);
  return node;
}

// Two joints and a triangle bound to them:
//   joint0  root, identity, not animated by the fixture
//   joint1  child of joint0, rest translation (0, 1, 0)
//   inverse bind matrices (when present): identity for joint 0, translate(0, -1, 0) for joint 1 (the inverse
//   of joint 1's rest global transform, so the rest pose leaves the vertices where POSITION puts them)
//   v0 (1, 0, 0) on joint 0;  v1 (0, 2, 0) on joint 1;  v2 (0, 1, 0) half on each.
// JOINTS_0 is UNSIGNED_SHORT and WEIGHTS_0 FLOAT; tests replace them to try other encodings.
// With inverse bind matrices and joint 1 at translation T (joint 0 identity), joint 1's skinning matrix is
// translate(T - (0, 1, 0)), so  v0 = (1, 0, 0),  v1 = (0, 2, 0) + T - (0, 1, 0),  v2 = (0, 1, 0) + (T - (0, 1, 0)) / 2.
struct TwoJointSkin {
  int joint0 = -1;
  int joint1 = -1;
  int mesh = -1;
  int mesh_node = -1;
  int skin = -1;
};

inline TwoJointSkin add_two_joint_skin(GltfBuilder& gltf, bool inverse_bind_matrices = true) {
  TwoJointSkin fixture;
  fixture.joint0 = gltf.add_node();
  fixture.joint1 = gltf.add_node({0, 1, 0});
  gltf.add_child(fixture.joint0, fixture.joint1);
  gltf.add_root(fixture.joint0);
  fixture.mesh = gltf.add_mesh(gltf.add_vec3({1, 0, 0, 0, 2, 0, 0, 1, 0}));
  gltf.set_skin_attributes(
      fixture.mesh, 0,
      gltf.add_uints({0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0}, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT),
      gltf.add_vec4({1, 0, 0, 0, 1, 0, 0, 0, 0.5f, 0.5f, 0, 0}));
  // Column-major 4×4: the identity, then translate(0, -1, 0) (translation in elements 12, 13, 14).
  const std::vector<float> inverse_binds = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0,  0, 1,  //
                                            1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1};
  const int inverse_bind = inverse_bind_matrices ? gltf.add_mat4(inverse_binds) : -1;
  fixture.skin = gltf.add_skin({fixture.joint0, fixture.joint1}, inverse_bind);
  fixture.mesh_node = gltf.add_mesh_node(fixture.mesh, fixture.skin);
  gltf.add_root(fixture.mesh_node);
  return fixture;
}

// Joint 1 translated LINEARly from its rest (0, 1, 0) at t = 0 to (2, 1, 0) at t = 1: T - (0, 1, 0) = (2t, 0, 0),
// so with inverse bind matrices  v1 = (2t, 2, 0)  and  v2 = (t, 1, 0).
inline void move_joint1(GltfBuilder& gltf, const TwoJointSkin& skin, int animation) {
  gltf.add_channel(animation, skin.joint1, "translation", {0, 1}, {0, 1, 0, 2, 1, 0});
}

}  // namespace
}  // namespace segmorph
