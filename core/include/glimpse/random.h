// Seeded draws that give the same numbers with every standard library (std::*_distribution do not).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace glimpse {

// Uniform in [0, 1) from the top 53 bits.
inline double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Standard normal, Box-Muller (one of the pair; two uniforms per draw).
inline double standard_normal(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform01(rng);  // (0, 1]: log is finite
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace glimpse
