// Procedural shapes for the five categories of sec. 3.4, built from evenly tessellated primitives
// (zoo_builder.h); chairs and tables are in zoo_furniture.cpp.
#include "glimpse/views/zoo.h"

#include <algorithm>
#include <cmath>
#include <new>

#include "glimpse/views/dataset.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/placement.h"
#include "views/zoo_builder.h"

namespace glimpse {
namespace zoo_internal {

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

// ---- angular machine parts; size ~1 before scaling ----
// A bolt ring: a short tube of radius `rad`, `height` tall, with a hole.
void boss(Builder& b, const Vec3& at, float rad, float height, float hole) {
  b.extrusion(at, Mat3::Identity(), [rad](float) { return rad; }, rad, height, hole);
}

// An L, T (t_or_u, half the time) or U (the other half) bracket with bolt rings and gussets.
void bracket(Builder& b, Rng& r, bool t_or_u) {
  const float len = r.uniform(0.6f, 1.0f), wid = r.uniform(0.3f, 0.7f), th = r.uniform(0.05f, 0.14f);
  const float wall = r.uniform(0.3f, 0.9f);
  b.box(Vec3(0, 0, th / 2), Vec3(len, wid, th));
  std::vector<float> walls = {-len / 2 + th / 2};       // L
  if (t_or_u) walls = r.chance(0.5) ? std::vector<float>{0.f}  // T
                                        : std::vector<float>{-len / 2 + th / 2, len / 2 - th / 2};  // U
  for (float x : walls) b.box(Vec3(x, 0, wall / 2), Vec3(th, wid, wall));
  if (r.chance(0.6))  // gussets in the corner of the first wall
    for (float sy : {-1.f, 1.f})
      b.beam(Vec3(walls[0] + th / 2, sy * wid * 0.35f, wall * 0.5f),
             Vec3(walls[0] + th / 2 + wall * 0.45f, sy * wid * 0.35f, th), th * 0.6f, th * 0.6f);
  const int holes = r.integer(1, 4);
  for (int k = 0; k < holes; ++k)
    boss(b, Vec3(-len / 2 + len * (k + 1.2f) / (holes + 1), r.uniform(-wid / 4, wid / 4), th + 0.02f), 0.06f, 0.04f, 0.03f);
}

// A flange: ring, hub, bolt circle.
void flange(Builder& b, Rng& r) {
  const Mat3 I = Mat3::Identity();
  const float R = 0.5f, hole = R * r.uniform(0.25f, 0.45f), th = r.uniform(0.06f, 0.15f);
  const int nb = r.integer(4, 8);
  const bool square = r.chance(0.4);
  b.extrusion(Vec3(0, 0, th / 2), I, [R, square](float a) {
    return square ? R / std::max(std::abs(std::cos(a)), std::abs(std::sin(a))) * 0.8f : R;
  }, R, th, hole, 1, 32);
  b.extrusion(Vec3(0, 0, th), I, [hole](float) { return hole * 1.5f; }, hole * 1.5f, r.uniform(0.3f, 0.7f), hole);
  for (int k = 0; k < nb; ++k) {
    const float a = 2 * kPi * k / nb;
    boss(b, Vec3(0.78f * R * std::cos(a), 0.78f * R * std::sin(a), th + 0.025f), 0.05f, 0.05f, 0.025f);
  }
}

// A spur gear (prism approximation), maybe compound.
void spur_gear(Builder& b, Rng& r) {
  const Mat3 I = Mat3::Identity();
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
}

// A stepped shaft with a key and a collar, lying along x.
void stepped_shaft(Builder& b, Rng& r) {
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
}

// A stepped or slotted block.
void slotted_block(Builder& b, Rng& r) {
  const float L = r.uniform(0.6f, 1.0f), W = r.uniform(0.3f, 0.7f), H = r.uniform(0.1f, 0.3f);
  b.box(Vec3(0, 0, H / 2), Vec3(L, W, H));
  const int n = r.integer(1, 3);
  for (int k = 0; k < n; ++k) {
    const float bl = L * r.uniform(0.15f, 0.4f), bh = r.uniform(0.1f, 0.35f);
    const float bx = r.uniform(-L / 2 + bl / 2, L / 2 - bl / 2);
    if (r.chance(0.5)) b.box(Vec3(bx, 0, H + bh / 2), Vec3(bl, W, bh));  // full-width step
    else for (float s : {-1.f, 1.f}) b.box(Vec3(bx, s * W * 0.35f, H + bh / 2), Vec3(bl, W * 0.3f, bh));  // slot
  }
  if (r.chance(0.5)) boss(b, Vec3(L * 0.3f, 0, H + 0.03f), 0.08f, 0.06f, 0.04f);
}

// A hex bolt with threads, or a hex nut.
void fastener(Builder& b, Rng& r) {
  const Mat3 I = Mat3::Identity();
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
}

// A pipe fitting: a tee or an elbow, with end flanges.
void pipe_fitting(Builder& b, Rng& r) {
  const Mat3 I = Mat3::Identity();
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

void mechanic(Builder& b, Rng& r) {
  const int style = r.integer(0, 7);
  switch (style) {
    case 0:
    case 1: return bracket(b, r, style == 1);
    case 2: return flange(b, r);
    case 3: return spur_gear(b, r);
    case 4: return stepped_shaft(b, r);
    case 5: return slotted_block(b, r);
    case 6: return fastener(b, r);
    default: return pipe_fitting(b, r);
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

}  // namespace zoo_internal

using namespace zoo_internal;

namespace {

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
  for (const std::string& category : zoo_categories()) {
    const bool any_pose = category_size(category).any_pose;
    size_t made = 0;
    for (size_t i = 0; i < objects_per_category; ++i) {
      const uint64_t s = splitmix64(seed * 0x9E3779B97F4A7C15ull + i);
      Expected<Mesh> mesh = make_zoo_shape(category, s, options);
      if (mesh) zoo.push_back({category, s, std::move(*mesh), std::to_string(made++), any_pose});
    }
  }
  return zoo;
}

}  // namespace glimpse
