// A depth camera's frame made by hand for the scene tests and benchmark: a pinhole camera's rays cast
// analytically at a floor (z = 0), a wall, and boxes, cylinders and spheres standing on the floor. The
// frame is organised (row after row, NaN where a ray hits nothing), with Gaussian depth noise; each
// object's visible points give its true box. World coordinates, z up.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "glimpse/cloud.h"

namespace glimpse::test {

struct SceneShape {
  enum Kind { kBox, kCylinder, kSphere } kind;
  Vec3 base;  // the centre of its foot on the floor
  Vec3 size;  // box: its sides; cylinder: radius, -, height; sphere: radius
};

struct SyntheticScene {
  Cloud frame;
  std::vector<Bounds> truth;  // per shape, its visible points
};

namespace detail {

constexpr float kMiss = std::numeric_limits<float>::infinity();

// The ray o + t d (t > 0) against each kind of surface: the nearest t, kMiss when none.
inline float hit_box(const Vec3& o, const Vec3& d, const Vec3& lo, const Vec3& hi) {
  float t0 = 0, t1 = kMiss;
  for (int a = 0; a < 3; ++a) {
    float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  return t0 <= t1 && t0 > 0 ? t0 : kMiss;
}
inline float hit_sphere(const Vec3& o, const Vec3& d, const Vec3& c, float r) {
  const Vec3 oc = o - c;
  const float b = oc.dot(d), disc = b * b - d.squaredNorm() * (oc.squaredNorm() - r * r);
  if (disc < 0) return kMiss;
  const float t = (-b - std::sqrt(disc)) / d.squaredNorm();
  return t > 0 ? t : kMiss;
}
inline float hit_cylinder(const Vec3& o, const Vec3& d, const Vec3& base, float r, float h) {
  float best = kMiss;
  const float a = d.x() * d.x() + d.y() * d.y(), ox = o.x() - base.x(), oy = o.y() - base.y();
  const float b = ox * d.x() + oy * d.y(), c = ox * ox + oy * oy - r * r, disc = b * b - a * c;
  if (a > 0 && disc >= 0) {
    const float t = (-b - std::sqrt(disc)) / a, z = o.z() + t * d.z();
    if (t > 0 && z >= 0 && z <= h) best = t;
  }
  if (d.z() != 0) {  // the top
    const float t = (h - o.z()) / d.z();
    const Vec3 p = o + t * d;
    if (t > 0 && (p.x() - base.x()) * (p.x() - base.x()) + (p.y() - base.y()) * (p.y() - base.y()) <= r * r) best = std::min(best, t);
  }
  return best;
}
inline float hit_shape(const Vec3& o, const Vec3& d, const SceneShape& s) {
  switch (s.kind) {
    case SceneShape::kBox:
      return hit_box(o, d, s.base - Vec3(s.size.x() / 2, s.size.y() / 2, 0), s.base + Vec3(s.size.x() / 2, s.size.y() / 2, s.size.z()));
    case SceneShape::kCylinder: return hit_cylinder(o, d, s.base, s.size.x(), s.size.z());
    case SceneShape::kSphere: return hit_sphere(o, d, s.base + Vec3(0, 0, s.size.x()), s.size.x());
  }
  return kMiss;
}

}  // namespace detail

// The room: a floor 2 * half_width wide up to a wall at y = wall_y, wall_height tall.
struct Room {
  float half_width = 2.f, wall_y = 4.f, wall_height = 2.f;
};

// A 57 x 43 degree camera of width x height pixels at `sensor` looking at `target`; depth noise
// noise_m along each ray.
inline SyntheticScene render_scene(const Room& room, const std::vector<SceneShape>& shapes, const Vec3& sensor,
                                   const Vec3& target, int width = 640, int height = 480, float noise_m = 0.002f,
                                   uint32_t seed = 1) {
  const Vec3 forward = (target - sensor).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = right.cross(forward);
  const float fx = 0.5f * float(width) / std::tan(0.5f * 57.f * std::numbers::pi_v<float> / 180.f);
  const float fy = 0.5f * float(height) / std::tan(0.5f * 43.f * std::numbers::pi_v<float> / 180.f);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, noise_m);
  SyntheticScene out;
  out.frame.sensor = sensor;
  std::vector<Points> seen(shapes.size());
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const Vec3 d = (forward + ((float(u) + 0.5f - 0.5f * float(width)) / fx) * right +
                      ((0.5f * float(height) - float(v) - 0.5f) / fy) * up).normalized();
      float t = detail::kMiss;
      int owner = -1;
      if (d.z() < 0) {  // the floor
        const float tf = -sensor.z() / d.z();
        const Vec3 p = sensor + tf * d;
        if (std::abs(p.x()) <= room.half_width && p.y() <= room.wall_y) t = tf;
      }
      if (d.y() > 0) {  // the wall
        const float tw = (room.wall_y - sensor.y()) / d.y();
        const Vec3 p = sensor + tw * d;
        if (tw < t && std::abs(p.x()) <= room.half_width && p.z() >= 0 && p.z() <= room.wall_height) t = tw;
      }
      for (size_t k = 0; k < shapes.size(); ++k) {
        const float ts = detail::hit_shape(sensor, d, shapes[k]);
        if (ts < t) t = ts, owner = int(k);
      }
      if (!std::isfinite(t)) {
        out.frame.points.push_back(Vec3::Constant(std::numeric_limits<float>::quiet_NaN()));
        continue;
      }
      out.frame.points.push_back(sensor + (t + noise(rng)) * d);
      if (owner >= 0) seen[size_t(owner)].push_back(out.frame.points.back());
    }
  for (const Points& p : seen) out.truth.push_back(bounds(p));
  return out;
}

// A room-sized 640 x 480 frame: four objects apart from each other on the floor, the camera 1.3 m up
// looking 30 degrees down.
inline SyntheticScene four_object_scene(uint32_t seed = 1, int width = 640, int height = 480) {
  const std::vector<SceneShape> shapes = {{SceneShape::kBox, Vec3(-0.7f, 1.9f, 0), Vec3(0.3f, 0.2f, 0.4f)},
                                          {SceneShape::kCylinder, Vec3(-0.15f, 2.3f, 0), Vec3(0.1f, 0, 0.35f)},
                                          {SceneShape::kSphere, Vec3(0.4f, 1.7f, 0), Vec3(0.15f, 0, 0)},
                                          {SceneShape::kBox, Vec3(0.9f, 2.6f, 0), Vec3(0.25f, 0.25f, 0.25f)}};
  return render_scene(Room{}, shapes, Vec3(0, 0, 1.3f), Vec3(0, 2.25f, 0), width, height, 0.002f, seed);
}

}  // namespace glimpse::test
