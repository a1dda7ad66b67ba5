// One grid-cell hash for every spatial grid in core: duplicates in clean(), the growing VoxelIndex of
// a scan, the keypoints' claims, the zoo's vertex welding.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "glimpse/cloud.h"

namespace glimpse {

// The index of the grid cell holding coordinate `v` for cells of size `cell`, clamped to Int's range,
// so huge coordinates or tiny cells share an edge cell (slower, still correct) instead of overflowing.
template <class Int>
Int grid_cell(float v, float cell) {
  const double c = std::floor(static_cast<double>(v) / static_cast<double>(cell));
  constexpr double lo = static_cast<double>(std::numeric_limits<Int>::lowest());
  const double hi = std::ldexp(1.0, std::numeric_limits<Int>::digits) - 1024.0;  // below max, exact
  return c != c ? Int{0} : static_cast<Int>(std::clamp(c, lo, hi));
}

struct CellKey {
  int64_t x = 0, y = 0, z = 0;
  bool operator==(const CellKey&) const = default;
};

// Teschner et al. 2003 ("Optimized spatial hashing for collision detection"), then a Fibonacci mix so
// the low bits are usable by power-of-two tables.
struct CellKeyHash {
  size_t operator()(const CellKey& k) const {
    const uint64_t h = uint64_t(k.x) * 73856093ull ^ uint64_t(k.y) * 19349663ull ^ uint64_t(k.z) * 83492791ull;
    return static_cast<size_t>(h * 0x9E3779B97F4A7C15ull);
  }
};

inline CellKey cell_key(const Vec3& p, float cell) {
  return {grid_cell<int64_t>(p.x(), cell), grid_cell<int64_t>(p.y(), cell), grid_cell<int64_t>(p.z(), cell)};
}

}  // namespace glimpse
