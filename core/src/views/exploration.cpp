// The top-to-bottom exploring sequence (sec. 4) and the protocol's stages.
#include "glimpse/views/exploration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>

namespace glimpse {

namespace {
// Before in the top-down order: higher, non-NaN before NaN (stable: ties keep their order).
bool above(const Points& points, uint32_t a, uint32_t b) {
  const float za = points[a].z(), zb = points[b].z();
  if (std::isnan(za) || std::isnan(zb)) return !std::isnan(za) && std::isnan(zb);
  return za > zb;
}
}  // namespace

std::vector<uint32_t> top_down_order(const Points& points) {
  std::vector<uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return above(points, a, b); });
  return order;
}

std::vector<uint32_t> highest_points(const Points& points, size_t count) {
  std::vector<uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  count = std::min(count, order.size());
  // Ties broken by index, as the stable sort does: the same set.
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(count), order.end(), [&](uint32_t a, uint32_t b) {
    return above(points, a, b) || (!above(points, b, a) && a < b);
  });
  order.resize(count);
  std::sort(order.begin(), order.end());
  return order;
}

Cloud reveal_top_down(const Cloud& cloud, size_t count) {
  const std::vector<uint32_t> order = top_down_order(cloud.points);
  Cloud out;
  out.sensor = cloud.sensor;
  out.frame = cloud.frame;
  count = std::min(count, order.size());
  out.points.reserve(count);
  for (size_t i = 0; i < count; ++i) out.points.push_back(cloud.points[order[i]]);
  return out;
}

std::string stage_name(const Stage& stage) {
  char buf[32];
  switch (stage.kind) {
    case StageKind::kFull: return "full";
    case StageKind::kKeypoints: std::snprintf(buf, sizeof buf, "%gkp", stage.value); return buf;
    case StageKind::kFraction: std::snprintf(buf, sizeof buf, "%g%%", 100.0 * stage.value); return buf;
  }
  return "?";
}

std::vector<Stage> paper_stages() {
  return {{StageKind::kFull, 0},       {StageKind::kKeypoints, 10}, {StageKind::kKeypoints, 25},
          {StageKind::kKeypoints, 55}, {StageKind::kFraction, 0.10}, {StageKind::kFraction, 0.20}};
}

size_t keypoint_prefix(const Points& view, std::vector<float> keypoint_heights, size_t k, float margin_m) {
  if (k == 0) return 0;
  if (keypoint_heights.size() < k) return view.size();
  std::nth_element(keypoint_heights.begin(), keypoint_heights.begin() + (k - 1), keypoint_heights.end(),
                   std::greater<float>());
  const float cut = keypoint_heights[k - 1] - std::max(0.f, margin_m);
  return static_cast<size_t>(
      std::count_if(view.begin(), view.end(), [cut](const Vec3& p) { return p.z() >= cut; }));
}

size_t fraction_prefix(size_t view_points, size_t full_cloud_points, double fraction) {
  const double n = std::round(std::max(0.0, fraction) * double(full_cloud_points));
  return std::min(view_points, static_cast<size_t>(n));
}

std::vector<size_t> exploration_grid(size_t max_keypoints, size_t step) {
  std::vector<size_t> grid;
  if (max_keypoints == 0) return grid;
  step = std::max<size_t>(1, step);
  grid.push_back(1);
  for (size_t k = step; k <= max_keypoints; k += step)
    if (k > grid.back()) grid.push_back(k);
  if (grid.back() != max_keypoints) grid.push_back(max_keypoints);
  return grid;
}

}  // namespace glimpse
