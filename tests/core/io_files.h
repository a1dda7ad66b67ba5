// The reader tests' files: a fixture that writes them in a temporary folder, and a value's bytes in
// either byte order for binary bodies.
#pragma once

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "common/temp_dir.h"

namespace glimpse::test {

// Appends v's bytes to s, big-endian when `big`, else little-endian.
template <class T>
void put(std::string& s, T v, bool big) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

// Files written in a temporary folder of the test's own.
class IoTest : public ::testing::Test {
 protected:
  std::string write(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  glimpse::testing::TempDir tmp_{"io"};
  std::filesystem::path dir_ = tmp_.path();
};

}  // namespace glimpse::test
