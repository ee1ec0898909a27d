// The command-line tool as a user meets it, whatever the command: help and usage errors, options, errors in
// one line (and one JSON object), outputs written whole or not at all, signals, the standard input and output.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"

using namespace cli_testing;

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

TEST(Cli, UnwritableOutputFailsCleanly) {
  const Result result =
      run("bake -q " + sample("SimpleSkin/SimpleSkin.gltf") + " -o " + temporary_path("no/such/dir/out.glb"));
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
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
