// libFuzzer target: the STL reader (core/src/io_stl.cpp), binary and ASCII.
#include "fuzz_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  glimpse::fuzz::CheckMesh(glimpse::io_detail::read_stl("fuzz.stl", glimpse::fuzz::Text(data, size)));
  return 0;
}
