// libFuzzer target: the PLY reader (core/src/io_ply.cpp), ascii and binary of both endiannesses, as a
// mesh and as a cloud (vertices only, with the glimpse_sensor and glimpse_frame comments).
#include "fuzz_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = glimpse::fuzz::Text(data, size);
  glimpse::fuzz::CheckMesh(glimpse::io_detail::read_ply("fuzz.ply", text, false, nullptr));
  glimpse::Cloud view;
  auto cloud = glimpse::io_detail::read_ply("fuzz.ply", text, true, &view);
  if (cloud && !cloud->faces.empty()) __builtin_trap();  // vertices only
  return 0;
}
