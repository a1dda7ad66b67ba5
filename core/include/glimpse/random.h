// Seeded draws that give the same numbers with every standard library (std::*_distribution do not).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string_view>

namespace glimpse {

// SplitMix64 (Steele, Lea & Flood 2014): independent seeds from a seed and a counter or hash.
inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
// The i-th of a seeded sequence: splitmix64 of seed + i x its increment.
inline uint64_t splitmix64(uint64_t seed, uint64_t i) { return splitmix64(seed + 0x9E3779B97F4A7C15ull * i); }

// FNV-1a of a name: a seed from a string that every standard library agrees on (std::hash differs).
inline uint32_t name_hash(std::string_view s) {
  uint32_t h = 2166136261u;
  for (unsigned char c : s) h = (h ^ c) * 16777619u;
  return h;
}

// Uniform in [0, 1) from the top 53 bits.
inline double uniform01(uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }
inline double uniform01(std::mt19937_64& rng) { return uniform01(rng()); }

// Standard normal, Box-Muller (one of the pair; two uniforms per draw).
inline double standard_normal(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform01(rng);  // (0, 1]: log is finite
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace glimpse
