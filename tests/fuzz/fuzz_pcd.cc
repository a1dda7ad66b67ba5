// libFuzzer target: the PCD reader (core/src/io_pcd.cpp), ascii and binary bodies.
#include "fuzz_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto cloud = glimpse::io_detail::read_pcd("fuzz.pcd", glimpse::fuzz::Text(data, size));
  if (!cloud && cloud.error().message.empty()) __builtin_trap();
  return 0;
}
