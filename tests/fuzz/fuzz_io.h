// Shared by the file-reader fuzz targets: the fuzzer's bytes are handed to the parsers as the file's
// text (a string_view over exactly those bytes, so AddressSanitizer sees any read past the end).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "io/text.h"  // core/src: the parsers behind read_cloud/read_mesh

namespace glimpse::fuzz {

inline std::string_view Text(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Whatever a parser returns must be usable: every face index within the vertices.
inline void CheckMesh(const Expected<Mesh>& mesh) {
  if (!mesh) {
    if (mesh.error().message.empty()) __builtin_trap();
    return;
  }
  for (const auto& f : mesh->faces)
    for (int a = 0; a < 3; ++a)
      if (f[a] < 0 || static_cast<size_t>(f[a]) >= mesh->vertices.size()) __builtin_trap();
}

}  // namespace glimpse::fuzz
