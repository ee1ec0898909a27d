// File names as the tool reads them.
#pragma once

#include <cctype>
#include <string>

namespace segmorph {

// `path` ends with `suffix` (given in lower case, such as ".glb"), in any case: "FOX.GLB" is a .glb.
inline bool has_suffix(const std::string& path, const std::string& suffix) {
  if (path.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(path[path.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

}  // namespace segmorph
