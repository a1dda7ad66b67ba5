// A small synthetic recognition problem for tests: rows of balls, boxes or cans of random sizes,
// seen from random cameras. Views are back-face culled (parts may hide each other a little: that is
// consistent between training and test, which is all the tests need).
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"

namespace glimpse::test {

struct Surfel {
  Vec3 p, n;
};

class Rng {
 public:
  explicit Rng(uint64_t seed) : g_(seed) {}
  float uniform(float lo, float hi) { return lo + (hi - lo) * static_cast<float>((g_() >> 11) * 0x1.0p-53); }

 private:
  std::mt19937_64 g_;
};

inline std::vector<Surfel> ball(float radius, float spacing, Rng& rng) {
  std::vector<Surfel> s;
  const int n = static_cast<int>(4 * 3.14159f * radius * radius / (spacing * spacing));
  for (int i = 0; i < n; ++i) {
    Vec3 d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (d.squaredNorm() > 1 || d.squaredNorm() < 1e-4f) { --i; continue; }
    d.normalize();
    s.push_back({radius * d, d});
  }
  return s;
}

inline std::vector<Surfel> box(Vec3 size, float spacing, Rng& rng) {
  std::vector<Surfel> s;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int n = static_cast<int>(size[u] * size[v] / (spacing * spacing));
      for (int i = 0; i < n; ++i) {
        Vec3 p, nrm = Vec3::Zero();
        p[axis] = side ? size[axis] / 2 : -size[axis] / 2;
        p[u] = rng.uniform(-size[u] / 2, size[u] / 2);
        p[v] = rng.uniform(-size[v] / 2, size[v] / 2);
        nrm[axis] = side ? 1.f : -1.f;
        s.push_back({p, nrm});
      }
    }
  return s;
}

inline std::vector<Surfel> can(float radius, float height, float spacing, Rng& rng) {
  std::vector<Surfel> s;
  const int side = static_cast<int>(2 * 3.14159f * radius * height / (spacing * spacing));
  for (int i = 0; i < side; ++i) {
    const float a = rng.uniform(0, 2 * 3.14159f);
    const Vec3 n(std::cos(a), std::sin(a), 0);
    s.push_back({Vec3(radius * n.x(), radius * n.y(), rng.uniform(-height / 2, height / 2)), n});
  }
  const int cap = static_cast<int>(3.14159f * radius * radius / (spacing * spacing));
  for (int end = 0; end < 2; ++end)
    for (int i = 0; i < cap; ++i) {
      const float x = rng.uniform(-radius, radius), y = rng.uniform(-radius, radius);
      if (x * x + y * y > radius * radius) { --i; continue; }
      s.push_back({Vec3(x, y, end ? height / 2 : -height / 2), Vec3(0, 0, end ? 1.f : -1.f)});
    }
  return s;
}

// The surfels facing a camera at `distance` in a random direction above the horizon.
inline Cloud view_of(const std::vector<Surfel>& shape, Rng& rng, float distance = 2.f) {
  const float az = rng.uniform(0, 2 * 3.14159f), el = rng.uniform(0.2f, 0.9f);
  const Vec3 camera = distance * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  Cloud c;
  c.sensor = camera;
  for (const Surfel& s : shape)
    if (s.n.dot(camera - s.p) > 0) c.points.push_back(s.p);
  return c;
}

inline std::vector<Surfel> synthetic_part(const std::string& category, Rng& rng, float spacing) {
  if (category == "ball") return ball(rng.uniform(0.04f, 0.08f), spacing, rng);
  if (category == "box") return box(Vec3(rng.uniform(0.1f, 0.25f), rng.uniform(0.1f, 0.25f), rng.uniform(0.08f, 0.2f)), spacing, rng);
  return can(rng.uniform(0.03f, 0.06f), rng.uniform(0.15f, 0.3f), spacing, rng);
}

// An object of 3 to 5 parts of its category's kind, side by side on a row (enough keypoints for
// every method, Bag of Graphs included, which needs 4 keypoints for a graph).
inline std::vector<Surfel> synthetic_shape(const std::string& category, Rng& rng, float spacing) {
  std::vector<Surfel> out;
  const int parts = 3 + static_cast<int>(rng.uniform(0, 2.999f));
  float x = 0;
  for (int i = 0; i < parts; ++i) {
    const auto part = synthetic_part(category, rng, spacing);
    float lo = 1e9f, hi = -1e9f;
    for (const Surfel& s : part) lo = std::min(lo, s.p.x()), hi = std::max(hi, s.p.x());
    const Vec3 offset(x - lo, rng.uniform(-0.05f, 0.05f), 0);
    for (const Surfel& s : part) out.push_back({s.p + offset, s.n});
    x += hi - lo + rng.uniform(0.03f, 0.08f);
  }
  for (Surfel& s : out) s.p.x() -= x / 2;
  return out;
}

inline const std::vector<std::string>& synthetic_categories() {
  static const std::vector<std::string> c = {"ball", "box", "can"};
  return c;
}

// objects_per_category objects x views_per_object views each; object ids are unique per seed.
inline std::vector<TrainingCloud> synthetic_views(int objects_per_category, int views_per_object, uint64_t seed,
                                                  float spacing = 0.008f) {
  std::vector<TrainingCloud> out;
  Rng rng(seed);
  for (const std::string& cat : synthetic_categories())
    for (int o = 0; o < objects_per_category; ++o) {
      const auto shape = synthetic_shape(cat, rng, spacing);
      for (int v = 0; v < views_per_object; ++v)
        out.push_back({cat, cat + "-" + std::to_string(seed) + "-" + std::to_string(o), view_of(shape, rng)});
    }
  return out;
}

// Training parameters for the synthetic problem's small models: every method, with small codebooks,
// trained in seconds.
inline TrainParams small_params() {
  TrainParams p;
  p.methods.assign(std::begin(kAllMethods), std::end(kAllMethods));
  p.bok_clusters = 12;
  p.bog_keypoint_clusters = 3;
  p.bog_volume_clusters = 2;
  p.kgh_clusters = 3;
  p.kgh_distance_bins = 4;
  p.decision.neighbours = 3;
  return p;
}

}  // namespace glimpse::test
