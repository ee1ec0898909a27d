// segmorph verify: every primitive measured, the gate (--max-error, --max-bpvf), files that do not play the
// same animation.
#include <gtest/gtest.h>

#include "cli_run.h"

using namespace cli_testing;

// verify reports every animated primitive as well as the worst; the worst is the largest of theirs.
TEST(Cli, VerifyReportsEveryPrimitive) {
  if (!segmorph::testing::have_shared_samples()) GTEST_SKIP() << "../shared/samples is absent";
  const std::string directory = output_directory("verify_primitives");
  const std::string input = std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/gltf/RobotExpressive/RobotExpressive.glb";
  const Result encoded = run("encode -q " + input + " -o " + directory + "/robot.glb --json");
  ASSERT_EQ(encoded.exit_code, 0) << encoded.err;
  // encode measures the 12 rigid parts too, in model space over the clips that move them, and leaves them out of the
  // file's KG (verify's). Before, they had no figures.
  size_t encoded_count = 0;
  double animated_worst = 0;
  for (std::string primitive; !(primitive = json_primitive(encoded.out, encoded_count)).empty(); ++encoded_count) {
    if (primitive.find("\"mode\":\"rigid\"") == std::string::npos) {
      animated_worst = std::max(animated_worst, json_number(primitive, "kg_percent"));
      continue;
    }
    EXPECT_GT(json_number(primitive, "frames"), 1) << primitive;
    EXPECT_GT(json_number(primitive, "kg_percent"), 0) << primitive;
    EXPECT_LT(json_number(primitive, "kg_percent"), 2) << primitive;
  }
  EXPECT_EQ(encoded_count, 19u) << "7 animated primitives and 12 rigid parts";
  EXPECT_EQ(animated_worst, json_number(encoded.out, "kg_percent"));
  const Result result = run("verify -q " + input + " " + directory + "/robot.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  double worst = 0;
  size_t count = 0;
  for (std::string primitive; !(primitive = json_primitive(result.out, count)).empty(); ++count)
    worst = std::max(worst, json_number(primitive, "kg_percent"));
  EXPECT_EQ(count, 7u) << "three morph heads and four skinned hands";
  EXPECT_EQ(worst, json_number(result.out, "kg_percent"));
  const Result text = run("verify -q " + input + " " + directory + "/robot.glb");
  EXPECT_NE(text.out.find("  Head_3, mesh 4 primitive 0: 876 vertices, KG "), std::string::npos) << text.out;
}

// verify as a CI gate: above --max-error or --max-bpvf it exits 1 with one line naming the bound (and, with --json,
// an "above_bound" error in its object); within them, 0. Before, verify had no bound and exited 0 on any error.
TEST(Cli, VerifyGatesOnItsBounds) {
  const std::string directory = output_directory("verify_gate");
  const std::string input = sample("Fox/Fox.glb"), encoded = directory + "/fox.glb";
  ASSERT_EQ(run("encode -q " + input + " -o " + encoded + " --error 0.15").exit_code, 0);
  const Result measured = run("verify -q " + input + " " + encoded + " --json");
  ASSERT_EQ(measured.exit_code, 0) << measured.err;
  const double kg = json_number(measured.out, "kg_percent"), bpvf = json_number(measured.out, "bpvf");
  char bounds[128];
  std::snprintf(bounds, sizeof(bounds), " --max-error %.6g --max-bpvf %.6g", kg * 1.01, bpvf * 1.01);
  EXPECT_EQ(run("verify -q " + input + " " + encoded + bounds).exit_code, 0);

  std::snprintf(bounds, sizeof(bounds), " --max-error %.6g", kg * 0.99);
  Result result = run("verify -q " + input + " " + encoded + bounds);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find("segmorph: error: " + encoded + ": KG "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("is above --max-error"), std::string::npos) << result.err;
  EXPECT_NE(result.out.find("KG "), std::string::npos) << "the figures are printed too";

  std::snprintf(bounds, sizeof(bounds), " --max-bpvf %.6g --json", bpvf * 0.99);
  result = run("verify -q " + input + " " + encoded + bounds);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.out.find("\"error\":{\"code\":\"above_bound\""), std::string::npos) << result.out;
  EXPECT_NE(result.err.find("is above --max-bpvf"), std::string::npos) << result.err;

  // Another animation altogether: RiggedSimple's original against the Fox's encode is far above any bound.
  result = run("verify -q " + sample("RiggedSimple/RiggedSimple.glb") + " " + encoded + " --max-error 1");
  EXPECT_EQ(result.exit_code, 1) << result.out << result.err;
  EXPECT_EQ(run("verify -q " + input + " " + encoded + " --max-error -1").exit_code, 2);
}

// Files that do not play the same animation: no primitive of the other follows the reference's trajectories, and
// verify says which primitive and exits 1 without a gate (before: it paired unrelated meshes and printed
// "KG 2754.9 %" with exit 0 for the cow against the Fox). Unrelated meshes of about the same size at the origin are
// 0.87 to 1.8 times their size apart (the bound is 0.5), skinned or morphed.
TEST(Cli, VerifyOfUnrelatedFilesNamesThePrimitiveWithoutACounterpart) {
  const std::string directory = output_directory("verify_unrelated");
  const std::string rigged = sample("RiggedSimple/RiggedSimple.glb");
  const std::pair<std::string, std::string> unrelated[] = {
      {rigged, sample("Fox/Fox.glb")},
      {sample("SimpleSkin/SimpleSkin.gltf"), rigged},
      {sample("AnimatedMorphCube/AnimatedMorphCube.glb"), sample("SimpleMorph/SimpleMorph.gltf")}};
  for (const auto& [reference, other] : unrelated) {
    SCOPED_TRACE(reference);
    const Result result = run("verify -q " + reference + " " + other);
    EXPECT_EQ(result.exit_code, 1) << result.out;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_NE(result.err.find("segmorph: error: " + other + ": has no primitive that plays primitive 0 of "),
              std::string::npos)
        << result.err;
    EXPECT_NE(result.err.find("(the files do not play the same animation)"), std::string::npos) << result.err;
    const Result json = run("verify -q " + reference + " " + other + " --json");
    EXPECT_EQ(json.exit_code, 1);
    EXPECT_EQ(json.out.rfind("{\"error\":{\"code\":\"bad_data\"", 0), 0u) << json.out;
  }
  // A file against its own encode still pairs.
  ASSERT_EQ(run("encode -q " + rigged + " -o " + directory + "/rigged.glb").exit_code, 0);
  EXPECT_EQ(run("verify -q " + rigged + " " + directory + "/rigged.glb").exit_code, 0);
}
