#include "cli/batch.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <system_error>
#include <thread>

#include "cli/reports.h"
#include "segmorph/segmorph.h"

namespace segmorph {
namespace {

namespace fs = std::filesystem;

// The children running now, for the signal handler (fixed slots: it reads only memory that is always there).
constexpr int kMaxChildren = 256;
std::atomic<pid_t> children[kMaxChildren];

// Passes the signal on and waits for the children to end (they remove their temporary files; one in a long fsync
// may take a while) before ending the batch the same way: when the batch has ended, none of its files is left being
// written. kill and waitpid are async-signal-safe.
extern "C" void pass_signal_to_children(int signal_number) {
  for (int c = 0; c < kMaxChildren; ++c)
    if (const pid_t pid = children[c].load()) kill(pid, signal_number);
  for (int c = 0; c < kMaxChildren; ++c)
    if (const pid_t pid = children[c].load())
      while (waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
      }
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

// Whether `path` lies under the folder `folder` (both as they resolve now).
bool is_under(const fs::path& path, const fs::path& folder) {
  std::error_code error;
  const fs::path a = fs::weakly_canonical(path, error), b = fs::weakly_canonical(folder, error);
  const auto mismatch = std::mismatch(b.begin(), b.end(), a.begin(), a.end());
  return mismatch.first == b.end();
}

struct Child {
  pid_t pid = 0;
  size_t file = 0;
  int slot = 0;
  FILE* report = nullptr;  // the child's stdout
};

std::string read_all(FILE* file) {
  std::string text;
  std::rewind(file);
  char buffer[4096];
  for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), file)) > 0;) text.append(buffer, n);
  return text;
}


}  // namespace

bool plan_batch(const std::vector<std::string>& inputs, const std::string& directory, std::vector<BatchFile>& files,
                std::string& error) {
  files.clear();
  for (const std::string& input : inputs) {
    std::error_code failure;
    if (!fs::is_directory(input, failure)) {
      files.push_back({input, ""});  // a missing or unreadable file is the child's to report
      continue;
    }
    std::vector<std::string> found;
    for (fs::recursive_directory_iterator it(input, failure), end; !failure && it != end; it.increment(failure))
      if (it->is_regular_file(failure) && has_gltf_extension(it->path().string()) &&
          !is_under(it->path(), directory))
        found.push_back(it->path().string());
    if (failure) return error = "cannot read the folder " + input + ": " + failure.message(), false;
    std::sort(found.begin(), found.end());
    for (const std::string& file : found) files.push_back({file, ""});
  }
  if (files.empty()) return error = "no .glb or .gltf file in the inputs", false;
  std::map<std::string, std::string> writers;  // output -> input
  for (BatchFile& file : files) {
    file.output = (fs::path(directory) / fs::path(file.input).filename().replace_extension(".glb")).string();
    const auto [at, added] = writers.emplace(file.output, file.input);
    if (!added) return error = at->second + " and " + file.input + " would both write " + file.output, false;
  }
  return true;
}

int run_batch(const CommandLine& options, const std::vector<BatchFile>& files, int (*single)(const CommandLine&)) {
  std::error_code failure;
  fs::create_directories(options.output_directory, failure);
  if (failure || !fs::is_directory(options.output_directory)) {
    std::fprintf(stderr, "segmorph: error: %s: cannot create the folder: %s\n", options.output_directory.c_str(),
                 failure.message().c_str());
    if (options.json)
      std::printf("%s\n", error_json("io_error", options.output_directory, "cannot create the folder").c_str());
    return 1;
  }
  struct sigaction action, previous_interrupt, previous_terminate;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = pass_signal_to_children;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &previous_interrupt);
  sigaction(SIGTERM, &action, &previous_terminate);

  const size_t jobs = size_t(std::clamp(options.jobs, 1, kMaxChildren));
  std::vector<std::string> reports(files.size());
  std::vector<bool> done(files.size(), false);
  std::vector<Child> running;
  size_t next = 0, printed = 0, failed = 0;
  while (printed < files.size()) {
    while (running.size() < jobs && next < files.size()) {
      Child child;
      child.file = next++;
      child.report = std::tmpfile();
      while (children[child.slot].load() != 0) ++child.slot;  // a free slot: fewer run than there are slots
      std::fflush(stdout);
      std::fflush(stderr);
      // The signals are held from the fork until the child is in `children`: a signal that came in between would
      // find the new child unknown, end the batch and leave it running, writing its file alone (seen under ASan,
      // whose fork is slow). The child lets them through once its own handlers are back.
      sigset_t held, before;
      sigemptyset(&held);
      sigaddset(&held, SIGINT);
      sigaddset(&held, SIGTERM);
      sigprocmask(SIG_BLOCK, &held, &before);
      child.pid = child.report ? fork() : -1;
      if (child.pid == 0) {
        sigaction(SIGINT, &previous_interrupt, nullptr);
        sigaction(SIGTERM, &previous_terminate, nullptr);
        sigprocmask(SIG_SETMASK, &before, nullptr);
        dup2(fileno(child.report), STDOUT_FILENO);
        CommandLine one = options;
        one.inputs = {files[child.file].input};
        one.output = files[child.file].output;
        one.output_directory.clear();
        one.label = files[child.file].input;
        // The cores are shared by the files running at once (unless --threads says otherwise).
        if (one.encode.threads == 0)
          one.encode.threads = one.decode.threads = std::max<size_t>(1, std::thread::hardware_concurrency() / jobs);
        const int code = single(one);
        std::fflush(stdout);
        std::fflush(stderr);
        _exit(code);
      }
      if (child.pid < 0) {  // no process: the file fails, the others go on
        const int error = errno;
        sigprocmask(SIG_SETMASK, &before, nullptr);
        reports[child.file] =
            "segmorph: error: " + files[child.file].input + ": cannot start a process: " + std::strerror(error) + "\n";
        if (child.report) std::fclose(child.report);
        done[child.file] = true, ++failed;
        continue;
      }
      children[child.slot].store(child.pid);
      sigprocmask(SIG_SETMASK, &before, nullptr);
      running.push_back(child);
    }
    if (!running.empty()) {
      int status = 0;
      const pid_t pid = waitpid(-1, &status, 0);
      if (pid < 0) {
        if (errno == EINTR) continue;
        break;  // no child left to wait for: cannot happen while `running` has one
      }
      const auto child = std::find_if(running.begin(), running.end(), [&](const Child& c) { return c.pid == pid; });
      if (child == running.end()) continue;
      children[child->slot].store(0);
      std::string report = read_all(child->report);
      std::fclose(child->report);
      const std::string& input = files[child->file].input;
      if (WIFSIGNALED(status)) {
        const std::string what = std::string("stopped by signal ") + std::to_string(WTERMSIG(status)) + " (" +
                                 strsignal(WTERMSIG(status)) + ")";
        std::fprintf(stderr, "segmorph: error: %s: %s\n", input.c_str(), what.c_str());
        if (options.json)
          report += error_json("internal", input, what) + "\n";
      }
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++failed;
      reports[child->file] = std::move(report);
      done[child->file] = true;
      running.erase(child);
    }
    for (; printed < files.size() && done[printed]; ++printed) {
      std::fputs(reports[printed].c_str(), stdout);
      std::fflush(stdout);
    }
  }
  sigaction(SIGINT, &previous_interrupt, nullptr);
  sigaction(SIGTERM, &previous_terminate, nullptr);
  if (options.json)
    std::printf("{\"files\":%zu,\"failed\":%zu}\n", files.size(), failed);
  else
    std::printf("%zu file%s, %zu failed\n", files.size(), files.size() == 1 ? "" : "s", failed);
  return failed ? 1 : 0;
}

}  // namespace segmorph
