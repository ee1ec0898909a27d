#include "gltf/json_reserve.h"

#include <atomic>

namespace segmorph {
namespace {

// Enough for the vectors nlohmann::json's destructors make (16 bytes a child) of any glTF's arrays.
constexpr size_t kReserveBytes = size_t(4) << 20;

std::mutex reserve_mutex;
std::atomic<char*> reserve{nullptr};  // the handler may run on any thread
std::atomic<bool> reserve_used{false};

// The new_handler: frees the block and steps aside (a second failure throws std::bad_alloc as usual).
void release_reserve() {
  delete[] reserve.exchange(nullptr);
  reserve_used = true;
  std::set_new_handler(nullptr);
}

}  // namespace

JsonReserve::JsonReserve() : lock_(reserve_mutex) {
  reserve = new char[kReserveBytes];
  reserve_used = false;
  previous_ = std::set_new_handler(release_reserve);
}

JsonReserve::~JsonReserve() {
  std::set_new_handler(previous_);
  delete[] reserve.exchange(nullptr);
}

bool JsonReserve::used() const { return reserve_used; }

void JsonReserve::check() const {
  if (used()) throw std::bad_alloc();
}

}  // namespace segmorph
