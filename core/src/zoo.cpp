// Procedural shapes for the five categories of sec. 3.4, built from evenly tessellated primitives.
#include "glimpse/zoo.h"

#include "glimpse/spatial_hash.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <new>
#include <random>
#include <unordered_map>

#include "glimpse/dataset.h"
#include "glimpse/views.h"

namespace glimpse {
namespace {

constexpr float kPi = 3.14159265f;
using Mat3 = Eigen::Matrix3f;

Mat3 rot_x(float a) { return Eigen::AngleAxisf(a, Vec3::UnitX()).toRotationMatrix(); }
Mat3 rot_y(float a) { return Eigen::AngleAxisf(a, Vec3::UnitY()).toRotationMatrix(); }
Mat3 rot_z(float a) { return Eigen::AngleAxisf(a, Vec3::UnitZ()).toRotationMatrix(); }
float deg(float d) { return d * kPi / 180.f; }

// SplitMix64 (Steele, Lea & Flood 2014) to derive independent seeds.
uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

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

  void box(const Vec3& centre, const Vec3& size, const Mat3& rot = Mat3::Identity()) {
    for (int axis = 0; axis < 3; ++axis)
      for (float side : {-0.5f, 0.5f}) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        grid(steps(size[u]), steps(size[v]), [&](float s, float t) {
          Vec3 p;
          p[axis] = side * size[axis];
          p[u] = (s - 0.5f) * size[u];
          p[v] = (t - 0.5f) * size[v];
          return Vec3(centre + rot * p);
        });
      }
  }

  // A box of cross-section w x d from a to b (a beam, a leg, a plank).
  void beam(const Vec3& a, const Vec3& b, float w, float d, float roll = 0) {
    const Mat3 r = Eigen::Quaternionf::FromTwoVectors(Vec3::UnitZ(), b - a).toRotationMatrix() * rot_z(roll);
    box(0.5f * (a + b), Vec3(w, d, (b - a).norm()), r);
  }

  void ellipsoid(const Vec3& centre, const Vec3& radii, const Mat3& rot = Mat3::Identity()) {
    const float r = radii.maxCoeff();
    grid(steps(2 * kPi * r, 8), steps(kPi * r, 4), [&](float u, float v) {
      const float th = 2 * kPi * u, ph = kPi * (v - 0.5f);
      return Vec3(centre + rot * Vec3(radii.x() * std::cos(ph) * std::cos(th),
                                      radii.y() * std::cos(ph) * std::sin(th), radii.z() * std::sin(ph)));
    });
  }

  // Extruded outline r(theta) (star-shaped about the axis) along local z, centred, with an optional
  // round hole, and the top outline scaled by top_scale (cones, tapered legs).
  void extrusion(const Vec3& centre, const Mat3& rot, const std::function<float(float)>& radius, float r_max,
                 float height, float hole = 0, float top_scale = 1, int min_segments = 12) {
    const int nt = steps(2 * kPi * r_max, min_segments), nz = steps(height), nr = steps(r_max - hole);
    auto at = [&](float r, float th, float z) {
      return Vec3(centre + rot * Vec3(r * std::cos(th), r * std::sin(th), z));
    };
    auto scale = [&](float v) { return 1 + (top_scale - 1) * v; };
    grid(nt, nz, [&](float u, float v) {
      return at(radius(2 * kPi * u) * scale(v), 2 * kPi * u, (v - 0.5f) * height);
    });
    if (hole > 0)
      grid(nt, nz, [&](float u, float v) { return at(hole * scale(v), 2 * kPi * u, (v - 0.5f) * height); });
    for (float end : {0.f, 1.f})
      grid(nt, nr, [&](float u, float v) {
        const float th = 2 * kPi * u;
        return at(scale(end) * (hole + v * (radius(th) - hole)), th, (end - 0.5f) * height);
      });
  }

  // Closed frustum from a (radius ra) to b (radius rb).
  void frustum(const Vec3& a, const Vec3& b, float ra, float rb, float hole = 0) {
    const Mat3 r = Eigen::Quaternionf::FromTwoVectors(Vec3::UnitZ(), b - a).toRotationMatrix();
    const float rr = std::max(ra, 1e-4f);
    extrusion(0.5f * (a + b), r, [rr](float) { return rr; }, rr, (b - a).norm(), hole, rb / rr);
  }

  // Tapered capsule: a limb between two joints.
  void capsule(const Vec3& a, const Vec3& b, float ra, float rb) {
    frustum(a, b, ra, rb);
    ellipsoid(a, Vec3::Constant(ra));
    ellipsoid(b, Vec3::Constant(rb));
  }

  // Torus about local z (ring radius R, tube radius r), swept over `sweep` radians.
  void torus(const Vec3& centre, const Mat3& rot, float R, float r, float sweep = 2 * kPi) {
    grid(steps(sweep * (R + r), 6), steps(2 * kPi * r, 8), [&](float u, float v) {
      const float th = sweep * u, ph = 2 * kPi * v;
      const float rr = R + r * std::cos(ph);
      return Vec3(centre + rot * Vec3(rr * std::cos(th), rr * std::sin(th), r * std::sin(ph)));
    });
  }

  // Merges coincident vertices (seams, poles, shared box edges) and drops the collapsed triangles.
  Mesh finish() {
    const double q = 1e-3 * h_;
    std::unordered_map<CellKey, int, CellKeyHash> index;
    std::vector<int> remap(mesh_.vertices.size());
    Mesh out;
    for (size_t i = 0; i < mesh_.vertices.size(); ++i) {
      const Vec3& p = mesh_.vertices[i];
      const CellKey key{std::lround(p.x() / q), std::lround(p.y() / q), std::lround(p.z() / q)};  // nearest, not floor
      const auto [it, added] = index.emplace(key, int(out.vertices.size()));
      if (added) out.vertices.push_back(p);
      remap[i] = it->second;
    }
    for (const Eigen::Vector3i& f : mesh_.faces) {
      const Eigen::Vector3i g(remap[f[0]], remap[f[1]], remap[f[2]]);
      if (g[0] != g[1] && g[1] != g[2] && g[0] != g[2]) out.faces.push_back(g);
    }
    return out;
  }

 private:
  float h_;
  Mesh mesh_;
};

// ---- human: torso, head, limbs on a random skeleton pose; stature ~1 before scaling ----
void human(Builder& b, Rng& r) {
  const float leg = r.uniform(0.45f, 0.52f), thigh = leg * r.uniform(0.48f, 0.54f), shin = leg - thigh - 0.04f;
  const float torso_len = r.uniform(0.27f, 0.33f), shoulders = r.uniform(0.20f, 0.27f);
  const float hips = r.uniform(0.13f, 0.19f), depth = r.uniform(0.09f, 0.15f), head = r.uniform(0.11f, 0.14f);
  const float upper_arm = r.uniform(0.15f, 0.19f), forearm = r.uniform(0.13f, 0.16f), bulk = r.uniform(0.8f, 1.3f);
  const int style = r.integer(0, 4);  // stand, walk, arms up, arms out, free
  const float lean = style == 4 ? r.uniform(deg(-10), deg(45)) : r.uniform(deg(-5), deg(12));
  const Mat3 torso = rot_z(r.uniform(deg(-20), deg(20))) * rot_y(lean);
  const Vec3 pelvis(0, 0, leg), top = pelvis + torso * Vec3(0, 0, torso_len), down(0, 0, -1);
  b.ellipsoid(pelvis + torso * Vec3(0, 0, 0.04f), Vec3(depth * 0.5f, hips * 0.62f, 0.09f) * bulk, torso);
  b.ellipsoid(pelvis + torso * Vec3(0, 0, torso_len * 0.6f),
              Vec3(depth * 0.55f * bulk, shoulders * 0.5f, torso_len * 0.45f), torso);
  const Mat3 head_rot = torso * rot_y(r.uniform(deg(-25), deg(30))) * rot_x(r.uniform(deg(-20), deg(20)));
  const Vec3 neck_top = top + head_rot * Vec3(0, 0, 0.05f);
  b.capsule(top, neck_top, 0.028f * bulk, 0.025f * bulk);
  b.ellipsoid(neck_top + head_rot * Vec3(0.01f, 0, head * 0.5f), Vec3(head * 0.48f, head * 0.4f, head * 0.55f), head_rot);
  const float walk = style == 1 ? r.uniform(deg(15), deg(35)) : 0.f;
  for (float side : {-1.f, 1.f}) {
    float flex, abd, knee;  // hip flexion (foot forward), abduction (outward), knee bend (foot back)
    if (style == 4) flex = r.uniform(deg(-25), deg(60)), abd = r.uniform(0, deg(30)), knee = r.uniform(0, deg(70));
    else flex = side * walk + r.uniform(deg(-5), deg(5)), abd = r.uniform(0, deg(8)), knee = r.uniform(0, deg(12)) + (side < 0 ? walk : 0);
    const Mat3 hip_rot = rot_x(side * abd);
    const Vec3 hip = pelvis + torso * Vec3(0, side * hips * 0.3f, 0) - Vec3(0, 0, 0.03f);
    const Vec3 kn = hip + hip_rot * rot_y(-flex) * down * thigh;
    const Vec3 ankle = kn + hip_rot * rot_y(-flex + knee) * down * shin;
    b.capsule(hip, kn, 0.06f * bulk, 0.042f * bulk);
    b.capsule(kn, ankle, 0.04f * bulk, 0.026f);
    b.box(ankle + Vec3(0.06f, 0, -0.025f), Vec3(r.uniform(0.20f, 0.27f) * 0.6f, 0.08f, 0.05f), rot_z(side * r.uniform(0, deg(20))));
    float arm_abd, arm_flex, elbow;
    switch (style) {
      case 2: arm_abd = r.uniform(deg(110), deg(175)), arm_flex = r.uniform(deg(-10), deg(30)), elbow = r.uniform(0, deg(50)); break;
      case 3: arm_abd = r.uniform(deg(65), deg(100)), arm_flex = r.uniform(deg(-15), deg(40)), elbow = r.uniform(0, deg(60)); break;
      case 4: arm_abd = r.uniform(0, deg(170)), arm_flex = r.uniform(deg(-40), deg(120)), elbow = r.uniform(0, deg(130)); break;
      default: arm_abd = r.uniform(deg(4), deg(20)), arm_flex = -side * walk + r.uniform(deg(-10), deg(15)), elbow = r.uniform(0, deg(45));
    }
    const Vec3 shoulder = top + torso * Vec3(0, side * shoulders * 0.48f, -0.04f);
    const Mat3 arm = torso * rot_x(side * arm_abd);
    const Vec3 el = shoulder + arm * rot_y(-arm_flex) * down * upper_arm;
    const Vec3 fore_dir = arm * rot_y(-arm_flex - elbow) * down;
    const Vec3 wrist = el + fore_dir * forearm;
    b.capsule(shoulder, el, 0.037f * bulk, 0.03f * bulk);
    b.capsule(el, wrist, 0.029f * bulk, 0.022f);
    b.ellipsoid(wrist + fore_dir * 0.045f, Vec3(0.05f, 0.02f, 0.045f), arm * rot_y(-arm_flex - elbow));
  }
}

// ---- chair: seat, back, one of four bases; metres ----
void chair(Builder& b, Rng& r) {
  const float hs = r.uniform(0.40f, 0.50f), w = r.uniform(0.38f, 0.56f), d = r.uniform(0.38f, 0.55f);
  const float t = r.uniform(0.02f, 0.08f), hb = r.uniform(0.33f, 0.6f), tilt = r.uniform(0, deg(20));
  const int base = r.integer(0, 9);  // 0-4 four legs, 5-6 pedestal, 7 sled, 8-9 boxy sides
  if (r.chance(0.2) && base < 8)
    b.extrusion(Vec3(0, 0, hs - t / 2), Mat3::Identity(), [w](float) { return w / 2; }, w / 2, t);
  else
    b.box(Vec3(0, 0, hs - t / 2), Vec3(d, w, t));
  if (base <= 4) {
    const float lw = r.uniform(0.025f, 0.06f), inset = r.uniform(0, 0.05f), splay = r.uniform(0, 0.08f);
    const bool round_legs = r.chance(0.4);
    for (float sx : {-1.f, 1.f})
      for (float sy : {-1.f, 1.f}) {
        const Vec3 top(sx * (d / 2 - inset - lw / 2), sy * (w / 2 - inset - lw / 2), hs - t);
        const Vec3 foot = top + Vec3(sx * splay, sy * splay, -(hs - t));
        round_legs ? b.frustum(foot, top, lw * 0.4f, lw / 2) : b.beam(foot, top, lw, lw);
      }
    if (r.chance(0.5)) {
      const float z = r.uniform(0.08f, 0.25f), f = z / (hs - t) * splay;
      for (float sy : {-1.f, 1.f})
        b.beam(Vec3(-(d / 2 - inset) - f, sy * (w / 2 - inset + f), z), Vec3(d / 2 - inset + f, sy * (w / 2 - inset + f), z), 0.02f, 0.02f);
    }
  } else if (base <= 6) {
    const float col = r.uniform(0.025f, 0.045f), reach = r.uniform(0.24f, 0.34f);
    b.frustum(Vec3(0, 0, 0.07f), Vec3(0, 0, hs - t), col * 1.4f, col);
    const int feet = r.integer(4, 5);
    for (int k = 0; k < feet; ++k) {
      const Vec3 dir(std::cos(2 * kPi * k / feet), std::sin(2 * kPi * k / feet), 0);
      b.beam(Vec3(0, 0, 0.07f), dir * reach + Vec3(0, 0, 0.06f), 0.04f, 0.03f, 2 * kPi * k / feet);
      b.ellipsoid(dir * reach + Vec3(0, 0, 0.025f), Vec3::Constant(0.025f));
    }
  } else if (base == 7) {
    for (float sy : {-1.f, 1.f}) {
      const float y = sy * w * 0.45f;
      b.capsule(Vec3(-d / 2, y, 0.012f), Vec3(d / 2, y, 0.012f), 0.012f, 0.012f);
      b.capsule(Vec3(d / 2, y, 0.012f), Vec3(d * 0.35f, y, hs - t), 0.012f, 0.012f);
      b.capsule(Vec3(-d / 2, y, 0.012f), Vec3(-d * 0.4f, y, hs - t), 0.012f, 0.012f);
    }
  } else {
    const float side_t = r.uniform(0.04f, 0.14f), arm_h = r.uniform(0.12f, 0.25f);
    b.box(Vec3(0, 0, (hs - t) / 2), Vec3(d, w, hs - t));
    for (float sy : {-1.f, 1.f})
      b.box(Vec3(0, sy * (w + side_t) / 2, (hs + arm_h) / 2), Vec3(d, side_t, hs + arm_h));
  }
  // Back, leaning back by `tilt`, standing on the rear edge of the seat.
  const float bt = r.uniform(0.02f, 0.06f), bw = w * r.uniform(0.75f, 1.0f);
  const Mat3 back_rot = rot_y(-tilt);
  const Vec3 back_base(-d / 2 + bt / 2, 0, hs);
  auto at = [&](float y, float z) { return Vec3(back_base + back_rot * Vec3(0, y, z)); };
  const int back = r.integer(0, 3);  // panel, vertical slats, horizontal rails, panel + top roll
  if (back == 0 || back == 3) {
    b.box(at(0, hb / 2), Vec3(bt, bw, hb), back_rot);
    if (back == 3) b.frustum(at(-bw / 2, hb), at(bw / 2, hb), bt * 0.9f, bt * 0.9f);
  } else {
    for (float sy : {-1.f, 1.f}) b.beam(at(sy * bw / 2, -0.02f), at(sy * bw / 2, hb), 0.03f, 0.03f);
    const int n = r.integer(2, 5);
    for (int k = 0; k < n; ++k) {
      if (back == 1) {
        const float y = -bw / 2 + bw * (k + 1) / (n + 1);
        b.beam(at(y, hb * 0.15f), at(y, hb * 0.95f), bt * 0.6f, 0.03f);
      } else {
        const float z = hb * (0.35f + 0.6f * k / std::max(1, n - 1));
        b.beam(at(-bw / 2, z), at(bw / 2, z), bt * 0.6f, 0.05f);
      }
    }
  }
  if (base < 8 && r.chance(0.3)) {  // armrests
    const float ah = r.uniform(0.18f, 0.26f);
    for (float sy : {-1.f, 1.f}) {
      b.beam(Vec3(d * 0.3f, sy * w / 2, hs), Vec3(d * 0.3f, sy * w / 2, hs + ah), 0.03f, 0.03f);
      b.beam(Vec3(-d / 2, sy * w / 2, hs + ah), Vec3(d * 0.45f, sy * w / 2, hs + ah), 0.05f, 0.03f, kPi / 2);
    }
  }
}

// ---- table: top, and legs, pedestal or trestles; metres ----
void table(Builder& b, Rng& r) {
  const float h = r.uniform(0.70f, 0.80f), t = r.uniform(0.02f, 0.06f);
  const int shape = r.integer(0, 3);  // rectangle, square, round, oval
  float a = r.uniform(0.8f, 2.0f), c = r.uniform(0.6f, 1.0f);  // half-sizes after the switch
  if (shape == 1) c = a = r.uniform(0.6f, 1.1f);
  if (shape == 2) c = a = r.uniform(0.7f, 1.4f);
  if (shape == 3) a = r.uniform(1.0f, 1.8f), c = a * r.uniform(0.5f, 0.75f);
  a /= 2, c /= 2;
  const Vec3 top_c(0, 0, h - t / 2);
  if (shape >= 2) {
    b.extrusion(top_c, Mat3::Identity(), [a, c](float th) {
      return a * c / std::hypot(c * std::cos(th), a * std::sin(th));  // ellipse in polar form
    }, a, t);
  } else {
    b.box(top_c, Vec3(2 * a, 2 * c, t));
  }
  const float under = h - t;
  int support = r.integer(0, 1);  // 0 four legs, 1 pedestal, 2 trestles (rectangles), 3 three legs (round)
  if (shape == 0 && r.chance(0.3)) support = 2;
  if (shape == 2 && r.chance(0.35)) support = 3;
  if (support == 0) {
    const float lw = r.uniform(0.04f, 0.09f), in = r.uniform(0.03f, 0.12f), taper = r.uniform(0.5f, 1.0f);
    const bool round_legs = r.chance(0.4);
    const float k = shape >= 2 ? 0.7071f : 1.f;  // corners of the inscribed rectangle for ovals
    for (float sx : {-1.f, 1.f})
      for (float sy : {-1.f, 1.f}) {
        const Vec3 top(sx * (a * k - in), sy * (c * k - in), under);
        round_legs ? b.frustum(Vec3(top.x(), top.y(), 0), top, lw * taper / 2, lw / 2)
                   : b.beam(Vec3(top.x(), top.y(), 0), top, lw, lw);
      }
    if (r.chance(0.5))  // apron
      for (float s : {-1.f, 1.f}) {
        b.box(Vec3(s * (a * k - in), 0, under - 0.05f), Vec3(0.02f, 2 * (c * k - in), 0.1f));
        b.box(Vec3(0, s * (c * k - in), under - 0.05f), Vec3(2 * (a * k - in), 0.02f, 0.1f));
      }
    if (r.chance(0.25)) b.box(Vec3(0, 0, r.uniform(0.1f, 0.3f)), Vec3(2 * (a * k - in), 2 * (c * k - in), 0.02f));
  } else if (support == 1) {
    const float col = r.uniform(0.04f, 0.1f), foot = std::min(a, c) * r.uniform(0.5f, 0.8f);
    b.frustum(Vec3(0, 0, 0.03f), Vec3(0, 0, under), col * r.uniform(1.0f, 1.8f), col);
    if (r.chance(0.5)) {
      b.extrusion(Vec3(0, 0, 0.015f), Mat3::Identity(), [foot](float) { return foot; }, foot, 0.03f);
    } else {
      const int n = r.integer(3, 4);
      for (int k = 0; k < n; ++k) {
        const float th = 2 * kPi * k / n;
        b.beam(Vec3(0, 0, 0.04f), Vec3(foot * std::cos(th), foot * std::sin(th), 0.03f), 0.05f, 0.06f, th);
      }
    }
    if (a > 0.7f && shape == 0) b.frustum(Vec3(a * 0.5f, 0, 0.03f), Vec3(a * 0.5f, 0, under), col, col);
  } else if (support == 2) {
    const float x = a * r.uniform(0.6f, 0.85f), slab = r.uniform(0.03f, 0.08f);
    const bool a_frame = r.chance(0.5);
    for (float s : {-1.f, 1.f}) {
      if (a_frame) {
        for (float sy : {-1.f, 1.f}) b.beam(Vec3(s * x, sy * c * 0.8f, 0), Vec3(s * x, sy * c * 0.15f, under), slab, slab);
      } else {
        b.box(Vec3(s * x, 0, under / 2), Vec3(slab, 2 * c * r.uniform(0.5f, 0.85f), under));
      }
    }
    b.beam(Vec3(-x, 0, under * 0.35f), Vec3(x, 0, under * 0.35f), 0.05f, 0.05f);
  } else {
    const float lw = r.uniform(0.035f, 0.07f), rr = std::min(a, c) * 0.7f, splay = r.uniform(0, 0.15f);
    for (int k = 0; k < 3; ++k) {
      const Vec3 dir(std::cos(2 * kPi * k / 3), std::sin(2 * kPi * k / 3), 0);
      b.frustum(dir * (rr + splay), dir * rr + Vec3(0, 0, under), lw * 0.35f, lw / 2);
    }
  }
}

// ---- angular machine parts; size ~1 before scaling ----
void mechanic(Builder& b, Rng& r) {
  const Mat3 I = Mat3::Identity();
  auto boss = [&](const Vec3& at, float rad, float height, float hole) {  // hole-like ring
    b.extrusion(at, I, [rad](float) { return rad; }, rad, height, hole);
  };
  const int style = r.integer(0, 7);
  if (style == 0 || style == 1) {  // L / T / U bracket with bolt rings and gussets
    const float len = r.uniform(0.6f, 1.0f), wid = r.uniform(0.3f, 0.7f), th = r.uniform(0.05f, 0.14f);
    const float wall = r.uniform(0.3f, 0.9f);
    b.box(Vec3(0, 0, th / 2), Vec3(len, wid, th));
    std::vector<float> walls = {-len / 2 + th / 2};       // L
    if (style == 1) walls = r.chance(0.5) ? std::vector<float>{0.f}  // T
                                          : std::vector<float>{-len / 2 + th / 2, len / 2 - th / 2};  // U
    for (float x : walls) b.box(Vec3(x, 0, wall / 2), Vec3(th, wid, wall));
    if (r.chance(0.6))  // gussets in the corner of the first wall
      for (float sy : {-1.f, 1.f})
        b.beam(Vec3(walls[0] + th / 2, sy * wid * 0.35f, wall * 0.5f),
               Vec3(walls[0] + th / 2 + wall * 0.45f, sy * wid * 0.35f, th), th * 0.6f, th * 0.6f);
    const int holes = r.integer(1, 4);
    for (int k = 0; k < holes; ++k)
      boss(Vec3(-len / 2 + len * (k + 1.2f) / (holes + 1), r.uniform(-wid / 4, wid / 4), th + 0.02f), 0.06f, 0.04f, 0.03f);
  } else if (style == 2) {  // flange: ring, hub, bolt circle
    const float R = 0.5f, hole = R * r.uniform(0.25f, 0.45f), th = r.uniform(0.06f, 0.15f);
    const int nb = r.integer(4, 8);
    const bool square = r.chance(0.4);
    b.extrusion(Vec3(0, 0, th / 2), I, [R, square](float a) {
      return square ? R / std::max(std::abs(std::cos(a)), std::abs(std::sin(a))) * 0.8f : R;
    }, R, th, hole, 1, 32);
    b.extrusion(Vec3(0, 0, th), I, [hole](float) { return hole * 1.5f; }, hole * 1.5f, r.uniform(0.3f, 0.7f), hole);
    for (int k = 0; k < nb; ++k) {
      const float a = 2 * kPi * k / nb;
      boss(Vec3(0.78f * R * std::cos(a), 0.78f * R * std::sin(a), th + 0.025f), 0.05f, 0.05f, 0.025f);
    }
  } else if (style == 3) {  // spur gear (prism approximation), maybe compound
    const int teeth = r.integer(8, 28);
    const float R = 0.5f, depth = r.uniform(0.05f, 0.1f), th = r.uniform(0.08f, 0.3f), hole = r.uniform(0.06f, 0.16f);
    auto gear = [&](float z, float radius, float thick, int n) {
      b.extrusion(Vec3(0, 0, z), I, [radius, depth, n](float a) {
        const float p = a * n / (2 * kPi), f = p - std::floor(p);  // trapezoidal tooth profile
        const float up = std::clamp((f < 0.5f ? f : 1 - f) * 6.f - 0.5f, 0.f, 1.f);
        return radius - depth + depth * up;
      }, radius, thick, hole, 1, 10 * n);
    };
    gear(th / 2, R, th, teeth);
    if (r.chance(0.4)) gear(th + th * 0.4f, R * r.uniform(0.4f, 0.7f), th * 0.8f, std::max(6, teeth / 2));
    else b.extrusion(Vec3(0, 0, th), I, [hole](float) { return hole * 1.8f; }, hole * 1.8f, r.uniform(0.1f, 0.3f), hole);
  } else if (style == 4) {  // stepped shaft with a key and a collar, lying along x
    const int n = r.integer(2, 5);
    std::vector<float> len(n), rad(n);
    float total = 0;
    for (int k = 0; k < n; ++k) total += len[k] = r.uniform(0.15f, 0.45f), rad[k] = r.uniform(0.06f, 0.16f);
    float x = -total / 2;
    for (int k = 0; k < n; ++k) {
      b.frustum(Vec3(x, 0, 0), Vec3(x + len[k], 0, 0), rad[k], rad[k]);
      if (k == 0) b.box(Vec3(x + len[k] / 2, 0, rad[k]), Vec3(len[k] * 0.6f, rad[k] * 0.5f, rad[k] * 0.4f));
      x += len[k];
    }
    if (r.chance(0.5)) b.frustum(Vec3(-0.02f, 0, 0), Vec3(0.04f, 0, 0), 0.22f, 0.22f, 0.05f);
  } else if (style == 5) {  // stepped / slotted block
    const float L = r.uniform(0.6f, 1.0f), W = r.uniform(0.3f, 0.7f), H = r.uniform(0.1f, 0.3f);
    b.box(Vec3(0, 0, H / 2), Vec3(L, W, H));
    const int n = r.integer(1, 3);
    for (int k = 0; k < n; ++k) {
      const float bl = L * r.uniform(0.15f, 0.4f), bh = r.uniform(0.1f, 0.35f);
      const float bx = r.uniform(-L / 2 + bl / 2, L / 2 - bl / 2);
      if (r.chance(0.5)) b.box(Vec3(bx, 0, H + bh / 2), Vec3(bl, W, bh));  // full-width step
      else for (float s : {-1.f, 1.f}) b.box(Vec3(bx, s * W * 0.35f, H + bh / 2), Vec3(bl, W * 0.3f, bh));  // slot
    }
    if (r.chance(0.5)) boss(Vec3(L * 0.3f, 0, H + 0.03f), 0.08f, 0.06f, 0.04f);
  } else if (style == 6) {  // hex bolt with threads, or hex nut
    const float ap = r.uniform(0.15f, 0.25f);
    auto hex = [ap](float a) {
      const float s = std::fmod(a + kPi / 6, kPi / 3) - kPi / 6;
      return ap / std::cos(s);
    };
    if (r.chance(0.3)) {
      b.extrusion(Vec3(0, 0, ap * 0.45f), I, hex, ap * 1.16f, ap * 0.9f, ap * 0.55f, 1, 60);
    } else {
      const float shaft = r.uniform(0.5f, 0.9f), sr = ap * 0.6f, hh = ap * 0.7f;
      b.extrusion(Vec3(0, 0, hh / 2), I, hex, ap * 1.16f, hh, 0, 1, 60);
      b.frustum(Vec3(0, 0, hh), Vec3(0, 0, hh + shaft), sr, sr);
      const int threads = int(shaft / (sr * 0.35f) * r.uniform(0.4f, 0.8f));
      for (int k = 0; k < threads; ++k)
        b.torus(Vec3(0, 0, hh + shaft - (k + 0.5f) * sr * 0.35f), I, sr, sr * 0.12f);
    }
  } else {  // pipe fitting: tee or elbow with end flanges
    const float pr = r.uniform(0.12f, 0.2f), hole = pr * 0.7f, arm = r.uniform(0.3f, 0.5f);
    const Mat3 along_x = rot_y(kPi / 2);
    if (r.chance(0.5)) {
      b.extrusion(Vec3(0, 0, 0), along_x, [pr](float) { return pr; }, pr, 2 * arm, hole);
      b.extrusion(Vec3(0, 0, arm / 2), I, [pr](float) { return pr; }, pr, arm, hole);
    } else {
      b.torus(Vec3(0, 0, 0), I, arm, pr, kPi / 2);
      b.extrusion(Vec3(arm, -arm * 0.25f, 0), rot_x(kPi / 2), [pr](float) { return pr; }, pr, arm * 0.5f, hole);
    }
    if (r.chance(0.6)) b.extrusion(Vec3(-arm, 0, 0), along_x, [pr](float) { return pr * 1.6f; }, pr * 1.6f, 0.06f, hole);
  }
}

// ---- quadruped: body, neck, head, four jointed legs, tail; body length ~1 ----
void fourleg(Builder& b, Rng& r) {
  const float leg = r.uniform(0.3f, 1.1f), bw = r.uniform(0.1f, 0.22f), bh = r.uniform(0.12f, 0.26f);
  const float neck_len = r.uniform(0.1f, 0.75f), neck_a = r.uniform(deg(10), deg(80));
  const float lr = r.uniform(0.03f, 0.075f), body_z = leg + bh * 0.5f;
  b.ellipsoid(Vec3(0, 0, body_z), Vec3(0.5f, bw, bh));
  if (r.chance(0.5)) b.ellipsoid(Vec3(0.25f, 0, body_z + bh * 0.1f), Vec3(0.28f, bw * 1.15f, bh * 1.15f));
  const float gait = r.uniform(0, deg(22)), phase = r.uniform(0, 2 * kPi), knee = r.uniform(0, deg(35));
  int i = 0;
  for (float sx : {-1.f, 1.f})
    for (float sy : {-1.f, 1.f}) {
      const float swing = gait * std::sin(phase + kPi * 0.5f * i++);
      const Vec3 hip(sx * 0.33f, sy * bw * 0.55f, body_z - bh * 0.3f);
      const float up = (body_z - bh * 0.3f) * 0.5f;
      // Front legs nearly straight; hind legs in a Z (thigh forward, hock back).
      const float bend = sx > 0 ? 0.3f * knee : knee;
      const Vec3 kn = hip + rot_y(-swing - bend) * Vec3(0, 0, -up);
      const Vec3 foot = kn + rot_y(-swing + bend) * Vec3(0, 0, -up);
      b.capsule(hip, kn, lr * 1.3f, lr);
      b.capsule(kn, foot, lr, lr * 0.8f);
    }
  const Mat3 yaw = rot_z(r.uniform(deg(-35), deg(35)));
  const Vec3 neck0(0.42f, 0, body_z + bh * 0.3f);
  const Vec3 neck1 = neck0 + yaw * Vec3(std::cos(neck_a), 0, std::sin(neck_a)) * neck_len;
  b.capsule(neck0, neck1, r.uniform(0.06f, 0.12f), r.uniform(0.04f, 0.07f));
  const float hl = r.uniform(0.14f, 0.3f), head_a = neck_a - r.uniform(deg(50), deg(110));
  const Mat3 head_rot = yaw * rot_y(-head_a);
  const Vec3 head_c = neck1 + head_rot * Vec3(hl * 0.35f, 0, 0);
  b.ellipsoid(head_c, Vec3(hl * 0.5f, r.uniform(0.045f, 0.09f), r.uniform(0.05f, 0.09f)), head_rot);
  if (r.chance(0.5)) b.capsule(head_c, head_c + head_rot * Vec3(hl * 0.6f, 0, -0.01f), 0.05f, 0.035f);  // snout
  const float ear = r.uniform(0.03f, 0.12f);
  const bool horns = r.chance(0.25);
  for (float sy : {-1.f, 1.f}) {
    const Vec3 base = head_c + head_rot * Vec3(-hl * 0.2f, sy * 0.04f, 0.05f);
    if (horns) b.capsule(base, base + head_rot * Vec3(-0.08f, sy * 0.1f, 0.15f), 0.025f, 0.008f);
    else b.frustum(base, base + head_rot * Vec3(-0.02f, sy * 0.02f, ear), 0.025f, 0.004f);
  }
  Vec3 p(-0.48f, 0, body_z + bh * 0.2f);
  float ta = r.uniform(deg(-70), deg(60));
  const float curl = r.uniform(deg(-30), deg(30)), seg = r.uniform(0.03f, 0.2f), tr = r.uniform(0.012f, 0.045f);
  for (int k = 0; k < 3; ++k, ta += curl) {
    const Vec3 q = p + Vec3(-std::cos(ta), 0, std::sin(ta)) * seg;
    b.capsule(p, q, tr, tr * 0.8f);
    p = q;
  }
}

using Generator = void (*)(Builder&, Rng&);

struct CategoryDef {
  const char* name;
  Generator build;
};

constexpr CategoryDef kCategories[] = {
    {"human", human}, {"chair", chair}, {"table", table}, {"mechanic", mechanic}, {"fourleg", fourleg}};

}  // namespace

std::vector<std::string> zoo_categories() {
  std::vector<std::string> names;
  for (const CategoryDef& c : kCategories) names.emplace_back(c.name);
  return names;
}

Expected<Mesh> make_zoo_shape(std::string_view category, uint64_t seed, const ZooOptions& options) {
  const CategoryDef* def = nullptr;
  uint64_t salt = 0;
  for (const CategoryDef& c : kCategories)
    if (++salt, c.name == category) def = &c;
  if (!def) return invalid_argument("unknown zoo category '" + std::string(category) + "'");
  try {
    const uint64_t shape_seed = splitmix64(seed ^ splitmix64(salt));
    // A coarse pass measures the area; the next picks the spacing that gives about target_vertices
    // (an even grid has ~area / spacing^2 vertices). Same seed, same proportions in every pass.
    Builder coarse(0.05f);
    Rng r1(shape_seed);
    def->build(coarse, r1);
    const double area = surface_area(coarse.finish());
    const double target = double(std::max<size_t>(options.target_vertices, 100));
    double spacing = std::clamp(std::sqrt(area / target), 1e-3, 1.0);
    Mesh mesh;
    for (int pass = 0; pass < 3; ++pass) {  // small parts have minimum segment counts: correct
      Builder fine{float(spacing)};
      Rng r2(shape_seed);
      def->build(fine, r2);
      mesh = fine.finish();
      const double ratio = double(mesh.vertices.size()) / target;
      if (ratio < 1.25 && ratio > 0.8) break;
      spacing = std::clamp(spacing * std::sqrt(ratio), 1e-3, 1.0);
    }
    // A random yaw and a real-life size drawn in the category's range (sec. 3.4).
    Rng place(splitmix64(shape_seed + 1));
    const Mat3 yaw = rot_z(place.uniform(0, 2 * kPi));
    for (Vec3& v : mesh.vertices) v = yaw * v;
    const CategorySize size = category_size(def->name);
    const float target_m = place.uniform(size.min_m, size.max_m);
    mesh = size.measure == CategorySize::kHeight ? scale_to_height(std::move(mesh), target_m)
                                                 : scale_to_largest_extent(std::move(mesh), target_m);
    return place_on_ground(std::move(mesh));
  } catch (const std::bad_alloc&) {
    return resource_exhausted("zoo: out of memory building '" + std::string(category) + "'");
  }
}

std::vector<LabelledMesh> make_zoo(size_t objects_per_category, uint64_t seed, const ZooOptions& options) {
  std::vector<LabelledMesh> zoo;
  for (const std::string& category : zoo_categories())
    for (size_t i = 0; i < objects_per_category; ++i) {
      const uint64_t s = splitmix64(seed * 0x9E3779B97F4A7C15ull + i);
      Expected<Mesh> mesh = make_zoo_shape(category, s, options);
      if (mesh) zoo.push_back({category, s, std::move(*mesh)});
    }
  return zoo;
}

}  // namespace glimpse
