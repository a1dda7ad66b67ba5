// Private helper: how many threads a stage uses. Results never depend on it (parallel loops write
// to preallocated slots and reductions run in a fixed order).
#pragma once

#include <omp.h>

#include <algorithm>

namespace glimpse {

inline int resolve_threads(int requested) {
  return requested > 0 ? requested : std::max(1, omp_get_max_threads());
}

}  // namespace glimpse
