// segmorph info: the animated primitives and clips of a file.
#include <gtest/gtest.h>

#include "cli_run.h"

using namespace cli_testing;

TEST(Cli, InfoReportsPrimitivesAndClips) {
  Result result = run("info -q " + sample("Fox/Fox.glb"));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("skinned, 1728 vertices"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("\"Walk\""), std::string::npos) << result.out;
  result = run("info -q --json " + sample("AnimatedMorphCube/AnimatedMorphCube.glb"));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* key : {"\"kind\":\"morph\"", "\"vertices\":24", "\"triangles\":12", "\"connected_components\":1",
                          "\"frames\":127", "\"baked_bytes\":36576"})
    EXPECT_NE(result.out.find(key), std::string::npos) << key << " in " << result.out;
}
