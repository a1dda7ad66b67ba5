// Wall time of a stage, for the diagnostics, progress and timings every stage reports.
#pragma once

#include <chrono>

namespace glimpse {

inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace glimpse
