// Analytic point clouds for tests: deterministic, noise-free unless asked.
#pragma once

#include <cmath>
#include <numbers>
#include <random>

#include "glimpse/cloud.h"

namespace glimpse::test {

inline constexpr float kPi = std::numbers::pi_v<float>;

// Fibonacci sphere: n nearly uniform points.
inline Points sphere(float radius, size_t n, Vec3 centre = Vec3::Zero()) {
  Points p;
  const float golden = kPi * (3.f - std::sqrt(5.f));
  for (size_t i = 0; i < n; ++i) {
    const float z = 1.f - 2.f * (static_cast<float>(i) + 0.5f) / static_cast<float>(n);
    const float rho = std::sqrt(1.f - z * z);
    const float a = golden * static_cast<float>(i);
    p.push_back(centre + radius * Vec3(rho * std::cos(a), rho * std::sin(a), z));
  }
  return p;
}

// Open cylinder along z, grid-sampled with the given spacing.
inline Points cylinder(float radius, float height, float spacing) {
  Points p;
  const int around = static_cast<int>(std::round(2 * kPi * radius / spacing));
  const int along = static_cast<int>(std::round(height / spacing));
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < around; ++i) {
      const float a = 2 * kPi * i / around + (j % 2) * kPi / around;
      p.emplace_back(radius * std::cos(a), radius * std::sin(a), j * spacing - height / 2);
    }
  return p;
}

// z = f(x, y) over a square grid of half-size `half` centred at the origin.
template <class F>
Points height_field(float half, float spacing, F f) {
  Points p;
  const int n = static_cast<int>(std::round(half / spacing));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      const float x = i * spacing, y = j * spacing;
      p.emplace_back(x, y, f(x, y));
    }
  return p;
}

inline Points plane(float half, float spacing) {
  return height_field(half, spacing, [](float, float) { return 0.f; });
}

// Surface of an axis-aligned cube [0, side]^3, each face a grid of the given spacing (no duplicates
// along edges matter: cleaning removes exact ones).
inline Points cube(float side, float spacing) {
  Points p;
  const int n = static_cast<int>(std::round(side / spacing));
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const float a = i * spacing, b = j * spacing;
      p.emplace_back(a, b, 0.f), p.emplace_back(a, b, side);
      p.emplace_back(a, 0.f, b), p.emplace_back(a, side, b);
      p.emplace_back(0.f, a, b), p.emplace_back(side, a, b);
    }
  return p;
}

inline Points jitter(Points p, float sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g(0.f, sigma);
  for (Vec3& q : p) q += Vec3(g(rng), g(rng), g(rng));
  return p;
}

}  // namespace glimpse::test
