// Runs one command and reports what it cost: wall time, CPU time and peak resident memory, the same way for
// every tool the benchmarks run (segmorph, gltfpack and glTF-Transform under Node.js, anything else).
//   run_measured REPORT.json -- COMMAND [ARGS...]
// The command inherits standard input, output and error. REPORT.json receives one JSON object:
//   {"exit":0,"wall_ms":812.4,"user_ms":790.1,"sys_ms":20.3,"max_rss_kb":48212}
// max_rss_kb is the peak resident set of the command's process (wait4's ru_maxrss); the tools measured here run
// in one process (gltfpack and glTF-Transform are WebAssembly and JavaScript inside Node.js).
// Exit status: the command's (128 + N when signal N ended it), 127 when it cannot be started, 2 on bad usage.
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

int main(int argc, char** argv) {
  if (argc < 4 || std::strcmp(argv[2], "--") != 0) {
    std::fprintf(stderr, "usage: run_measured REPORT.json -- COMMAND [ARGS...]\n");
    return 2;
  }
  const char* report_path = argv[1];
  const auto start = std::chrono::steady_clock::now();
  const pid_t child = fork();
  if (child < 0) {
    std::fprintf(stderr, "run_measured: fork failed: %s\n", std::strerror(errno));
    return 127;
  }
  if (child == 0) {
    execvp(argv[3], argv + 3);
    std::fprintf(stderr, "run_measured: cannot run %s: %s\n", argv[3], std::strerror(errno));
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  while (wait4(child, &status, 0, &usage) < 0) {
    if (errno != EINTR) {
      std::fprintf(stderr, "run_measured: wait4 failed: %s\n", std::strerror(errno));
      return 127;
    }
  }
  const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const int exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  auto ms = [](const timeval& t) { return double(t.tv_sec) * 1e3 + double(t.tv_usec) / 1e3; };
  std::FILE* report = std::fopen(report_path, "w");
  if (!report) {
    std::fprintf(stderr, "run_measured: cannot write %s: %s\n", report_path, std::strerror(errno));
    return 127;
  }
  std::fprintf(report, "{\"exit\":%d,\"wall_ms\":%.1f,\"user_ms\":%.1f,\"sys_ms\":%.1f,\"max_rss_kb\":%ld}\n",
               exit_code, wall_ms, ms(usage.ru_utime), ms(usage.ru_stime), usage.ru_maxrss);
  std::fclose(report);
  return exit_code;
}
