// Work split over threads: the encoder's stages, and the runtime decoder's version-4 frames where its caller asks
// for threads (AnimationDecoder::set_threads; never in its WebAssembly build, which has none). Each call runs items
// (or contiguous ranges of them) on up to `threads` threads and returns when all are done; what the body computes per
// item or range does not depend on the thread count. Callers keep results per item (or per range in range order), so
// the output is the same bytes for every thread count.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace segmorph {

// Threads for a setting: 0 means every hardware thread; at least 1.
inline size_t thread_count(size_t requested) {
  if (requested > 0) return requested;
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware > 0 ? hardware : 1;
}

// Calls body(i) for every i in [0, count), the items handed out one at a time, in order, to up to `threads` threads
// as each finishes its last (item 0 on the calling thread, which may report progress from it): for items of unequal
// cost, which fixed shares would leave some threads idle behind others. What an item computes must depend on the
// item alone (results kept per item): the output is then the same for every thread count and every order in which
// they finish. A thread that cannot be started leaves its share to the others. An exception in an item stops the
// handing out; the lowest failed item's exception is rethrown here after every thread has finished.
template <typename Body>
void parallel_items(size_t count, size_t threads, Body&& body) {
  const size_t wanted = std::min(std::max<size_t>(threads, 1), count);
  std::atomic<size_t> next{1};  // item 0 is the calling thread's
  std::atomic<bool> failed{false};
  std::vector<std::exception_ptr> errors(count);
  auto item = [&](size_t i) {
    try {
      body(i);
    } catch (...) {
      errors[i] = std::current_exception();
      failed = true;
    }
  };
  auto run = [&] {
    for (size_t i; !failed.load(std::memory_order_relaxed) && (i = next.fetch_add(1)) < count;) item(i);
  };
  std::vector<std::thread> workers;
  if (wanted > 1) {
    workers.reserve(wanted - 1);
    try {
      for (size_t t = 1; t < wanted; ++t) workers.emplace_back(run);
    } catch (const std::system_error&) {  // no more threads: those started and this one share the items
    }
  }
  if (count > 0) item(0);
  run();
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& error : errors)
    if (error) std::rethrow_exception(error);
}

// Calls body(begin, end) for consecutive ranges covering [0, count): at most `threads` ranges, of near-equal size,
// each an item of parallel_items (the first on the calling thread; a range whose thread cannot be started runs on
// another). The ranges do not depend on how many threads start. An exception in a range is rethrown here after every
// thread has finished (the lowest failed range's).
template <typename Body>
void parallel_ranges(size_t count, size_t threads, Body&& body) {
  const size_t ranges = std::min(std::max<size_t>(threads, 1), count);
  parallel_items(ranges, ranges, [&](size_t r) { body(count * r / ranges, count * (r + 1) / ranges); });
}

}  // namespace segmorph
