// libFuzzer target: the model deserializer (glimpse::deserialize, core/src/serialize.cpp).
// The input is a model's payload: the target frames it with the magic, a format version, the length and
// a correct CRC-32, so the fuzzer explores the parser instead of the checksum, once for every format
// version this build reads (1 to the one serialize writes: each version parses the payload its own
// way); the raw bytes are tried as a whole file too. A model that loads must serialize and load again
// to the same bytes.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "glimpse/learning/model.h"

namespace {

uint32_t Crc32(const uint8_t* p, size_t n) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

void Le(std::vector<uint8_t>& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// The format version serialize writes (bytes 8-11 of any model file), so a new format is fuzzed
// without editing this target.
uint32_t CurrentVersion() {
  const std::vector<uint8_t> bytes = glimpse::serialize(glimpse::Model{});
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(bytes.at(8 + static_cast<size_t>(i))) << (8 * i);
  return v;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const uint32_t current = CurrentVersion();
  (void)glimpse::deserialize({data, size});
  for (uint32_t version = 1; version <= current; ++version) {
    std::vector<uint8_t> framed = {'G', 'L', 'M', 'P', 'S', 'M', 'D', 'L'};
    Le(framed, version, 4);
    Le(framed, size, 8);
    framed.insert(framed.end(), data, data + size);
    Le(framed, Crc32(data, size), 4);
    auto model = glimpse::deserialize(framed);
    if (!model) continue;
    const std::vector<uint8_t> again = glimpse::serialize(*model);
    auto reloaded = glimpse::deserialize(again);
    if (!reloaded || glimpse::serialize(*reloaded) != again) __builtin_trap();
  }
  return 0;
}
