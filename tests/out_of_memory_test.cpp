// The pipeline API promises errors as a Status, "never as an exception" (include/segmorph/segmorph.h): a failed
// allocation anywhere in info, bake, encode, decode or verify comes back as OUT_OF_MEMORY, and the process lives on.
// This test binary replaces the global operator new so that one chosen allocation fails (the nth from a point on),
// and sweeps n over each call's allocations. As the standard operator new does, a failed allocation first calls the
// new_handler, if one is installed, and is tried again (gltf/json_reserve.h frees a reserve there while the JSON
// library, which allocates in its destructors, runs); without one it throws std::bad_alloc.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <string>

#include "segmorph/segmorph.h"
#include "test_files.h"

namespace {

std::atomic<long long> allocations_until_failure{-1};  // -1: none fails
std::atomic<long long> allocations_counted{0};

void* allocate(std::size_t size) {
  allocations_counted.fetch_add(1, std::memory_order_relaxed);
  if (allocations_until_failure.load(std::memory_order_relaxed) >= 0 &&
      allocations_until_failure.fetch_sub(1, std::memory_order_relaxed) == 0) {
    const std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();  // it made room (or threw): tried again below
  }
  for (;;) {
    if (void* p = std::malloc(size ? size : 1)) return p;
    const std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace segmorph {
namespace {

// Runs `call` once to count the allocations of its API call, then again with the nth of them failing for n spread over
// them (and the first): each run ends in a Status, ok or OUT_OF_MEMORY with a message. `call(arm)` prepares its
// inputs, then calls arm() just before the API call, so that only the call's allocations count and may fail.
template <typename Call>
void sweep(const std::string& what, Call call) {
  long long armed_at = -1;
  auto count = [] { allocations_counted = 0; };
  ASSERT_TRUE(call(count).ok()) << what;
  const long long total = allocations_counted;
  ASSERT_GT(total, 0) << what;
  int failed = 0;
  for (long long n : {0LL, 1LL, total / 7, total / 3, total / 2, (total * 4) / 5, total - 1}) {
    armed_at = n;
    const Status status = call([&] { allocations_until_failure = armed_at; });
    const bool failure_happened = allocations_until_failure < 0;
    allocations_until_failure = -1;
    if (!failure_happened) {
      EXPECT_TRUE(status.ok()) << what << ", allocation " << n << ": " << status.message();
      continue;
    }
    ++failed;
    EXPECT_EQ(status.code(), StatusCode::out_of_memory)
        << what << ", allocation " << n << " of " << total << ": " << status.message();
    EXPECT_FALSE(status.message().empty());
  }
  EXPECT_GT(failed, 0) << what << ": no allocation failed: the test did not test";
}

TEST(OutOfMemory, EveryApiCallReturnsAStatus) {
  const std::string input = std::string(SEGMORPH_SAMPLES_DIR) + "/AnimatedMorphCube/AnimatedMorphCube.glb";
  Model original;
  ASSERT_TRUE(Model::load(input, original).ok());
  EncodeSettings settings;
  settings.threads = 1;
  const SampleSettings sampling;
  Model encoded;
  ASSERT_TRUE(encode(original, settings, encoded).ok());

  sweep("info", [&](auto arm) {
    InfoReport report;
    arm();
    return info(original, sampling, report);
  });
  sweep("bake", [&](auto arm) {
    Model model = original;
    arm();
    return bake(model, sampling);
  });
  sweep("encode", [&](auto arm) {
    Model output;
    arm();
    return encode(original, settings, output);
  });
  sweep("decode", [&](auto arm) {
    Model model = encoded;
    arm();
    return decode(model);
  });
  sweep("verify", [&](auto arm) {
    VerifyReport report;
    arm();
    return verify(original, encoded, sampling, report);
  });
}

}  // namespace
}  // namespace segmorph
