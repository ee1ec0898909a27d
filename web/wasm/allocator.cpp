// The WebAssembly module's memory allocation for JavaScript (web/segmorph_decoder.js), which copies streams and base
// meshes into the module's memory and frames out of it. Everything else the module exports is the C API
// (include/segmorph/decoder_c.h).
#include <cstddef>
#include <cstdlib>

extern "C" {

__attribute__((visibility("default"))) void* segmorph_wasm_malloc(size_t bytes) { return std::malloc(bytes); }

__attribute__((visibility("default"))) void segmorph_wasm_free(void* pointer) { std::free(pointer); }

}  // extern "C"
