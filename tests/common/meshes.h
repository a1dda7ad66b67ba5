// Small mesh files for tests that read folders of meshes.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace glimpse::testing {

// A closed OFF box of 12 triangles, sx x sy x sz (the file's units), one corner at the origin; creates the
// file's folders and returns its path.
inline std::string WriteOffBox(const std::filesystem::path& path, float sx, float sy, float sz) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  out << "OFF\n8 12 0\n";
  for (int i = 0; i < 8; ++i) out << sx * (i & 1) << " " << sy * ((i >> 1) & 1) << " " << sz * ((i >> 2) & 1) << "\n";
  const int f[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  for (const auto& t : f) out << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return path.string();
}

}  // namespace glimpse::testing
