#include "cli/huge_pages.h"

#include <unistd.h>
#if defined(__linux__)
#include <sys/auxv.h>
#endif

#include <cstdlib>
#include <cstring>
#include <string>

namespace segmorph {

// Large buffers (a production cache's frames are gigabytes) are first touched page by page, and with 4 KiB pages each
// touch is a page fault: on the machine the benchmarks run on, a third of a 200k-vertex encode's time. glibc backs its
// large allocations with transparent huge pages when its tunable glibc.malloc.hugetlb is 1 (where the kernel leaves
// them to madvise, as Debian's does), but reads its tunables only at start: so the tool starts itself again, once,
// from its own file, with the tunable added to GLIBC_TUNABLES and SEGMORPH_HUGE_PAGES=1 (which also stops a second
// restart where glibc ignores the tunables). The arguments, descriptors and output bytes are the same. It does not
// restart when SEGMORPH_HUGE_PAGES is set (0 turns this off: for a tool that does not follow a restart, valgrind
// without --trace-children), when GLIBC_TUNABLES already names the tunable, for a secure-mode (setuid) start, under
// a sanitizer or valgrind (which replace malloc), when started through the dynamic loader, or when the restart
// fails (it then goes on as started).
void use_transparent_huge_pages(char** argv) {
#if defined(__linux__) && defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
  constexpr const char* kTunable = "glibc.malloc.hugetlb";
  if (std::getenv("SEGMORPH_HUGE_PAGES") != nullptr || getauxval(AT_SECURE) != 0) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, kTunable) != nullptr) return;
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload != nullptr && std::strstr(preload, "vgpreload") != nullptr) return;  // valgrind
  // The file this process runs (not the dynamic loader's, when it was started through it).
  char self[4096];
  const ssize_t length = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length <= 0) return;
  self[length] = '\0';
  const char* name = std::strrchr(self, '/');
  if (std::strncmp(name != nullptr ? name + 1 : self, "ld-", 3) == 0) return;
  const std::string previous = tunables != nullptr ? tunables : "";
  const std::string wanted = (previous.empty() ? "" : previous + ":") + kTunable + "=1";
  if (setenv("GLIBC_TUNABLES", wanted.c_str(), 1) != 0 || setenv("SEGMORPH_HUGE_PAGES", "1", 1) != 0) return;
  execv(self, argv);
  // Still here: the restart failed; go on as started.
  unsetenv("SEGMORPH_HUGE_PAGES");
  if (tunables != nullptr)
    setenv("GLIBC_TUNABLES", previous.c_str(), 1);
  else
    unsetenv("GLIBC_TUNABLES");
#else
  (void)argv;
#endif
}

}  // namespace segmorph
