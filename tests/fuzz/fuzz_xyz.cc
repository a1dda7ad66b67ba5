// libFuzzer target: the XYZ reader through the public read_cloud (core/src/io.cpp: the whole-file
// read, the extension dispatch and the text parser), from a file in a private temporary folder.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "glimpse/io/files.h"

namespace {
// The folder lives as long as the process (a leaked string: atexit handlers run after statics die).
const std::string& Path() {
  static const std::string* path = [] {
    const char* shm = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
    static const std::string* dir = new std::string(std::string(shm) + "/glimpse-fuzz-xyz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(*dir);
    std::atexit([] { std::filesystem::remove_all(*dir); });
    return new std::string(*dir + "/cloud.xyz");
  }();
  return *path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = Path();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  auto cloud = glimpse::read_cloud(path);
  if (!cloud && cloud.error().message.rfind(path, 0) != 0) __builtin_trap();  // errors start with the path
  return 0;
}
