#include "glimpse/keypoints.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace glimpse {

std::vector<Keypoint> characteristic_scale_keypoints(const KdTree& tree, const std::vector<LocalSurface>& surfaces,
                                                     float r, const KeypointParams& params, KeypointStats* stats) {
  KeypointStats st;
  std::vector<Keypoint> keypoints;
  const Points& pts = tree.points();
  const float max_radius =
      params.max_characteristic_radius_m > 0 ? params.max_characteristic_radius_m : params.max_radius_supports * r;
  st.max_radius_m = max_radius;
  // rho1 <= max_radius  <=>  lambda_min >= 4 / max_radius^2 (eq. 3).
  const float lambda_threshold = 4.f / (max_radius * max_radius);

  std::vector<uint32_t> candidates;
  for (uint32_t i = 0; i < surfaces.size(); ++i)
    if (surfaces[i].valid && surfaces[i].lambda_min >= lambda_threshold) candidates.push_back(i);
  std::sort(candidates.begin(), candidates.end(), [&](uint32_t a, uint32_t b) {
    if (surfaces[a].lambda_min != surfaces[b].lambda_min) return surfaces[a].lambda_min > surfaces[b].lambda_min;
    return a < b;
  });
  st.candidates = candidates.size();

  std::vector<uint8_t> suppressed(pts.size(), 0);
  std::vector<int8_t> boundary(params.exclude_boundary ? pts.size() : 0, -1);  // -1: not yet known
  std::vector<Neighbour> near, scratch;
  auto on_boundary = [&](uint32_t i) {
    if (boundary[i] < 0) {
      const Vec3& n = surfaces[i].valid ? surfaces[i].normal : Vec3::Zero();
      boundary[i] = is_boundary_point(tree, i, n, r, params.boundary_gap_rad, scratch) ? 1 : 0;
    }
    return boundary[i] == 1;
  };

  for (uint32_t c : candidates) {
    if (suppressed[c]) continue;
    if (params.exclude_boundary) {
      tree.radius(pts[c], r, near);
      const bool touches = std::any_of(near.begin(), near.end(), [&](const Neighbour& q) { return on_boundary(q.index); });
      if (touches) {
        ++st.boundary_rejected;
        continue;
      }
    }
    const LocalSurface& s = surfaces[c];
    Keypoint kp{c, pts[c], characteristic_radius(s.lambda_min), s.lambda_min, s.lambda_max};
    keypoints.push_back(kp);
    if (params.max_keypoints && keypoints.size() >= params.max_keypoints) break;
    // The keypoint claims the sphere of its characteristic radius: no other keypoint inside it. Below
    // the support radius r curvature is not resolved, so the claim is never smaller than r.
    tree.radius(pts[c], std::max(kp.characteristic_radius, r), near);
    for (const Neighbour& q : near) suppressed[q.index] = 1;
  }
  if (stats) *stats = st;
  return keypoints;
}

}  // namespace glimpse
