// The procedural zoo's building blocks (zoo.h): evenly tessellated primitives and the seeded random
// draws the category generators use. Internal to core/src: zoo.cpp and zoo_furniture.cpp.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>

#include "glimpse/cloud.h"
#include "glimpse/random.h"

namespace glimpse::zoo_internal {

constexpr float kPi = 3.14159265f;
using Mat3 = Eigen::Matrix3f;

inline Mat3 rot_x(float a) { return Eigen::AngleAxisf(a, Vec3::UnitX()).toRotationMatrix(); }
inline Mat3 rot_y(float a) { return Eigen::AngleAxisf(a, Vec3::UnitY()).toRotationMatrix(); }
inline Mat3 rot_z(float a) { return Eigen::AngleAxisf(a, Vec3::UnitZ()).toRotationMatrix(); }
inline float deg(float d) { return d * kPi / 180.f; }


struct Rng {
  std::mt19937_64 g;
  explicit Rng(uint64_t seed) : g(seed) {}
  double unit() { return double(g() >> 11) * 0x1.0p-53; }  // [0, 1), library-independent
  float uniform(float a, float b) { return float(a + unit() * (b - a)); }
  int integer(int lo, int hi) { return lo + int(unit() * (hi - lo + 1)); }  // inclusive
  bool chance(double p) { return unit() < p; }
  float sign() { return chance(0.5) ? 1.f : -1.f; }
};

// Adds evenly tessellated primitives; `spacing` is the target edge length.
class Builder {
 public:
  explicit Builder(float spacing) : h_(spacing) {}

  // Parametric patch f(u, v), u, v in [0, 1], as an nu x nv grid of triangle pairs.
  template <class F>
  void grid(int nu, int nv, F&& f) {
    const int base = int(mesh_.vertices.size());
    for (int j = 0; j <= nv; ++j)
      for (int i = 0; i <= nu; ++i) mesh_.vertices.push_back(f(float(i) / nu, float(j) / nv));
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const int a = base + j * (nu + 1) + i, b = a + 1, c = a + nu + 1, d = c + 1;
        mesh_.faces.emplace_back(a, b, d);
        mesh_.faces.emplace_back(a, d, c);
      }
  }

  int steps(float length, int min_steps = 1) const {
    return std::clamp(int(std::ceil(length / h_)), min_steps, 400);
  }

  void box(const Vec3& centre, const Vec3& size, const Mat3& rot = Mat3::Identity());

  // A box of cross-section w x d from a to b (a beam, a leg, a plank).
  void beam(const Vec3& a, const Vec3& b, float w, float d, float roll = 0);

  void ellipsoid(const Vec3& centre, const Vec3& radii, const Mat3& rot = Mat3::Identity());

  // Extruded outline r(theta) (star-shaped about the axis) along local z, centred, with an optional
  // round hole, and the top outline scaled by top_scale (cones, tapered legs).
  void extrusion(const Vec3& centre, const Mat3& rot, const std::function<float(float)>& radius, float r_max,
                 float height, float hole = 0, float top_scale = 1, int min_segments = 12);

  // Closed frustum from a (radius ra) to b (radius rb).
  void frustum(const Vec3& a, const Vec3& b, float ra, float rb, float hole = 0);

  // Tapered capsule: a limb between two joints.
  void capsule(const Vec3& a, const Vec3& b, float ra, float rb);

  // Torus about local z (ring radius R, tube radius r), swept over `sweep` radians.
  void torus(const Vec3& centre, const Mat3& rot, float R, float r, float sweep = 2 * kPi);

  // Merges coincident vertices (seams, poles, shared box edges) and drops the collapsed triangles.
  Mesh finish();

 private:
  float h_;
  Mesh mesh_;
};

// The category generators: each adds one shape of its category to `b`, proportions from `r`.
void human(Builder& b, Rng& r);     // zoo.cpp
void mechanic(Builder& b, Rng& r);  // zoo.cpp
void fourleg(Builder& b, Rng& r);   // zoo.cpp
void chair(Builder& b, Rng& r);     // zoo_furniture.cpp
void table(Builder& b, Rng& r);     // zoo_furniture.cpp

}  // namespace glimpse::zoo_internal
