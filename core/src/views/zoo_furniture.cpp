// The zoo's furniture (zoo.h): chairs and tables in metres, from the primitives of zoo_builder.h.
#include <algorithm>
#include <cmath>

#include "views/zoo_builder.h"

namespace glimpse::zoo_internal {

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

}  // namespace glimpse::zoo_internal
