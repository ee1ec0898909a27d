// The command-line tool as a user meets it: exit codes, one-line errors, no partial output.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include "accessor.h"
#include "gltf/gltf_io.h"
#include "test_files.h"

namespace {

using segmorph::testing::json_number;
using segmorph::testing::temporary_path;
namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string out, err;
};

std::string read_text(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

Result run(const std::string& arguments) {
  const std::string out = temporary_path("cli.out"), err = temporary_path("cli.err");
  const std::string command = std::string(SEGMORPH_BINARY) + " " + arguments + " >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(command.c_str());
  Result result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = read_text(out);
  result.err = read_text(err);
  return result;
}

std::string sample(const std::string& relative) {
  return std::string(SEGMORPH_SAMPLES_DIR) + "/" + relative;
}

// A fresh directory for outputs, so leftovers are easy to see.
std::string output_directory(const std::string& name) {
  const std::string directory = temporary_path(name);
  fs::remove_all(directory);
  fs::create_directories(directory);
  return directory;
}

// Runs bake (or `command`) with a bad input and checks the promise: exit 1, one line naming the file, no output,
// no leftovers.
// SimpleMorph's two .bin files copied into `directory`, and its JSON to edit and write beside them.
std::string simple_morph_in(const std::string& directory) {
  fs::copy_file(sample("SimpleMorph/simpleMorphGeometry.bin"), directory + "/simpleMorphGeometry.bin");
  fs::copy_file(sample("SimpleMorph/simpleMorphAnimation.bin"), directory + "/simpleMorphAnimation.bin");
  return read_text(sample("SimpleMorph/SimpleMorph.gltf"));
}

void expect_clean_failure(const std::string& input, const std::string& expected_message,
                          const std::string& command = "bake", const std::string& options = "") {
  SCOPED_TRACE(input + options);
  const std::string directory = output_directory("failure");
  const Result result = run(command + " -q '" + input + "' " + options + " -o " + directory + "/out.glb");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find(input), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(expected_message), std::string::npos) << result.err;
  EXPECT_TRUE(fs::is_empty(directory)) << command << " left files behind";
}

TEST(Cli, HelpAndVersion) {
  Result help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("bake IN -o OUT"), std::string::npos);
  EXPECT_NE(help.out.find("info FILE"), std::string::npos);
  EXPECT_EQ(run("--version").exit_code, 0);
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run("").exit_code, 2);
  EXPECT_EQ(run("frobnicate x.glb").exit_code, 2);
  EXPECT_EQ(run("bake " + sample("Fox/Fox.glb")).exit_code, 2);                  // no -o
  EXPECT_EQ(run("bake " + sample("Fox/Fox.glb") + " -o out.obj").exit_code, 2);  // not glTF
  EXPECT_EQ(run("info " + sample("Fox/Fox.glb") + " --fps abc").exit_code, 2);
  EXPECT_EQ(run("info " + sample("Fox/Fox.glb") + " --fps -3").exit_code, 2);
  EXPECT_EQ(run("info --bogus " + sample("Fox/Fox.glb")).exit_code, 2);
  EXPECT_EQ(run("info a.glb b.glb").exit_code, 2);
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --error 0.5 --bpvf 2").exit_code, 2);
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --error -1").exit_code, 2);
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --clusters 0").exit_code, 2);
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --position-bits 7").exit_code, 2);
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --position-bits 23").exit_code, 2);
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --position-bits 30").exit_code, 2);  // crashed
  EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o x.glb --position-bits 12.5").exit_code, 2);
  EXPECT_EQ(run("verify " + sample("Fox/Fox.glb")).exit_code, 2);
}

// Options come from one table: --name=value is the same as --name value, and an option the command does not use is
// refused, naming the option and the command.
TEST(Cli, OptionsAreReadOneWayForEveryCommand) {
  const std::string directory = output_directory("options");
  const std::string input = sample("SimpleMorph/SimpleMorph.gltf");
  ASSERT_EQ(run("encode -q " + input + " -o " + directory + "/spaced.glb --error 0.5 --clusters 3").exit_code, 0);
  ASSERT_EQ(run("-q encode " + input + " --error=0.5 --clusters=3 --output=" + directory + "/equals.glb").exit_code,
            0);
  EXPECT_EQ(read_text(directory + "/spaced.glb"), read_text(directory + "/equals.glb"));
  struct Refused {
    std::string arguments, message;
  };
  const Refused refused[] = {
      {"decode " + input + " -o " + directory + "/x.glb --json", "--json is not an option of decode"},
      {"decode " + input + " -o " + directory + "/x.glb --error 0.5", "--error is not an option of decode"},
      {"bake " + input + " -o " + directory + "/x.glb --json", "--json is not an option of bake"},
      {"verify " + input + " " + input + " --clusters 4", "--clusters is not an option of verify"},
      {"info " + input + " -o " + directory + "/x.glb", "-o is not an option of info"},
      {"info " + input + " --frames " + directory + "/x.bin", "--frames is not an option of info"},
      {"info " + input + " --json=yes", "--json takes no value"},
      {"info " + input + " --fps=", "--fps takes a number more than 0 and at most 1000, not ''"},
      {"info " + input + " --fps 0", "--fps takes a number more than 0 and at most 1000, not '0'"},
      {"encode " + input + " -o " + directory + "/x.glb --error 1000", "at most 100, not '1000'"},
      {"encode " + input + " -o " + directory + "/x.glb --skins=some", "--skins takes keep or bake, not 'some'"},
      {"encode " + input + " -o " + directory + "/x.glb --targets", "--targets needs auto, keep or bake"},
      {"encode " + input + " -o " + directory + "/x.glb --lossless --error=1", "give one of --error, --bpvf and"},
  };
  for (const Refused& r : refused) {
    const Result result = run(r.arguments);
    EXPECT_EQ(result.exit_code, 2) << r.arguments;
    EXPECT_NE(result.err.find(r.message), std::string::npos) << r.arguments << ": " << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  }
  EXPECT_FALSE(fs::exists(directory + "/x.glb"));
}

// Every range --help states is the one the tool holds: its ends are accepted (the run then fails on the missing
// input, exit 1) and a step beyond them is a usage error (exit 2).
TEST(Cli, HelpStatesEveryRangeTheToolHolds) {
  const std::string help = run("--help").out;
  std::vector<std::string> entries;  // one per option, its wrapped lines joined
  std::istringstream lines(help.substr(help.find("\nOptions")));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("  -", 0) == 0)
      entries.push_back(line);
    else if (!entries.empty() && line.rfind("                     ", 0) == 0)
      entries.back() += " " + line.substr(21);
  }
  const std::regex range(R"(^  (?:-\w, )?(--[a-z-]+) \S+ +([a-z, ]+): .*(from (\d+) to (\d+)|more than (\S+) and at most (\S+)))");
  const std::string missing = temporary_path("missing.glb"), output = temporary_path("never.glb");
  fs::remove(missing);
  fs::remove_all(output);
  int ranges = 0;
  for (const std::string& entry : entries) {
    std::smatch match;
    if (!std::regex_search(entry, match, range)) continue;
    ++ranges;
    const std::string option = match[1], command = std::string(match[2]).substr(0, std::string(match[2]).find(','));
    std::string files = command + " " + missing;
    if (command == "verify") files += " " + missing;
    if (command == "bake" || command == "encode")
      files += option == "--jobs" ? " --output-dir " + output + ".d" : " -o " + output;
    const bool whole = match[4].matched;
    const double low = std::stod(whole ? match[4] : match[6]), high = std::stod(whole ? match[5] : match[7]);
    std::vector<std::pair<double, int>> cases = {{high, 1}, {high + 1, 2}};
    if (whole)
      cases.insert(cases.end(), {{low, 1}, {low - 1, 2}});
    else
      cases.insert(cases.end(), {{low, 2}, {low + (high - low) * 1e-3, 1}});
    for (const auto& [value, code] : cases) {
      char text[32];
      std::snprintf(text, sizeof(text), "%.10g", value);
      EXPECT_EQ(run(files + " -q " + option + " " + text).exit_code, code) << entry << "\n  value " << text;
    }
  }
  EXPECT_EQ(ranges, 12) << help;  // --fps, --error, --bpvf, --clusters, the Draco precisions, verify's bounds, --jobs,
                                 // --threads, --max-stream-version
  EXPECT_FALSE(fs::exists(output));
  fs::remove_all(output + ".d");  // the batch's folder (its one file was missing)
}

TEST(Cli, BadInputsFailCleanly) {
  const std::string directory = output_directory("inputs");
  expect_clean_failure(directory + "/missing.glb", "cannot open");
  expect_clean_failure(directory, "no .obj files in the folder (a folder input is an OBJ sequence)");

  write_text(directory + "/text.gltf", "hello, I am not glTF\n");
  expect_clean_failure(directory + "/text.gltf", "not a glTF file");
  // GLB chunks longer than the file: tinygltf 2.7 reads past its buffer (found by fuzzing). A file cut short,
  // and one whose header says so but whose BIN chunk claims 4 bytes more.
  const std::string glb = read_text(sample("AnimatedMorphCube/AnimatedMorphCube.glb"));
  write_text(directory + "/short.glb", glb.substr(0, glb.size() - 4));
  expect_clean_failure(directory + "/short.glb", "chunk lengths");
  std::string longer = glb;
  const size_t bin = 20 + size_t(uint8_t(glb[12])) + (size_t(uint8_t(glb[13])) << 8) + (size_t(uint8_t(glb[14])) << 16);
  longer[bin] = char(uint8_t(longer[bin]) + 4);  // the BIN chunk's length, low byte (0xBC in this file: no carry)
  write_text(directory + "/long_chunk.glb", longer);
  expect_clean_failure(directory + "/long_chunk.glb", "chunk lengths");
  // 30 000 nested arrays crash tinygltf 2.7's recursive parser (stack overflow); segmorph refuses them first.
  write_text(directory + "/deep.gltf",
             "{\"asset\": {\"version\": \"2.0\"}, \"x\": " + std::string(30000, '[') + std::string(30000, ']') + "}");
  expect_clean_failure(directory + "/deep.gltf", "nested deeper");

  write_text(directory + "/broken.gltf", "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ {");
  expect_clean_failure(directory + "/broken.gltf", "cannot parse");

  const std::string fox = read_text(sample("Fox/Fox.glb"));
  write_text(directory + "/truncated.glb", fox.substr(0, fox.size() / 2));
  expect_clean_failure(directory + "/truncated.glb", "cannot parse");

  write_text(directory + "/still.gltf", R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{}]})");
  expect_clean_failure(directory + "/still.gltf", "nothing animated");

  write_text(directory + "/meshopt.gltf", R"({"asset":{"version":"2.0"},"extensionsUsed":["EXT_meshopt_compression"],)"
                                          R"("extensionsRequired":["EXT_meshopt_compression"],"nodes":[{}]})");
  expect_clean_failure(directory + "/meshopt.gltf", "EXT_meshopt_compression");

  // SimpleMorph with its first accessor claiming more vertices than its bufferView holds.
  std::string morph = simple_morph_in(directory);
  const size_t count = morph.find("\"count\"");
  ASSERT_NE(count, std::string::npos);
  morph.replace(count, morph.find_first_of(",}", count) - count, "\"count\" : 3000000");
  write_text(directory + "/out_of_range.gltf", morph);
  expect_clean_failure(directory + "/out_of_range.gltf", "accessor");
}

// SimpleMorph with its last key time (the fifth float of simpleMorphAnimation.bin) at 1e9 s: at --fps 30, 3e10
// frames. Refused in one line; before, sampling hung building them.
TEST(Cli, AGridOfTooManyFramesIsRefused) {
  const std::string directory = output_directory("forever");
  write_text(directory + "/forever.gltf", simple_morph_in(directory));
  {
    std::fstream times(directory + "/simpleMorphAnimation.bin", std::ios::in | std::ios::out | std::ios::binary);
    const float forever = 1e9f;
    times.seekp(16);
    times.write(reinterpret_cast<const char*>(&forever), sizeof(forever));
    ASSERT_TRUE(times.good());
  }
  expect_clean_failure(directory + "/forever.gltf", "frames at --fps 30, above the 1e+06 a clip may have", "bake",
                       "--fps 30");
  EXPECT_EQ(run("info -q " + directory + "/forever.gltf").exit_code, 0) << "without --fps, the frames are the keys";
}

// SimpleMorph with a TEXCOORD_0 accessor whose bufferView names a missing buffer, or lies outside its buffer: bake
// keeps the attribute without reading it, and repack copied the view unchecked (found by tests/fuzz).
TEST(Cli, UnreadBufferViewOutsideItsBufferFailsCleanly) {
  const std::string directory = output_directory("views");
  const std::string original = simple_morph_in(directory);
  for (const std::string view :
       {R"({"buffer":7,"byteLength":24})", R"({"buffer":1,"byteOffset":48,"byteLength":24})"}) {
    std::string morph = original;
    const std::string position = "\"POSITION\":1";
    morph.insert(morph.find(position) + position.size(), ",\"TEXCOORD_0\":6");
    // New last entries of "accessors" (followed by "asset") and "bufferViews" (followed by "accessors").
    morph.insert(morph.rfind(']', morph.find("\"asset\"")),
                 R"(,{"bufferView":4,"componentType":5126,"count":3,"type":"VEC2"})");
    morph.insert(morph.rfind(']', morph.find("\"accessors\"")), "," + view);
    write_text(directory + "/texcoord.gltf", morph);
    expect_clean_failure(directory + "/texcoord.gltf", "bufferView 4");
  }
}

// References bake_model follows without checking them itself (found by tests/fuzz): a skin index on a node without
// a mesh (analyze_scene checks skins only where there is a mesh), and a child index in an encoded file (decoding
// bakes without analyze_scene).
TEST(Cli, BadNodeReferencesFailCleanly) {
  const std::string directory = output_directory("references");
  std::string morph = simple_morph_in(directory);
  morph.insert(morph.find('}', morph.find("\"mesh\":0")) + 1, R"(,{"skin":99})");  // a second node
  write_text(directory + "/skin.gltf", morph);
  expect_clean_failure(directory + "/skin.gltf", "skin that does not exist");

  ASSERT_EQ(run("encode -q " + sample("AnimatedMorphCube/AnimatedMorphCube.glb") + " -o " + directory + "/cube.gltf")
                .exit_code,
            0);
  std::string cube = read_text(directory + "/cube.gltf");
  cube.insert(cube.find("\"mesh\": 0"), R"("children": [99], )");
  write_text(directory + "/cube.gltf", cube);
  expect_clean_failure(directory + "/cube.gltf", "child that does not exist", "decode");
}

// An encoded file whose Draco attribute map gives TANGENT the normals (three components) or NORMAL the tangents
// (four): decoding baked them unchecked and read past the end (found by tests/fuzz).
TEST(Cli, DecodedNormalsOrTangentsOfTheWrongShapeFailCleanly) {
  const std::string directory = output_directory("shapes");
  ASSERT_EQ(run("encode -q " + sample("AnimatedMorphCube/AnimatedMorphCube.glb") + " -o " + directory + "/cube.gltf")
                .exit_code,
            0);
  const std::string cube = read_text(directory + "/cube.gltf");
  ASSERT_NE(cube.find("\"NORMAL\": 1,"), std::string::npos);
  ASSERT_NE(cube.find("\"TANGENT\": 2"), std::string::npos);
  std::string tangent = cube, normal = cube;
  tangent.replace(tangent.find("\"TANGENT\": 2"), 12, "\"TANGENT\": 1");
  normal.replace(normal.find("\"NORMAL\": 1,"), 12, "\"NORMAL\": 2,");
  write_text(directory + "/tangent.gltf", tangent);
  write_text(directory + "/normal.gltf", normal);
  expect_clean_failure(directory + "/tangent.gltf", "TANGENT must be VEC4", "decode");
  expect_clean_failure(directory + "/normal.gltf", "NORMAL must be VEC3", "decode");
}

TEST(Cli, CorruptedInputsFailCleanlyOrBake) {
  // Random byte changes and truncations of small samples: every run either bakes or fails with exit 1 and one
  // line, and never leaves output behind on failure. (Crashes and memory errors show under the sanitizer build.)
  std::mt19937 random(2024);
  const std::string directory = output_directory("corrupt");
  for (const char* name : {"AnimatedMorphCube/AnimatedMorphCube.glb", "SimpleSkin/SimpleSkin.gltf"}) {
    const std::string original = read_text(sample(name));
    const std::string extension = fs::path(name).extension().string();
    for (int trial = 0; trial < 60; ++trial) {
      std::string bytes = original;
      const int changes = 1 + int(random() % 8);
      for (int c = 0; c < changes; ++c) bytes[random() % bytes.size()] = char(random() % 256);
      if (trial % 5 == 0) bytes.resize(random() % bytes.size());
      const std::string input = directory + "/input" + extension, output = directory + "/out.glb";
      write_text(input, bytes);
      fs::remove(output);
      const Result result = run("bake -q " + input + " -o " + output);
      SCOPED_TRACE(std::string(name) + " trial " + std::to_string(trial));
      ASSERT_TRUE(result.exit_code == 0 || result.exit_code == 1) << result.exit_code << " " << result.err;
      if (result.exit_code == 1) {
        EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
        EXPECT_FALSE(fs::exists(output));
      }
    }
  }
}

TEST(Cli, UnwritableOutputFailsCleanly) {
  const Result result =
      run("bake -q " + sample("SimpleSkin/SimpleSkin.gltf") + " -o " + temporary_path("no/such/dir/out.glb"));
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
}

// `command` run by bash, its output and exit status.
Result run_shell(const std::string& command) {
  const std::string out = temporary_path("shell.out"), err = temporary_path("shell.err");
  const std::string line = "bash -c '" + command + "' >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(line.c_str());
  Result result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = read_text(out);
  result.err = read_text(err);
  return result;
}

// A write that fails part way (the file size limit of the process, as a full disk would) is an error of one line,
// exit 1, and leaves neither the output nor a temporary file: for bake, encode and decode, .glb and .gltf (both of
// its files), and decode --frames.
TEST(Cli, FailedWritesLeaveNothing) {
  const std::string directory = output_directory("failed-writes");
  const std::string encoded = directory + "/../failed-writes-input.glb";
  ASSERT_EQ(run("encode -q --skins bake " + sample("Fox/Fox.glb") + " -o " + encoded).exit_code, 0);
  const std::string segmorph = SEGMORPH_BINARY;
  const std::vector<std::string> commands = {
      "bake -q " + sample("Fox/Fox.glb") + " -o " + directory + "/out.glb",
      "bake -q " + sample("Fox/Fox.glb") + " -o " + directory + "/out.gltf",
      "encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/out.glb",
      "encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/out.gltf",
      "decode -q " + encoded + " -o " + directory + "/out.glb",
      "decode -q " + encoded + " -o " + directory + "/out.gltf",
      "decode -q " + encoded + " --frames " + directory + "/frames.bin",
  };
  for (const std::string& command : commands) {
    // Files grow past 16 KiB only by failing writes (EFBIG; the signal that would end the process is ignored).
    const Result result = run_shell("trap \"\" XFSZ; ulimit -f 16; exec " + segmorph + " " + command);
    EXPECT_EQ(result.exit_code, 1) << command << "\n" << result.err;
    EXPECT_NE(result.err.find("cannot write"), std::string::npos) << command << "\n" << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_TRUE(fs::is_empty(directory)) << command << " left files behind";
    fs::remove_all(directory);
    fs::create_directories(directory);
  }
  // A full file system where the machine lets a user mount one (a tmpfs in a user namespace).
  if (run_shell("unshare -rm true").exit_code != 0) {
    std::printf("note: no user namespaces here; the full tmpfs part is skipped (the file size limit above ran)\n");
    return;
  }
  for (const std::string& command : {commands[0], commands[3], commands[5]}) {
    const Result result = run_shell("unshare -rm sh -c \"mount -t tmpfs -o size=12k tmpfs " + directory + " && " +
                                    segmorph + " " + command + "; echo exit \\$?; ls -A " + directory + "\"");
    EXPECT_NE(result.out.find("exit 1\n"), std::string::npos) << command << "\n" << result.out << result.err;
    EXPECT_EQ(result.out.substr(result.out.find("exit 1\n") + 7), "") << command << " left files behind";
    EXPECT_NE(result.err.find("No space left on device"), std::string::npos) << result.err;
  }
}

// An output that is the input, a link to it or a file it reads is refused before any work (exit 2, the input
// unchanged) unless --force, which replaces it.
TEST(Cli, OutputThatIsTheInputIsRefusedWithoutForce) {
  const std::string directory = output_directory("same-file");
  fs::copy_file(sample("Fox/Fox.glb"), directory + "/fox.glb");
  fs::create_symlink(directory + "/fox.glb", directory + "/link.glb");
  const std::string original = read_text(directory + "/fox.glb");
  for (const char* command : {"encode", "bake", "decode"})
    for (const char* output : {"fox.glb", "link.glb"}) {
      const Result result = run(std::string(command) + " -q " + directory + "/fox.glb -o " + directory + "/" + output);
      EXPECT_EQ(result.exit_code, 2) << command << " " << output;
      EXPECT_NE(result.err.find("would replace the input"), std::string::npos) << result.err;
      EXPECT_NE(result.err.find("--force"), std::string::npos) << result.err;
    }
  EXPECT_EQ(read_text(directory + "/fox.glb"), original);
  // A .gltf output whose .bin is the input's buffer.
  simple_morph_in(directory);
  write_text(directory + "/morph.gltf", read_text(sample("SimpleMorph/SimpleMorph.gltf")));
  const std::string geometry = read_text(directory + "/simpleMorphGeometry.bin");
  EXPECT_EQ(run("bake -q " + directory + "/morph.gltf -o " + directory + "/simpleMorphGeometry.gltf").exit_code, 2);
  EXPECT_EQ(read_text(directory + "/simpleMorphGeometry.bin"), geometry);
  EXPECT_FALSE(fs::exists(directory + "/simpleMorphGeometry.gltf"));
  // With --force the input is replaced by the encode, atomically, and nothing else is left.
  ASSERT_EQ(run("encode -q --force " + directory + "/fox.glb -o " + directory + "/fox.glb").exit_code, 0);
  EXPECT_NE(read_text(directory + "/fox.glb"), original);
  EXPECT_NE(read_text(directory + "/fox.glb").find("SEGMORPH_animation_compression"), std::string::npos);
  size_t hidden = 0;
  for (const auto& entry : fs::directory_iterator(directory)) hidden += entry.path().filename().string()[0] == '.';
  EXPECT_EQ(hidden, 0u);
}

// How many processes have `argument` among their command-line arguments (zombies have none).
int processes_with_argument(const std::string& argument) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream file(entry.path() / "cmdline", std::ios::binary);
    for (std::string word; std::getline(file, word, '\0');)
      if (word == argument) {
        ++count;
        break;
      }
  }
  return count;
}

// Runs segmorph with `arguments` and sends it `signal_number` once a line of its stderr (its progress) contains
// `line` ("" at once, before it starts), then returns its wait status (-1 when it could not be started or waited for).
// No clock: the signal follows a stage's announcement, whatever the machine's speed.
int signal_on_line(const std::vector<std::string>& arguments, const std::string& line, int signal_number) {
  std::vector<const char*> argv = {SEGMORPH_BINARY};
  for (const std::string& argument : arguments) argv.push_back(argument.c_str());
  argv.push_back(nullptr);
  int pipe_ends[2];
  if (pipe(pipe_ends) != 0) return -1;
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    dup2(pipe_ends[1], 2);
    close(pipe_ends[0]);
    close(pipe_ends[1]);
    execv(argv[0], const_cast<char* const*>(argv.data()));
    _exit(127);
  }
  close(pipe_ends[1]);
  std::string seen;
  char buffer[256];
  ssize_t got = 0;
  while (!line.empty() && seen.find(line) == std::string::npos && (got = read(pipe_ends[0], buffer, sizeof buffer)) > 0)
    seen.append(buffer, size_t(got));
  kill(pid, signal_number);
  while (read(pipe_ends[0], buffer, sizeof buffer) > 0) {
  }
  close(pipe_ends[0]);
  int status = 0;
  return waitpid(pid, &status, 0) == pid ? status : -1;
}

// A named pipe with a glTF name: a process that opens it to read waits until a writer opens it (none does), so a
// signal surely finds it before its end.
std::string waiting_input(const std::string& directory) {
  const std::string path = directory + "/waiting.glb";
  EXPECT_EQ(mkfifo(path.c_str(), 0600), 0) << path;
  return path;
}

// SIGINT or SIGTERM at any point of a bake (reading, baking, writing, done) leaves no temporary file, and either no
// output or a whole one. The signal follows each stage's progress line (it may land in that stage or a later one, or
// after the end: each outcome is checked), and one run waits for an input that never comes, which the signal must
// interrupt (before: delays of 0 to 1500 ms, and a fast machine could finish before any).
TEST(Cli, SignalsLeaveNoPartialOutput) {
  const std::string directory = output_directory("signals");
  const std::string output = directory + "/out.glb";
  const std::string fox = sample("Fox/Fox.glb");
  for (int signal_number : {SIGTERM, SIGINT})
    for (const std::string stage : {"", "reading", "sampling", "writing", "baked"}) {
      SCOPED_TRACE("signal " + std::to_string(signal_number) + " after \"" + stage + "\"");
      const int status = signal_on_line({"bake", fox, "-o", output, "--fps", "120"}, stage, signal_number);
      ASSERT_GE(status, 0);
      std::vector<std::string> left;
      for (const auto& entry : fs::directory_iterator(directory)) left.push_back(entry.path().filename());
      if (WIFSIGNALED(status)) {
        EXPECT_EQ(WTERMSIG(status), signal_number);
        // Before the rename nothing is left; a signal after it (between the rename and the exit) finds the output
        // whole. Never a temporary file or a partial output.
        if (!left.empty()) {
          ASSERT_EQ(left, std::vector<std::string>{"out.glb"});
          EXPECT_EQ(run("info -q " + output).exit_code, 0) << "a whole file";
        }
      } else {
        ASSERT_TRUE(WIFEXITED(status));
        EXPECT_EQ(WEXITSTATUS(status), 0);
        ASSERT_EQ(left, std::vector<std::string>{"out.glb"});
        EXPECT_EQ(run("info -q " + output).exit_code, 0) << "a whole file";
      }
      fs::remove_all(directory);
      fs::create_directories(directory);
    }
  for (int signal_number : {SIGTERM, SIGINT}) {
    const int status = signal_on_line({"bake", waiting_input(directory), "-o", output}, "reading", signal_number);
    ASSERT_TRUE(WIFSIGNALED(status)) << "a bake waiting for its input was not interrupted";
    EXPECT_EQ(WTERMSIG(status), signal_number);
    fs::remove(directory + "/waiting.glb");
    EXPECT_TRUE(fs::is_empty(directory)) << "the interrupted bake left a file";
  }
}

TEST(Cli, BakeWritesGlbAndGltfAndNothingElse) {
  const std::string directory = output_directory("bake");
  Result result = run("bake " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.glb");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("sampling"), std::string::npos) << "progress goes to stderr";
  result = run("bake -q " + sample("SimpleMorph/SimpleMorph.gltf") + " -o " + directory + "/morph.gltf");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.err.empty());
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"fox.glb", "morph.bin", "morph.gltf"}));
  EXPECT_NE(read_text(directory + "/morph.gltf").find("\"uri\": \"morph.bin\""), std::string::npos);
}

// The base mesh's position precision follows the error target unless --position-bits sets it.
TEST(Cli, BaseMeshPrecisionFollowsTheErrorTarget) {
  const std::string directory = output_directory("position_bits");
  const std::string input = sample("Fox/Fox.glb");
  auto draco_bytes = [&](const std::string& options) {
    const Result result = run("encode -q " + input + " -o " + directory + "/fox.glb --json " + options);
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return json_number(result.out, "draco_bytes");
  };
  const double coarse = draco_bytes("--error 1"), fine = draco_bytes("--error 0.01");
  EXPECT_LT(coarse, fine);
  EXPECT_EQ(draco_bytes("--error 1 --position-bits 16"), draco_bytes("--error 0.01 --position-bits 16"));
  EXPECT_LT(draco_bytes("--error 1 --position-bits 12"), draco_bytes("--error 1 --position-bits 16"));
  // A sequence's base is at least 10 bits (--help), however coarse the target: the waving flag's cache, coded as
  // frames, at --error 5, where the rule alone would take fewer.
  const std::string flag = sample("WavingFlag/flag.obj") + " --cache " + sample("WavingFlag/flag.pc2");
  auto flag_draco_bytes = [&](const std::string& options) {
    const Result result = run("encode -q " + flag + " -o " + directory + "/flag.glb --json --error 5 " + options);
    EXPECT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find("\"mode\":\"frames\""), std::string::npos) << result.out;
    return json_number(result.out, "draco_bytes");
  };
  EXPECT_EQ(flag_draco_bytes(""), flag_draco_bytes("--position-bits 10"));
  EXPECT_NE(flag_draco_bytes(""), flag_draco_bytes("--position-bits 9"));
}

// The automatic cluster count comes within 2 % of the best of the counts it could pick from on the bundled Fox
// (the segmentation's 9, and 6 and 4 below it). Its estimate once chose 6, 7 % larger than 9.
// The Fox's skin baked, so that its frames go through the codec (a kept skin never does, and every --clusters would
// give the same bytes): the automatic K codes them about as small as the best of a few fixed ones.
TEST(Cli, AutomaticClusterCountIsNearTheBestFixedOne) {
  const std::string directory = output_directory("automatic_clusters");
  auto stream_bytes = [&](const std::string& options) {
    const Result result =
        run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.glb --skins bake --json " + options);
    EXPECT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(json_number(result.out, "streams"), 1) << "the codec did not run";
    return json_number(result.out, "animation_bytes");
  };
  double best = INFINITY;
  for (const char* k : {"4", "6", "9"}) best = std::min(best, stream_bytes(std::string("--clusters ") + k));
  EXPECT_LE(stream_bytes(""), 1.02 * best);
}

// K is merged down from the Morse segmentation, never split up: --clusters above what it gives is said, not hidden
// (the Fox's baked frames segment into 9 clusters).
TEST(Cli, ClustersAboveTheSegmentationsCountAreSaid) {
  const std::string directory = output_directory("too_many_clusters");
  Result result = run("encode " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.glb --skins bake --json --clusters 100");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_number(result.out, "clusters"), 9);
  EXPECT_NE(result.err.find("warning: --clusters 100 is more than the segmentation gives a primitive (9 clusters)"),
            std::string::npos)
      << result.err;
  result = run("encode " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.glb --skins bake --json --clusters 6");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_number(result.out, "clusters"), 6);
  EXPECT_EQ(result.err.find("warning"), std::string::npos) << result.err;
}

// The Fox stores each vertex once per triangle (1728 vertices, 434 distinct): the copies are coded once, and the
// decoded file has the 434, with the animation within its error bound.
TEST(Cli, CopiesOfAVertexAreCodedOnce) {
  const std::string directory = output_directory("vertex_copies");
  const std::string input = sample("Fox/Fox.glb"), encoded = directory + "/fox.glb", decoded = directory + "/plain.glb";
  Result result = run("encode -q " + input + " -o " + encoded + " --skins bake --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_LT(json_number(result.out, "draco_bytes"), 4000);  // 10950 with every copy
  ASSERT_EQ(run("decode -q " + encoded + " -o " + decoded).exit_code, 0);
  result = run("info -q " + decoded + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_number(result.out, "vertices"), 434);
  result = run("verify -q " + input + " " + decoded + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_LE(json_number(result.out, "kg_percent"), 0.15);
}

// --normal-bits and --texcoord-bits set the base mesh's other precisions (RiggedSimple has normals, Fox texture
// coordinates); a finer one costs more Draco bytes.
TEST(Cli, BaseMeshNormalAndTexcoordPrecisionsAreOptions) {
  const std::string directory = output_directory("attribute_bits");
  auto draco_bytes = [&](const std::string& file, const std::string& options) {
    const Result result = run("encode -q " + sample(file) + " -o " + directory + "/out.glb --json " + options);
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return json_number(result.out, "draco_bytes");
  };
  EXPECT_EQ(draco_bytes("RiggedSimple/RiggedSimple.glb", ""),
            draco_bytes("RiggedSimple/RiggedSimple.glb", "--normal-bits 8"));
  EXPECT_LT(draco_bytes("RiggedSimple/RiggedSimple.glb", ""),
            draco_bytes("RiggedSimple/RiggedSimple.glb", "--normal-bits 12"));
  EXPECT_EQ(draco_bytes("Fox/Fox.glb", ""), draco_bytes("Fox/Fox.glb", "--texcoord-bits 12"));
  EXPECT_GT(draco_bytes("Fox/Fox.glb", ""), draco_bytes("Fox/Fox.glb", "--texcoord-bits 6"));
  for (const char* bad : {"--normal-bits 3", "--normal-bits 17", "--texcoord-bits 31", "--texcoord-bits x"})
    EXPECT_EQ(run("encode " + sample("Fox/Fox.glb") + " -o " + directory + "/bad.glb " + bad).exit_code, 2) << bad;
}

// KHR_draco_mesh_compression gives a compressed primitive an indices accessor without a bufferView, as
// segmorph writes and other tools do; tinygltf 2.7 refuses it, so segmorph rewrites the JSON before parsing
// (json_prepass.h). Both .gltf and .glb.
TEST(Cli, DracoIndicesWithoutBufferViewAreRead) {
  const std::string directory = output_directory("draco_indices");
  const std::string input = sample("AnimatedMorphCube/AnimatedMorphCube.glb");
  for (const char* extension : {"gltf", "glb"}) {
    const std::string encoded = directory + "/cube." + extension;
    ASSERT_EQ(run("encode -q " + input + " -o " + encoded).exit_code, 0);
    const std::string text = read_text(encoded);
    const size_t primitive = text.find("\"KHR_draco_mesh_compression\"", text.find("\"meshes\""));
    ASSERT_NE(primitive, std::string::npos);
    EXPECT_NE(text.find("\"indices\"", primitive), std::string::npos) << extension;
    const Result result = run("verify -q " + input + " " + encoded + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(json_number(result.out, "vertices"), 24);
    EXPECT_LE(json_number(result.out, "kg_percent"), 0.15);
    ASSERT_EQ(run("decode -q " + encoded + " -o " + directory + "/decoded.glb").exit_code, 0);
  }
}

// Two clips of a compressed primitive naming one animation would make decode write an invalid file.
TEST(Cli, ClipsNamingOneAnimationTwiceAreRefused) {
  const std::string directory = output_directory("clips_twice");
  ASSERT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.gltf --error 1 --skins bake").exit_code, 0);
  std::string json = read_text(directory + "/fox.gltf");
  const size_t second = json.find("\"animation\": 1,", json.find("SEGMORPH_animation_compression\": {"));
  ASSERT_NE(second, std::string::npos);
  json.replace(second, 15, "\"animation\": 0,");
  write_text(directory + "/fox.gltf", json);
  expect_clean_failure(directory + "/fox.gltf", "two clips name the same animation", "decode");
}

TEST(Cli, EncodeDecodeAndVerify) {
  const std::string directory = output_directory("encode");
  const std::string input = sample("Fox/Fox.glb");
  Result result = run("encode -q " + input + " -o " + directory + "/fox.glb --error 0.5 --skins bake --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_GT(json_number(result.out, "clusters"), 0);
  EXPECT_GT(json_number(result.out, "e_pi"), 0);
  EXPECT_LT(json_number(result.out, "e_pi"), 0.01);
  EXPECT_GT(json_number(result.out, "bpvf"), 0);
  EXPECT_FALSE(std::isnan(json_number(result.out, "rate_control")));
  // Three times smaller than the input at least (the input's frames as skin; the output carries the texture too).
  EXPECT_LT(fs::file_size(directory + "/fox.glb") * 2, fs::file_size(input));

  result = run("verify -q " + input + " " + directory + "/fox.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const double kg = json_number(result.out, "kg_percent");
  EXPECT_LE(kg, 0.5);
  EXPECT_GT(kg, 0.1);
  EXPECT_EQ(json_number(result.out, "vertices"), 1728);
  EXPECT_GT(json_number(result.out, "bpvf_animation"), 0);

  result = run("decode -q " + directory + "/fox.glb -o " + directory + "/fox-decoded.glb");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run("verify -q " + input + " " + directory + "/fox-decoded.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_DOUBLE_EQ(json_number(result.out, "kg_percent"), kg);  // the decoded file plays the decoder's frames
  EXPECT_EQ(json_number(result.out, "bpvf_animation"), 0);      // standard glTF: no stream left

  // Decoding a file that is not encoded says so.
  result = run("decode -q " + input + " -o " + directory + "/not.glb");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.err.find("not encoded"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(directory + "/not.glb"));
}

// --fast-decode writes version-2 streams (the table residual code), the default version 1; decode and verify read
// them, within the error target, sampled frames (the Fox's skin baked: 1728 vertices, 434 welded) and kept morph
// targets alike.
TEST(Cli, FastDecodeEncodesDecodesAndVerifies) {
  const std::string directory = output_directory("fast_decode");
  const std::string version_1("SGMA\x01", 5), version_2("SGMA\x02", 5);
  const struct {
    const char* input;
    const char* options;
  } cases[] = {{"Fox/Fox.glb", "--skins bake --error 0.15"},
               {"AnimatedMorphCube/AnimatedMorphCube.glb", "--targets keep --error 0.15"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.input);
    const std::string input = sample(c.input), fast = directory + "/fast.glb", plain = directory + "/plain.glb",
                      decoded = directory + "/decoded.glb";
    // Capped at the versions of the table code and of the plain stream (version 3 adds tools of its own).
    Result result = run("encode -q " + input + " -o " + fast + " --fast-decode --max-stream-version 2 " + c.options);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    ASSERT_EQ(run("encode -q " + input + " -o " + plain + " --max-stream-version 1 " + c.options).exit_code, 0);
    const std::string fast_bytes = read_text(fast), plain_bytes = read_text(plain);
    EXPECT_NE(fast_bytes, plain_bytes);
    EXPECT_NE(fast_bytes.find(version_2), std::string::npos);
    EXPECT_EQ(fast_bytes.find(version_1), std::string::npos);
    EXPECT_NE(plain_bytes.find(version_1), std::string::npos);
    EXPECT_EQ(plain_bytes.find(version_2), std::string::npos);

    result = run("verify -q " + input + " " + fast + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const double kg = json_number(result.out, "kg_percent");
    EXPECT_LE(kg, 0.15);
    EXPECT_GT(kg, 0);
    result = run("decode -q " + fast + " -o " + decoded);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    result = run("verify -q " + input + " " + decoded + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_DOUBLE_EQ(json_number(result.out, "kg_percent"), kg);  // the decoded file plays the decoder's frames
  }
}

// --fast-decode is documented, and refused with --lossless (the table code is for lossy residuals) and with
// --max-stream-version 1 (it is version 2's): a usage error in one line, nothing written.
TEST(Cli, FastDecodeIsDocumentedAndNotLossless) {
  const Result help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--fast-decode"), std::string::npos);
  EXPECT_NE(help.out.find("--max-stream-version"), std::string::npos);
  const std::string directory = output_directory("fast_decode_lossless");
  for (const char* order :
       {"--fast-decode --lossless", "--lossless --fast-decode", "--fast-decode --max-stream-version 1"}) {
    const Result result =
        run("encode -q " + sample("AnimatedMorphCube/AnimatedMorphCube.glb") + " -o " + directory + "/x.glb " + order);
    EXPECT_EQ(result.exit_code, 2) << order;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_NE(result.err.find("--fast-decode"), std::string::npos) << result.err;
    EXPECT_TRUE(fs::is_empty(directory)) << order;
  }
}

// --gpu-playable: the baked flag, whose default stream is version 3 (version 4 is larger there), gets version 4 at
// no more than the error target; encode's and info's --json say it plays on the GPU, and decode and verify read it.
TEST(Cli, GpuPlayableWritesVersionFourWhereTheDefaultDoesNot) {
  const std::string directory = output_directory("gpu_playable");
  const std::string input = sample("WavingFlag/flag.glb"), plain = directory + "/plain.glb",
                    playable = directory + "/playable.glb";
  const std::string version_3("SGMA\x03", 5), version_4("SGMA\x04", 5);
  Result result = run("encode -q " + input + " -o " + plain + " --targets bake --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("\"stream_version\":3,\"gpu_playable\":false"), std::string::npos) << result.out;
  result = run("encode -q " + input + " -o " + playable + " --targets bake --gpu-playable --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("\"stream_version\":4,\"gpu_playable\":true"), std::string::npos) << result.out;
  EXPECT_LE(json_number(result.out, "kg_percent"), 0.15);
  EXPECT_NE(read_text(plain).find(version_3), std::string::npos);
  EXPECT_NE(read_text(playable).find(version_4), std::string::npos);
  for (const auto& [file, playable_on_gpu] : {std::pair{plain, false}, std::pair{playable, true}}) {
    result = run("info -q " + file + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find(playable_on_gpu ? "\"gpu_playable\":true" : "\"gpu_playable\":false"),
              std::string::npos) << result.out;
    result = run("info -q " + file);
    EXPECT_NE(result.out.find(playable_on_gpu ? "plays on the GPU from its model" : "plays as decoded frames"),
              std::string::npos) << result.out;
  }
  result = run("verify -q " + input + " " + playable + " --max-error 0.15");
  EXPECT_EQ(result.exit_code, 0) << result.out << result.err;
}

// --gpu-playable is documented, and refused with what cannot write version 4: a usage error in one line, nothing
// written.
TEST(Cli, GpuPlayableIsDocumentedAndRefusesWhatCannotWriteVersionFour) {
  const Result help = run("--help");
  EXPECT_NE(help.out.find("--gpu-playable"), std::string::npos);
  const std::string directory = output_directory("gpu_playable_refused");
  for (const char* options : {"--gpu-playable --lossless", "--bpvf 4 --gpu-playable", "--gpu-playable --fast-decode",
                              "--gpu-playable --max-stream-version 3"}) {
    const Result result = run("encode -q " + sample("WavingFlag/flag.glb") + " -o " + directory + "/x.glb " + options);
    EXPECT_EQ(result.exit_code, 2) << options;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_NE(result.err.find("--gpu-playable"), std::string::npos) << result.err;
    EXPECT_TRUE(fs::is_empty(directory)) << options;
  }
}

// --targets keep: the morph targets stay, filled in from the stream by decode; the weights animation stays.
TEST(Cli, KeptMorphTargetsEncodeDecodeAndVerify) {
  const std::string directory = output_directory("kept_targets");
  const std::string input = sample("AnimatedMorphCube/AnimatedMorphCube.glb");
  for (const char* target : {"0.5", "0.15"}) {
    SCOPED_TRACE(target);
    const std::string encoded = directory + "/cube.gltf", decoded = directory + "/decoded.gltf";
    Result result = run("encode -q " + input + " -o " + encoded + " --targets keep --error " + target);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string text = read_text(encoded);
    EXPECT_NE(text.find("\"morphTargets\": true"), std::string::npos);
    EXPECT_EQ(text.find("\"clips\""), std::string::npos);
    EXPECT_NE(text.find("\"path\": \"weights\""), std::string::npos);  // the original weights animation
    EXPECT_NE(text.find("\"targets\""), std::string::npos);

    result = run("verify -q " + input + " " + encoded + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const double kg = json_number(result.out, "kg_percent");
    EXPECT_LE(kg, std::stod(target));
    EXPECT_GT(kg, 0);

    ASSERT_EQ(run("decode -q " + encoded + " -o " + decoded).exit_code, 0);
    const std::string restored = read_text(decoded);
    EXPECT_EQ(restored.find("SEGMORPH_animation_compression"), std::string::npos);
    EXPECT_EQ(restored.find("KHR_draco_mesh_compression"), std::string::npos);
    result = run("verify -q " + input + " " + decoded + " --json");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_DOUBLE_EQ(json_number(result.out, "kg_percent"), kg);
    EXPECT_EQ(json_number(result.out, "frames"), 127);  // the original animation, at its own key times
  }
  // The choice is the smaller file: on this cube the baked form wins (its two weight tracks cost more than
  // the frames they spare), on SimpleMorph too; --targets bake never keeps them.
  for (const char* mode : {"auto", "bake"}) {
    const Result result = run("encode -q " + input + " -o " + directory + "/cube.glb --targets " + std::string(mode));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(read_text(directory + "/cube.glb").find("morphTargets"), std::string::npos) << mode;
  }
  // With --bpvf 8 the kept variant is refused (its weights track leaves too little of the budget): auto goes on
  // with the baked one rather than failing.
  const Result rate = run("encode -q " + input + " -o " + directory + "/rate.glb --bpvf 8");
  ASSERT_EQ(rate.exit_code, 0) << rate.err;
  EXPECT_EQ(read_text(directory + "/rate.glb").find("morphTargets"), std::string::npos);
  EXPECT_EQ(run("encode -q " + input + " -o " + directory + "/rate.glb --bpvf 8 --targets keep").exit_code, 1);
  // Lossless encodes bake (kept targets are lossy). The stream restores the sampled frames bit for bit; verify
  // plays them in the morph-target form, base + delta in float, which is within an ulp of each frame (spec/README.md).
  Result lossless = run("encode -q " + input + " -o " + directory + "/lossless.glb --lossless");
  ASSERT_EQ(lossless.exit_code, 0) << lossless.err;
  EXPECT_EQ(read_text(directory + "/lossless.glb").find("morphTargets"), std::string::npos);
  lossless = run("verify -q " + input + " " + directory + "/lossless.glb --json");
  ASSERT_EQ(lossless.exit_code, 0) << lossless.err;
  EXPECT_LT(json_number(lossless.out, "kg_percent"), 1e-5);
  EXPECT_EQ(run("encode -q " + input + " -o " + directory + "/x.glb --targets keep --lossless").exit_code, 2);
  EXPECT_EQ(run("encode -q " + input + " -o " + directory + "/x.glb --targets some").exit_code, 2);
}

// decode --frames writes what the streams decode to, as raw floats: for a primitive that plays clips, its frames, whose
// first is the decoded file's base and each other the base plus its target (within an ulp of the larger of the two,
// spec/README.md); for kept
// targets, their displacements, which are the decoded file's target accessors exactly.
TEST(Cli, DecodeFramesWritesWhatTheStreamsDecodeTo) {
  const std::string directory = output_directory("decode_frames");
  const std::string input = sample("AnimatedMorphCube/AnimatedMorphCube.glb");
  for (const char* targets : {"bake", "keep"}) {
    SCOPED_TRACE(targets);
    const std::string encoded = directory + "/cube.glb", decoded = directory + "/decoded.glb";
    const std::string frames = directory + "/frames.bin", only = directory + "/only.bin";
    ASSERT_EQ(run("encode -q " + input + " -o " + encoded + " --targets " + targets).exit_code, 0);
    Result result = run("decode -q " + encoded + " -o " + decoded + " --frames " + frames);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    result = run("decode -q " + encoded + " --frames " + only);  // without -o: the frames alone
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string bytes = read_text(frames);
    EXPECT_EQ(bytes, read_text(only));
    std::vector<float> values(bytes.size() / 4);
    std::memcpy(values.data(), bytes.data(), values.size() * 4);

    tinygltf::Model model;
    ASSERT_TRUE(segmorph::load_gltf(decoded, model).ok());
    ASSERT_EQ(model.meshes.size(), 1u);
    const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
    std::vector<float> base;
    ASSERT_TRUE(segmorph::read_floats(model, primitive.attributes.at("POSITION"), "base", base).ok());
    const bool kept = std::string(targets) == "keep";
    // The cube's 2 kept targets, or its 127 frames (the base, then one target each).
    const size_t frame_count = kept ? 2 : 127;
    ASSERT_EQ(primitive.targets.size(), kept ? 2u : 126u);
    ASSERT_EQ(values.size(), frame_count * base.size());
    if (!kept) {
      EXPECT_EQ(std::memcmp(values.data(), base.data(), base.size() * 4), 0) << "frame 0 is the base";
    }
    for (size_t t = 0; t < primitive.targets.size(); ++t) {
      std::vector<float> delta;
      ASSERT_TRUE(segmorph::read_floats(model, primitive.targets[t].at("POSITION"), "target", delta).ok());
      const float* frame = &values[(kept ? t : t + 1) * base.size()];
      for (size_t i = 0; i < base.size(); ++i) {
        if (kept) {
          ASSERT_EQ(std::memcmp(&frame[i], &delta[i], 4), 0) << "target " << t << " float " << i;
        } else {
          const float played = base[i] + delta[i], larger = std::max(std::fabs(base[i]), std::fabs(frame[i]));
          ASSERT_LE(std::fabs(played - frame[i]), std::nextafter(larger, INFINITY) - larger)
              << "frame " << t + 1 << " float " << i;
        }
      }
    }
  }
  EXPECT_EQ(run("encode -q " + input + " -o " + directory + "/x.glb --frames " + directory + "/x.bin").exit_code, 2);
  EXPECT_EQ(run("decode -q " + input + " --frames " + directory + "/x.bin").exit_code, 1);  // not encoded
  EXPECT_FALSE(fs::exists(directory + "/x.bin"));
}

// A kept-targets file whose stream does not match its targets is refused, with nothing written.
TEST(Cli, KeptMorphTargetsThatDisagreeAreRefused) {
  const std::string directory = output_directory("kept_targets_bad");
  const std::string encoded = directory + "/cube.gltf";
  ASSERT_EQ(run("encode -q " + sample("AnimatedMorphCube/AnimatedMorphCube.glb") + " -o " + encoded +
                " --targets keep")
                .exit_code,
            0);
  const std::string text = read_text(encoded);
  std::string one_target = text;
  const size_t targets = one_target.find("\"targets\": [");
  ASSERT_NE(targets, std::string::npos);
  const size_t second = one_target.find("},", targets);
  const size_t end = one_target.find("]", second);
  one_target.replace(second + 1, end - second - 1, "");  // the first target only
  write_text(encoded, one_target);
  expect_clean_failure(encoded, "disagree with the morph target count", "decode");

  std::string both = text;
  both.replace(both.find("\"morphTargets\": true"), 20, "\"morphTargets\": true, \"clips\": [{\"animation\": 0}]");
  write_text(encoded, both);
  expect_clean_failure(encoded, "exclude each other", "decode");
}

// --bpvf is the rate of the whole file: the Fox's texture, JSON and frame times (1.25 bpvf) come off the codec's
// budget. A target below them alone is refused; one far above what the frames need gives the finest stream (it
// made the steps shrink until quantized motion left int32, and encode failed its own decoding check).
TEST(Cli, BpvfTargetIsTheWholeFile) {
  const std::string directory = output_directory("bpvf");
  const std::string input = sample("Fox/Fox.glb"), output = directory + "/fox.glb";
  Result result = run("encode -q " + input + " -o " + output + " --bpvf 3");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run("verify -q " + input + " " + output + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NEAR(json_number(result.out, "bpvf"), 3.0, 0.15);

  fs::remove(output);
  result = run("encode -q " + input + " -o " + output + " --bpvf 1");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.err.find("below what the rest of the file takes"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(output));

  // Above the rest but below what the base mesh and the motion need: encoded, with a warning.
  result = run("encode " + input + " -o " + output + " --bpvf 1.3");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("warning: --bpvf 1.3 is out of reach"), std::string::npos) << result.err;

  result = run("encode -q " + input + " -o " + output + " --bpvf 200");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run("verify -q " + input + " " + output + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_LT(json_number(result.out, "kg_percent"), 0.001);
  EXPECT_LT(json_number(result.out, "bpvf"), 200);
}

TEST(Cli, CorruptedEncodedFilesFailCleanlyOrDecode) {
  const std::string directory = output_directory("corrupt_encoded");
  ASSERT_EQ(run("encode -q " + sample("RiggedSimple/RiggedSimple.glb") + " -o " + directory + "/encoded.glb").exit_code,
            0);
  const std::string original = read_text(directory + "/encoded.glb");
  std::mt19937 random(99);
  for (int trial = 0; trial < 60; ++trial) {
    std::string bytes = original;
    // Damage the binary chunk (past the JSON), where the Draco and animation streams are.
    const size_t from = bytes.size() / 3;
    for (int c = 0; c < 1 + int(random() % 6); ++c)
      bytes[from + random() % (bytes.size() - from)] = char(random() % 256);
    if (trial % 6 == 0) bytes.resize(from + random() % (bytes.size() - from));
    write_text(directory + "/input.glb", bytes);
    fs::remove(directory + "/out.glb");
    const Result result = run("decode -q " + directory + "/input.glb -o " + directory + "/out.glb");
    SCOPED_TRACE("trial " + std::to_string(trial));
    ASSERT_TRUE(result.exit_code == 0 || result.exit_code == 1) << result.exit_code << " " << result.err;
    if (result.exit_code == 1) {
      EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
      EXPECT_FALSE(fs::exists(directory + "/out.glb"));
    }
  }
}

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

}  // namespace

// A skinned mesh keeps its skin by default: Draco holds the mesh with its joints and weights, the joints' tracks are
// coded (the extension is then required), and the file is smaller than the baked one at the same error target.
// decode restores a plain skinned file that plays exactly what verify measured on the encoded one.
TEST(Cli, SkinsAreKeptAndTracksCoded) {
  const std::string directory = output_directory("kept_skin");
  const std::string input = sample("Fox/Fox.glb"), kept = directory + "/kept.gltf", baked = directory + "/baked.glb",
                    decoded = directory + "/decoded.gltf";
  Result result = run("encode -q " + input + " -o " + kept + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_number(result.out, "streams"), 0);  // no frame stream
  const std::string json = read_text(kept);
  EXPECT_NE(json.find("\"JOINTS_0\""), std::string::npos);
  EXPECT_NE(json.find("\"skins\""), std::string::npos);
  const size_t required = json.find("\"extensionsRequired\"");
  ASSERT_NE(required, std::string::npos);
  EXPECT_NE(json.find("SEGMORPH_animation_compression", required), std::string::npos);
  EXPECT_NE(json.find("\"samplers\": ["), std::string::npos);  // an animation's coded samplers
  ASSERT_EQ(run("encode -q " + input + " -o " + baked + " --skins bake").exit_code, 0);
  ASSERT_EQ(run("encode -q " + input + " -o " + directory + "/kept.glb").exit_code, 0);
  EXPECT_LT(fs::file_size(directory + "/kept.glb"), fs::file_size(baked));

  result = run("verify -q " + input + " " + kept + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const double kg = json_number(result.out, "kg_percent");
  EXPECT_LE(kg, 0.15);
  EXPECT_GT(kg, 0.05);  // the search spends the error budget
  EXPECT_EQ(json_number(result.out, "vertices"), 1728);

  result = run("decode -q " + kept + " -o " + decoded);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::string plain = read_text(decoded);
  EXPECT_EQ(plain.find("SEGMORPH_animation_compression"), std::string::npos);
  EXPECT_EQ(plain.find("KHR_draco_mesh_compression"), std::string::npos);
  EXPECT_NE(plain.find("\"skins\""), std::string::npos);
  result = run("verify -q " + input + " " + decoded + " --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_DOUBLE_EQ(json_number(result.out, "kg_percent"), kg);
}

// Tracks that hold their node's rest value are dropped, others coded; --skins bake and --lossless bake as before.
TEST(Cli, SkinsOption) {
  const std::string directory = output_directory("skins_option");
  EXPECT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/x.glb --skins maybe").exit_code, 2);
  EXPECT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/x.glb --skins").exit_code, 2);
  Result result = run("encode -q " + sample("RiggedSimple/RiggedSimple.glb") + " -o " + directory +
                      "/baked.glb --skins bake --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_number(result.out, "streams"), 1);
  result = run("encode -q " + sample("RiggedSimple/RiggedSimple.glb") + " -o " + directory + "/lossless.glb --lossless --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(json_number(result.out, "streams"), 1);
}

// A kept skin's weights are bytes, which sets a floor under its error: below it, encode bakes the skin instead of
// writing a file above the target (SimpleSkin kept stays at KG 0.07 %).
TEST(Cli, KeptSkinsBelowTheirFloorAreBaked) {
  const std::string directory = output_directory("skin_floor");
  const std::string input = sample("SimpleSkin/SimpleSkin.gltf");
  Result result = run("encode " + input + " -o " + directory + "/fine.glb --error 0.05");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("baking them instead"), std::string::npos) << result.err;
  result = run("verify -q " + input + " " + directory + "/fine.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_LE(json_number(result.out, "kg_percent"), 0.05);
  // Within reach, the skin stays kept.
  result = run("encode " + input + " -o " + directory + "/coarse.glb --error 0.15");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.err.find("baking them instead"), std::string::npos) << result.err;
  result = run("verify -q " + input + " " + directory + "/coarse.glb --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_LE(json_number(result.out, "kg_percent"), 0.15);
}

// A coded animation that disagrees with its stream, or whose stream is damaged, is refused in one line.
TEST(Cli, DamagedTrackStreamsAreRefused) {
  const std::string directory = output_directory("damaged_tracks");
  const std::string encoded = directory + "/fox.gltf";
  ASSERT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + encoded).exit_code, 0);
  const std::string json = read_text(encoded);
  const size_t list = json.find("\"samplers\": [");
  ASSERT_NE(list, std::string::npos);

  std::string bad = json;
  bad.replace(list, 13, "\"samplers\": [99, ");
  write_text(encoded, bad);
  expect_clean_failure(encoded, "a coded sampler does not exist", "decode");

  // The stream's view, its bytes flipped in the .bin: the view named just before the list.
  const size_t view_key = json.rfind("\"bufferView\": ", list);
  ASSERT_NE(view_key, std::string::npos);
  const int view = std::stoi(json.substr(view_key + 14));
  tinygltf::Model model;
  write_text(encoded, json);
  ASSERT_TRUE(segmorph::load_gltf(encoded, model).ok());
  const tinygltf::BufferView& stream = model.bufferViews[size_t(view)];
  std::string bin = read_text(directory + "/fox.bin");
  for (size_t i = 4; i < stream.byteLength; i += 3) bin[stream.byteOffset + i] = char(bin[stream.byteOffset + i] ^ 0x5a);
  write_text(directory + "/fox.bin", bin);
  expect_clean_failure(encoded, "animation", "decode");
}

namespace {

// The value of `key` in the object of encode --json's "primitives" array at `index` (NaN when absent).
std::string json_primitive(const std::string& json, size_t index) {
  size_t at = json.find("\"primitives\":[");
  for (size_t i = 0; at != std::string::npos && i <= index; ++i) at = json.find("{\"node\":", at + 1);
  if (at == std::string::npos) return "";
  return json.substr(at, json.find('}', at) - at + 1);
}

}  // namespace

// encode --json reports each primitive: how it was stored, its bytes and the error measured on the decoded result,
// the same figures verify gives; the whole file's KG is the worst primitive's. Before: "primitives":0 for a kept
// skin, no KG, "coded as frames" whatever the mode.
TEST(Cli, EncodeReportsEveryPrimitiveAsVerifyMeasuresIt) {
  const std::string directory = output_directory("encode_report");
  const struct {
    std::string input, options, mode;
    int streams;
  } cases[] = {{"Fox/Fox.glb", "", "kept_skin", 0},
               {"SimpleMorph/SimpleMorph.gltf", "--targets keep", "kept_targets", 1},
               {"RiggedSimple/RiggedSimple.glb", "--skins bake", "frames", 1}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.input + " " + c.options);
    const std::string output = directory + "/out.glb";
    const Result encoded = run("encode -q " + sample(c.input) + " -o " + output + " --json " + c.options);
    ASSERT_EQ(encoded.exit_code, 0) << encoded.err;
    const std::string primitive = json_primitive(encoded.out, 0);
    EXPECT_NE(primitive.find("\"mode\":\"" + c.mode + "\""), std::string::npos) << encoded.out;
    EXPECT_TRUE(json_primitive(encoded.out, 1).empty()) << "one animated primitive";
    EXPECT_EQ(json_number(encoded.out, "streams"), c.streams);
    EXPECT_EQ(json_number(encoded.out, "bytes"), double(fs::file_size(output)));
    EXPECT_GT(json_number(primitive, "bytes"), 0);
    EXPECT_GT(json_number(primitive, "vertices"), 0);
    EXPECT_GT(json_number(primitive, "frames"), 0);
    const double kg = json_number(encoded.out, "kg_percent");
    EXPECT_GT(kg, 0);
    EXPECT_LE(kg, 0.15);
    EXPECT_EQ(json_number(primitive, "kg_percent"), kg);
    const Result verified = run("verify -q " + sample(c.input) + " " + output + " --json");
    ASSERT_EQ(verified.exit_code, 0) << verified.err;
    EXPECT_NEAR(json_number(verified.out, "kg_percent"), kg, 1e-5 * kg);
    const Result text = run("encode -q " + sample(c.input) + " -o " + output + " " + c.options);
    EXPECT_NE(text.out.find(": " + c.mode + ", "), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("measured on the decoded file"), std::string::npos) << text.out;
  }
}

// With --json, an error is also one JSON object on stdout with a stable code; without it, stdout stays empty.
TEST(Cli, JsonErrorsAreOneObjectOnStdout) {
  const std::string directory = output_directory("json_errors");
  Result result = run("encode " + directory + "/missing.glb -o " + directory + "/x.glb --json");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.out, "{\"error\":{\"code\":\"io_error\",\"file\":\"" + directory +
                            "/missing.glb\",\"message\":\"cannot open: No such file or directory\"}}\n");
  EXPECT_NE(result.err.find("segmorph: error: " + directory + "/missing.glb: cannot open"), std::string::npos);
  result = run("encode " + directory + "/missing.glb -o " + directory + "/x.glb");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.out, "");
  result = run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/x.glb --error 1000 --json");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.out.rfind("{\"error\":{\"code\":\"usage\",\"file\":null,\"message\":\"--error takes", 0), 0u)
      << result.out;
  write_text(directory + "/bad.glb", "glTF\x02");
  result = run("verify -q " + sample("Fox/Fox.glb") + " " + directory + "/bad.glb --json");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.out.rfind("{\"error\":{\"code\":\"bad_data\",\"file\":\"" + directory + "/bad.glb\"", 0), 0u)
      << result.out;
  result = run("info -q " + sample("SimpleSkin/SimpleSkin.gltf") + " " + sample("Fox/Fox.glb") + " --json");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.out.rfind("{\"error\":{\"code\":\"usage\"", 0), 0u) << result.out;
}

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

// A file compressed with meshopt is refused naming the extension and how to undo it (before: tinygltf's
// "Invalid 'byteLength'" for EXT_meshopt_compression).
TEST(Cli, MeshoptFilesAreRefusedByName) {
  const std::string directory = output_directory("meshopt");
  const std::string json = simple_morph_in(directory);
  for (const std::string name : {"EXT_meshopt_compression", "KHR_meshopt_compression"}) {
    SCOPED_TRACE(name);
    std::string edited = json;
    edited.insert(edited.find('{') + 1, "\"extensionsUsed\":[\"" + name + "\"],");
    write_text(directory + "/in.gltf", edited);
    const Result result = run("verify -q " + sample("SimpleMorph/SimpleMorph.gltf") + " " + directory + "/in.gltf");
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_EQ(result.err, "segmorph: error: " + directory + "/in.gltf: uses " + name +
                              ", which segmorph does not read: undo it first, for example with glTF-Transform's "
                              "'gltf-transform copy IN OUT.glb'\n");
  }
}

// Every file segmorph writes names it as asset.generator, with its version; the input's generator is kept in
// asset.extras.segmorph.input_generator (before: the input's generator stayed, so nothing told which tool wrote it).
TEST(Cli, OutputsNameSegmorphAsTheirGenerator) {
  const std::string directory = output_directory("generator");
  const std::string version = run("--version").out;
  const std::string ours = version.substr(0, version.find(' ', version.find(' ') + 1));  // "segmorph X.Y.Z"
  ASSERT_EQ(ours.rfind("segmorph 0.", 0), 0u) << version;
  std::string json = simple_morph_in(directory);
  const size_t asset = json.find("\"asset\"");
  ASSERT_NE(asset, std::string::npos);
  json.insert(json.find('{', asset) + 1, "\"generator\":\"An exporter 1.0\",");
  write_text(directory + "/in.gltf", json);
  ASSERT_EQ(run("encode -q " + directory + "/in.gltf -o " + directory + "/encoded.gltf").exit_code, 0);
  ASSERT_EQ(run("decode -q " + directory + "/encoded.gltf -o " + directory + "/decoded.gltf").exit_code, 0);
  ASSERT_EQ(run("bake -q " + directory + "/in.gltf -o " + directory + "/baked.gltf").exit_code, 0);
  for (const std::string name : {"encoded", "decoded", "baked"}) {
    SCOPED_TRACE(name);
    const std::string written = read_text(directory + "/" + name + ".gltf");
    EXPECT_NE(written.find("\"generator\": \"" + ours + "\""), std::string::npos) << written.substr(0, 400);
    EXPECT_NE(written.find("\"input_generator\": \"An exporter 1.0\""), std::string::npos) << written.substr(0, 400);
  }
}

namespace {

// The lines of `text`.
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

// Encodes every file of `inputs` as one batch (2 jobs) and one by one, and expects the same bytes.
void expect_batch_bytes_of_single_runs(const std::vector<std::string>& inputs, const std::string& folder,
                                       const std::string& directory) {
  const Result batch = run("encode -q " + folder + " --output-dir " + directory + "/batch --jobs 2 --json");
  const std::vector<std::string> lines = lines_of(batch.out);
  ASSERT_EQ(lines.size(), inputs.size() + 1) << batch.out << batch.err;
  size_t failed = 0;
  for (size_t i = 0; i < inputs.size(); ++i) {
    SCOPED_TRACE(inputs[i]);
    EXPECT_NE(lines[i].find(inputs[i]), std::string::npos) << "input order: " << lines[i];
    const std::string name = fs::path(inputs[i]).stem().string() + ".glb";
    const Result single = run("encode -q " + inputs[i] + " -o " + directory + "/" + name);
    if (single.exit_code != 0) {  // a file with nothing to encode fails the same way in the batch
      ++failed;
      EXPECT_EQ(lines[i].rfind("{\"error\":", 0), 0u) << lines[i];
      EXPECT_FALSE(fs::exists(directory + "/batch/" + name));
      continue;
    }
    EXPECT_EQ(read_text(directory + "/batch/" + name), read_text(directory + "/" + name)) << "not the same bytes";
  }
  EXPECT_EQ(lines.back(), "{\"files\":" + std::to_string(inputs.size()) + ",\"failed\":" + std::to_string(failed) + "}");
  EXPECT_EQ(batch.exit_code, failed ? 1 : 0);
}

}  // namespace

// A batch writes, for each input (files, and the glTF files under folders), the bytes a single run writes, reports
// each file in input order and ends with a count; a file that fails stops no other (exit status 1); two inputs that
// would write the same output are refused before any work.
TEST(Cli, BatchesWriteTheBytesOfSingleRuns) {
  const std::string directory = output_directory("batch");
  expect_batch_bytes_of_single_runs(segmorph::testing::bundled_samples(), SEGMORPH_SAMPLES_DIR, directory);

  write_text(directory + "/broken.glb", "not glTF");
  Result result = run("encode -q " + sample("Fox/Fox.glb") + " " + directory + "/broken.glb " +
                      sample("RiggedSimple/RiggedSimple.glb") + " --output-dir " + directory + "/mixed -j 2");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_TRUE(fs::exists(directory + "/mixed/Fox.glb"));
  EXPECT_TRUE(fs::exists(directory + "/mixed/RiggedSimple.glb"));
  EXPECT_FALSE(fs::exists(directory + "/mixed/broken.glb"));
  EXPECT_EQ(lines_of(result.out).back(), "3 files, 1 failed");
  EXPECT_NE(result.err.find("segmorph: error: " + directory + "/broken.glb: not a glTF file"), std::string::npos)
      << result.err;

  fs::create_directories(directory + "/other");
  fs::copy_file(sample("Fox/Fox.glb"), directory + "/other/Fox.glb");
  result = run("encode -q " + sample("Fox/Fox.glb") + " " + directory + "/other --output-dir " + directory + "/clash");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("would both write " + directory + "/clash/Fox.glb"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(directory + "/clash"));
  EXPECT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " -o " + directory + "/x.glb --jobs 2").exit_code, 2);
  EXPECT_EQ(run("encode -q - --output-dir " + directory + "/stdin").exit_code, 2);
  EXPECT_EQ(run("encode -q " + sample("Fox/Fox.glb") + " " + sample("Fox/Fox.glb") + " -o " + directory + "/x.glb")
                .exit_code,
            2);
}

TEST(Cli, BatchOfTheSharedSamplesWritesTheBytesOfSingleRuns) {
  if (!segmorph::testing::have_shared_samples()) GTEST_SKIP() << "../shared/samples is absent";
  const std::string folder = std::string(SEGMORPH_SHARED_SAMPLES_DIR) + "/gltf";
  expect_batch_bytes_of_single_runs(segmorph::testing::gltf_files_under(folder), folder,
                                    output_directory("batch_shared"));
}

// - is the standard input and (a .glb) the standard output; the report then goes to stderr. The bytes are those of
// files.
TEST(Cli, StandardInputAndOutput) {
  const std::string directory = output_directory("standard_streams");
  const std::string segmorph = SEGMORPH_BINARY, fox = sample("Fox/Fox.glb");
  ASSERT_EQ(run("encode -q " + fox + " -o " + directory + "/file.glb").exit_code, 0);
  Result result = run_shell("cat " + fox + " | " + segmorph + " encode -q - -o - > " + directory + "/piped.glb");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(read_text(directory + "/piped.glb"), read_text(directory + "/file.glb"));
  EXPECT_NE(result.err.find("-: "), std::string::npos) << "the report, on stderr: " << result.err;
  result = run_shell(segmorph + " decode -q " + directory + "/file.glb -o - | " + segmorph + " verify -q " + fox +
                     " - --max-error 0.15");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("KG 0.1"), std::string::npos) << result.out;
  result = run_shell("echo nonsense | " + segmorph + " info -q -");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.err, "segmorph: error: -: not a glTF file (neither GLB nor JSON)\n");
  EXPECT_EQ(run("verify -q - -").exit_code, 2);
}

// SIGTERM to a batch reaches the files being written: when the batch has ended, none is left half written or as a
// temporary file, and no process of the batch outlives it. (Ctrl-C reaches the whole process group anyway.) The
// batch waits for its children (a test that gave them 300 ms once failed in CI, where a child's temporary file was
// still there: a child in a long fsync under load). The batch's processes are found by the output folder in their
// command lines. The signal follows a progress line of the batch; with a third input that never comes, the batch
// cannot end before it (before: delays of 50 to 700 ms, which a fast machine could outrun).
TEST(Cli, SignalsStopABatchCleanly) {
  const std::string directory = output_directory("batch_signals");
  const std::string fox = sample("Fox/Fox.glb"), rigged = sample("RiggedSimple/RiggedSimple.glb");
  const std::string outputs = directory + "/out";
  for (const std::string stage : {"", "reading", "sampling", "writing"})
    for (bool waiting : {false, true}) {
      SCOPED_TRACE("SIGTERM after \"" + stage + "\"" + (waiting ? ", an input waiting" : ""));
      std::vector<std::string> arguments = {"bake", fox, rigged, "--output-dir", outputs, "--fps", "480", "--jobs", "2"};
      if (waiting) arguments.insert(arguments.begin() + 3, waiting_input(directory));
      const int status = signal_on_line(arguments, stage, SIGTERM);
      ASSERT_GE(status, 0);
      if (waiting) {
        EXPECT_TRUE(WIFSIGNALED(status)) << "a batch waiting for an input was not interrupted";
      }
      EXPECT_EQ(processes_with_argument(outputs), 0) << "a process of the batch outlived it";
      if (fs::exists(outputs))
        for (const auto& entry : fs::directory_iterator(outputs)) {
          const std::string name = entry.path().filename();
          EXPECT_TRUE(name == "Fox.glb" || name == "RiggedSimple.glb") << name << " left";
          EXPECT_EQ(run("info -q " + entry.path().string()).exit_code, 0) << name << " is not whole";
        }
      fs::remove_all(outputs);
      fs::remove(directory + "/waiting.glb");
    }
}

// The kept skins' error search says what it measures as it goes (before: silent for over a minute on a large
// file), on a subsample of frames, then its choice on every frame.
TEST(Cli, KeptSkinSearchReportsEachMeasurement) {
  const std::string directory = output_directory("kept_skin_progress");
  const Result result = run("encode " + sample("Fox/Fox.glb") + " -o " + directory + "/fox.glb");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("segmorph: kept skins: tracks within "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("(a subsample of frames, measurement 1)"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("(every frame, measurement "), std::string::npos) << result.err;
}

// --- vertex caches (tests/vertex_cache_test.cpp reads them through the library) ---

std::string flag(const std::string& file) { return sample("WavingFlag/" + file); }

TEST(Cli, VertexCachesEncodeAndVerify) {
  const std::string directory = output_directory("caches");
  for (const std::string& input : {flag("flag.obj") + " --cache " + flag("flag.pc2"), flag("obj_sequence"),
                                   "'" + flag("obj_sequence/flag_%04d.obj") + "'"}) {
    SCOPED_TRACE(input);
    const Result encoded = run("encode -q " + input + " --fps 24 --z-up -o " + directory + "/flag.glb --json");
    ASSERT_EQ(encoded.exit_code, 0) << encoded.err;
    EXPECT_LE(json_number(encoded.out, "kg_percent"), 0.15 * 1.05) << encoded.out;
    // Blender wrote the glTF, the PC2 and the sequence at the same times: verify compares them as they are.
    const Result verified = run("verify -q " + flag("flag.glb") + " " + directory + "/flag.glb --max-error 0.16");
    EXPECT_EQ(verified.exit_code, 0) << verified.out << verified.err;
    const Result against_cache = run("verify -q " + flag("flag.glb") + " " + input.substr(0, input.find(" --cache")) +
                                     (input.find("--cache") != std::string::npos ? " --cache2 " + flag("flag.pc2") : "") +
                                     " --fps 24 --z-up --max-error 0.0001");
    EXPECT_EQ(against_cache.exit_code, 0) << against_cache.out << against_cache.err;
  }
  // Without --z-up the caches lie on their back.
  const Result lying = run("verify -q " + flag("flag.glb") + " " + flag("flag.obj") + " --cache2 " + flag("flag.pc2") +
                           " --fps 24 --max-error 1");
  EXPECT_EQ(lying.exit_code, 1) << lying.out;
  // bake writes the cache as standard morph targets; info lists it.
  EXPECT_EQ(run("bake -q " + flag("flag.obj") + " --cache " + flag("flag.mdd") + " --z-up -o " + directory +
                "/baked.glb").exit_code,
            0);
  const Result info = run("info -q " + directory + "/baked.glb");
  EXPECT_NE(info.out.find("clip 0 \"flag\": 24 frames, 0.958 s"), std::string::npos) << info.out;
}

TEST(Cli, BadVertexCachesFailCleanly) {
  const std::string directory = output_directory("bad_caches");
  const std::string obj = flag("flag.obj");
  const std::string pc2 = read_text(flag("flag.pc2"));
  auto cache = [&](const std::string& name, const std::string& bytes) {
    write_text(directory + "/" + name, bytes);
    return " --cache " + directory + "/" + name;
  };
  std::string other_count = pc2;
  other_count[16] = char(116);  // 116 points: the file's size no longer fits either
  expect_clean_failure(obj, "other_count.pc2: PC2 cache of 24 frames of 116 points is", "encode",
                       cache("other_count.pc2", other_count));
  std::string fewer_points = pc2.substr(0, 32 + 24 * 116 * 12);
  fewer_points[16] = char(116);
  expect_clean_failure(obj, "fewer_points.pc2 moves 116 points, the base mesh", "encode",
                       cache("fewer_points.pc2", fewer_points));
  expect_clean_failure(obj, "truncated.pc2: PC2 cache of 24 frames of 117 points is 33728 bytes, the file 33727 "
                            "(truncated)", "encode", cache("truncated.pc2", pc2.substr(0, pc2.size() - 1)));
  std::string absurd = pc2;
  absurd[31] = char(0x7f);  // samples: 2 130 706 456
  expect_clean_failure(obj, "absurd.pc2: PC2 header claims 117 points and", "encode", cache("absurd.pc2", absurd));
  std::string infinite = pc2;
  const uint32_t infinity = 0x7f800000;
  std::memcpy(&infinite[32 + (3 * 117 + 5) * 12], &infinity, 4);
  expect_clean_failure(obj, "infinite.pc2: frame 3, point 5: not a finite position", "bake",
                       cache("infinite.pc2", infinite));
  expect_clean_failure(obj, "missing.pc2: cannot open", "encode", " --cache " + directory + "/missing.pc2");
  expect_clean_failure(flag("flag.pc2"), "a point cache moves a base mesh", "encode");
  expect_clean_failure(obj, "an .obj alone is one frame", "encode");

  // OBJ sequences: a frame with other faces or another vertex count, a missing frame, an index out of range, an
  // empty OBJ.
  const std::string sequence = output_directory("bad_sequence");
  for (int f = 1; f <= 24; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "/flag_%04d.obj", f);
    fs::copy_file(flag("obj_sequence") + name, sequence + name);
  }
  std::string frame = read_text(sequence + "/flag_0007.obj");
  write_text(sequence + "/flag_0007.obj", frame + "f 1/1/1 3/3/1 2/2/1\n");
  expect_clean_failure(sequence, ": more faces than the first frame's 96", "encode");
  std::string changed = frame;
  const size_t face = changed.find("\nf ") + 1;
  changed.replace(face, changed.find('\n', face) - face, "f 1 2 3 4");
  const std::string line = std::to_string(std::count(changed.begin(), changed.begin() + long(face), '\n') + 1);
  write_text(sequence + "/flag_0007.obj", changed);
  expect_clean_failure(sequence, "flag_0007.obj line " + line + ": face 1 differs from the first frame's", "encode");
  write_text(sequence + "/flag_0007.obj", frame + "v 0 0 0\n");
  expect_clean_failure(sequence, "flag_0007.obj: 118 vertices, the first frame 117", "encode");
  write_text(sequence + "/flag_0007.obj", frame);
  const std::string first = read_text(sequence + "/flag_0001.obj");
  write_text(sequence + "/flag_0001.obj", first + "f 1 2 118\n");
  expect_clean_failure(sequence, "flag_0001.obj: a face index is out of range (117 vertices", "encode");
  write_text(sequence + "/flag_0001.obj", "");
  expect_clean_failure(sequence, "flag_0001.obj: no faces", "encode");
  write_text(sequence + "/flag_0001.obj", first);
  fs::remove(sequence + "/flag_0012.obj");
  expect_clean_failure(sequence, "frame 12 is missing", "bake");
  expect_clean_failure(sequence + "/flag_%04d.obj", "frame 12 is missing", "encode");
}

// --json prints one valid JSON object per line, whatever the file names hold: quotes, backslashes, control
// characters and bytes that are not UTF-8 (written as U+FFFD).
TEST(Cli, JsonIsValidForAnyFileName) {
  const std::string directory = output_directory("json");
  const std::string name = directory + "/we\"ird\\name\t\xff.glb", encoded = directory + "/out.glb";
  fs::copy_file(sample("AnimatedMorphCube/AnimatedMorphCube.glb"), name);
  const std::string quoted = "'" + name + "'";
  const Result results[] = {run("info -q " + quoted + " --json"),
                            run("encode -q " + quoted + " -o " + encoded + " --json"),
                            run("verify -q " + quoted + " " + encoded + " --json --max-error 1e-9"),
                            run("info -q '" + directory + "/missing\"\xff.glb' --json")};
  const int exit_codes[] = {0, 0, 1, 1};
  const std::string keys[] = {"primitives", "primitives", "error", "error"};
  for (size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(results[i].out + results[i].err);
    EXPECT_EQ(results[i].exit_code, exit_codes[i]);
    ASSERT_EQ(std::count(results[i].out.begin(), results[i].out.end(), '\n'), 1);
    const nlohmann::json json = nlohmann::json::parse(results[i].out, nullptr, false);
    ASSERT_FALSE(json.is_discarded());
    EXPECT_TRUE(json.contains(keys[i]));
    const std::string file = json.contains("file")        ? json["file"].get<std::string>()
                             : json.contains("compressed") ? json["original"].get<std::string>()
                                                           : json["error"]["file"].get<std::string>();
    EXPECT_NE(file.find("\xef\xbf\xbd"), std::string::npos) << "the byte 0xff as U+FFFD";
    EXPECT_NE(file.find('"'), std::string::npos);
  }
  EXPECT_EQ(results[1].out.find("\"file\":\"" + directory + "/we\\\"ird\\\\name\\t\xef\xbf\xbd.glb\""),
            size_t(results[1].out.find("\"file\":")));
  EXPECT_GT(nlohmann::json::parse(results[2].out)["vertex_frames"].get<double>(), 0);
  EXPECT_EQ(nlohmann::json::parse(results[2].out)["error"]["code"], "above_bound");
}
