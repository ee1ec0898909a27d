// Memory standing by while tinygltf reads or writes JSON. Its JSON library, nlohmann::json, allocates in its
// destructors (it moves a tree's children onto a vector before freeing them), and an allocation that fails in a
// destructor ends the process instead of throwing. While a JsonReserve lives, a block stands by: the first allocation
// that fails frees it (the standard std::new_handler, which operator new calls before it gives up) and is tried again,
// and check() then reports the shortage as std::bad_alloc, outside the library, where it becomes an OUT_OF_MEMORY
// Status. The handler is the process's: one reserve at a time (the constructor waits for the last to end).
#pragma once

#include <cstddef>
#include <mutex>
#include <new>

namespace segmorph {

class JsonReserve {
 public:
  JsonReserve();
  ~JsonReserve();
  JsonReserve(const JsonReserve&) = delete;
  JsonReserve& operator=(const JsonReserve&) = delete;
  // Whether the reserve was needed; check() throws std::bad_alloc if it was.
  bool used() const;
  void check() const;

 private:
  std::unique_lock<std::mutex> lock_;
  std::new_handler previous_ = nullptr;
};

}  // namespace segmorph
