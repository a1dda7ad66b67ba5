// libFuzzer target: the OFF reader (core/src/io_off.cpp), vertices and faces.
#include "fuzz_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  glimpse::fuzz::CheckMesh(glimpse::io_detail::read_off("fuzz.off", glimpse::fuzz::Text(data, size)));
  return 0;
}
