#include "glimpse/geometry/boundaries.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace glimpse {

namespace {

// A number that orders directions (a, b) as atan2(b, a) does, in (-2, 2], without the arctangent.
float pseudo_angle(float a, float b) {
  const float s = std::abs(a) + std::abs(b);
  if (s == 0) return 0;
  const float t = a / s;
  return b >= 0 ? 1 - t : t - 1;
}

}  // namespace

bool is_boundary_point(const NeighbourIndex& tree, uint32_t index, const Vec3& normal, float r, float max_gap_rad,
                       std::vector<Neighbour>& nb) {
  const Points& pts = tree.points();
  tree.radius(pts[index], r, nb);
  if (nb.size() < 4 || !normal.allFinite() || normal.isZero()) return true;
  const Vec3 u = normal.unitOrthogonal();
  const Vec3 v = normal.cross(u);
  struct Direction {
    float key, a, b;
  };
  thread_local std::vector<Direction> dirs;
  dirs.clear();
  for (const Neighbour& q : nb) {
    if (q.index == index) continue;
    const Vec3 d = pts[q.index] - pts[index];
    float a = d.dot(u), b = d.dot(v);
    if (a == 0 && b == 0) a = 1;  // straight above the point: angle 0, as atan2(0, 0)
    dirs.push_back({pseudo_angle(a, b), a, b});
  }
  if (dirs.size() < 3) return true;
  std::sort(dirs.begin(), dirs.end(), [](const Direction& x, const Direction& y) { return x.key < y.key; });
  if (dirs.front().key == dirs.back().key) return true;  // one direction only: the gap is the full turn
  if (!(max_gap_rad < std::numbers::pi_v<float>)) {
    // Gaps beyond a half turn: measure them (the usual threshold, a quarter turn, never comes here).
    auto angle = [](const Direction& x) { return std::atan2(x.b, x.a); };
    float gap = angle(dirs.front()) + 2.f * std::numbers::pi_v<float> - angle(dirs.back());
    for (size_t i = 1; i < dirs.size(); ++i) gap = std::max(gap, angle(dirs[i]) - angle(dirs[i - 1]));
    return gap > max_gap_rad;
  }
  // Does the counter-clockwise angle from one direction to the next exceed theta (< pi)? Told from
  // cross and dot products and the pseudo-angle step (4 is a full turn) instead of arctangents.
  const float cos_max = std::cos(max_gap_rad), cos_sq = cos_max * cos_max;
  auto gap_exceeds = [&](const Direction& x, const Direction& y, float key_step) {
    const float cross = x.a * y.b - x.b * y.a, dot = x.a * y.a + x.b * y.b;
    if (dot > 0 && key_step > 2) return true;   // nearly a full turn
    if (cross < 0) return dot <= 0;             // beyond a half turn, or rounding of a zero step
    // dot < cos(theta) |x| |y|, squared so no root is needed.
    const float bound = cos_sq * (x.a * x.a + x.b * x.b) * (y.a * y.a + y.b * y.b);
    return cos_max >= 0 ? dot < 0 || dot * dot < bound : dot < 0 && dot * dot > bound;
  };
  if (gap_exceeds(dirs.back(), dirs.front(), dirs.front().key + 4 - dirs.back().key)) return true;
  for (size_t i = 1; i < dirs.size(); ++i)
    if (gap_exceeds(dirs[i - 1], dirs[i], dirs[i].key - dirs[i - 1].key)) return true;
  return false;
}

}  // namespace glimpse
