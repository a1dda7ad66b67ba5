#include "glimpse/geometry/frame_cut.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace glimpse {

namespace {
constexpr float kDeg = std::numbers::pi_v<float> / 180.f;

bool valid_fov(float deg) { return deg > 0 && deg < 180; }
}  // namespace

FrameCut frame_cut(const Cloud& cloud, const FrameCutParams& params) {
  FrameCut cut;
  if (!cloud.sensor || !cloud.frame || cloud.points.empty()) return cut;
  const CameraFrame& f = *cloud.frame;
  if (!valid_fov(f.fov_h_deg) || !valid_fov(f.fov_v_deg) || !(f.axis.norm() > 0)) return cut;
  const Vec3 axis = f.axis.normalized();
  Vec3 right = axis.cross(f.up);
  if (!(right.norm() > 1e-6f)) return cut;  // up along the axis: no image orientation
  right.normalize();
  const Vec3 up = right.cross(axis);
  const float half_u = std::tan(0.5f * f.fov_h_deg * kDeg), half_v = std::tan(0.5f * f.fov_v_deg * kDeg);
  const float edge_u = half_u * (1 - params.edge_share), edge_v = half_v * (1 - params.edge_share);
  size_t on[4] = {0, 0, 0, 0};  // top, bottom, left, right
  for (const Vec3& p : cloud.points) {
    if (!p.allFinite()) continue;
    const Vec3 d = p - *cloud.sensor;
    const float depth = d.dot(axis);
    if (!(depth > 0)) continue;
    const float u = d.dot(right) / depth, v = d.dot(up) / depth;
    const bool edge[4] = {v >= edge_v, v <= -edge_v, u <= -edge_u, u >= edge_u};
    for (int k = 0; k < 4; ++k) on[k] += edge[k];
  }
  cut.top = on[0] >= params.min_points, cut.bottom = on[1] >= params.min_points;
  cut.left = on[2] >= params.min_points, cut.right = on[3] >= params.min_points;
  return cut;
}

std::vector<std::string> frame_edges(const FrameCut& cut) {
  std::vector<std::string> out;
  const std::pair<bool, const char*> edges[] = {{cut.top, "top"}, {cut.bottom, "bottom"}, {cut.left, "left"}, {cut.right, "right"}};
  for (const auto& [on, name] : edges)
    if (on) out.emplace_back(name);
  return out;
}

std::string describe(const FrameCut& cut) {
  std::string s;
  for (const std::string& edge : frame_edges(cut)) s += (s.empty() ? "" : ", ") + edge;
  return s;
}

}  // namespace glimpse
