#include "glimpse/features/keypoints.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace glimpse {

std::vector<Keypoint> characteristic_scale_keypoints(const NeighbourIndex& tree, const std::vector<LocalSurface>& surfaces,
                                                     float r, const KeypointParams& params, KeypointStats* stats,
                                                     BoundaryMemo* memo) {
  KeypointStats st;
  std::vector<Keypoint> keypoints;
  const Points& pts = tree.points();
  const bool capped = params.max_characteristic_radius_m > 0 || params.max_radius_supports > 0;
  const float max_radius = params.max_characteristic_radius_m > 0 ? params.max_characteristic_radius_m
                           : capped ? params.max_radius_supports * r
                                    : std::numeric_limits<float>::infinity();
  st.max_radius_m = capped ? max_radius : 0;
  // rho1 <= max_radius  <=>  lambda_min >= 4 / max_radius^2 (eq. 3); rho1 must be finite in any case.
  const float lambda_threshold = capped ? 4.f / (max_radius * max_radius) : 0.f;
  const bool harris = params.response == KeypointResponse::kHarris;
  auto response = [&](uint32_t i) { return harris ? surfaces[i].harris_response : surfaces[i].lambda_min; };

  std::vector<uint32_t> candidates;
  std::vector<Neighbour> near, scratch;
  for (uint32_t i = 0; i < surfaces.size(); ++i) {
    const LocalSurface& s = surfaces[i];
    if (!s.valid || !(s.lambda_min > 0) || s.lambda_min < lambda_threshold) continue;
    if (harris) {
      // A Harris keypoint is a positive local maximum of the response within r (ties: the lower index).
      if (!(s.harris_response > 0)) continue;
      tree.radius(pts[i], r, near);
      const bool is_max = std::none_of(near.begin(), near.end(), [&](const Neighbour& q) {
        const LocalSurface& o = surfaces[q.index];
        return q.index != i && o.valid &&
               (o.harris_response > s.harris_response || (o.harris_response == s.harris_response && q.index < i));
      });
      if (!is_max) continue;
    }
    candidates.push_back(i);
  }
  std::sort(candidates.begin(), candidates.end(), [&](uint32_t a, uint32_t b) {
    if (response(a) != response(b)) return response(a) > response(b);
    return a < b;
  });
  st.candidates = candidates.size();

  // Accepted keypoints in a grid of cells as large as the largest claim, so "is this candidate inside
  // an accepted keypoint's sphere" looks at 27 cells, not at every point of the cloud. Without a cap on
  // rho1 a claim has no bound: every accepted keypoint is looked at.
  const float claim_floor = params.claim_min_supports * r;
  const float claim_max = std::max(max_radius, claim_floor);
  auto cell_of = [&](const Vec3& p) { return cell_key(p, claim_max); };
  std::unordered_map<CellKey, std::vector<uint32_t>, CellKeyHash> accepted;  // cell -> keypoint slots
  auto inside_claim = [&](uint32_t k, const Vec3& p) {
    const float claim = std::max(keypoints[k].characteristic_radius, claim_floor);
    return (keypoints[k].position - p).squaredNorm() <= claim * claim;
  };
  auto claimed = [&](const Vec3& p) {
    // A handful of keypoints (the usual case) are cheaper to scan than 27 cells to look up.
    if (keypoints.size() <= 64 || !capped) {
      for (uint32_t k = 0; k < keypoints.size(); ++k)
        if (inside_claim(k, p)) return true;
      return false;
    }
    const CellKey c = cell_of(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = accepted.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == accepted.end()) continue;
          for (uint32_t k : it->second)
            if (inside_claim(k, p)) return true;
        }
    return false;
  };

  BoundaryMemo local;
  BoundaryMemo& m = memo ? *memo : local;
  if (params.exclude_boundary) {
    m.boundary.resize(pts.size(), -1);
    m.touches_boundary.resize(pts.size(), -1);
  }
  const float band = params.boundary_band_supports * r;
  const float boundary_radius = params.boundary_radius_supports * r;
  auto on_boundary = [&](uint32_t i) {
    if (m.boundary[i] < 0) {
      const Vec3& n = surfaces[i].valid ? surfaces[i].normal : Vec3::Zero();
      m.boundary[i] = is_boundary_point(tree, i, n, boundary_radius, params.boundary_gap_rad, scratch) ? 1 : 0;
    }
    return m.boundary[i] == 1;
  };
  auto touches_boundary = [&](uint32_t c) {
    if (m.touches_boundary[c] < 0) {
      if (band > 0) {
        tree.radius(pts[c], band, near);
        m.touches_boundary[c] =
            std::any_of(near.begin(), near.end(), [&](const Neighbour& q) { return on_boundary(q.index); });
      } else {
        m.touches_boundary[c] = on_boundary(c);
      }
    }
    return m.touches_boundary[c] == 1;
  };

  for (uint32_t c : candidates) {
    // The keypoint claims the sphere of its characteristic radius: no other keypoint inside it (eq. 3).
    if (claimed(pts[c])) continue;
    if (params.exclude_boundary && touches_boundary(c)) {
      ++st.boundary_rejected;
      continue;
    }
    const LocalSurface& s = surfaces[c];
    keypoints.push_back({c, pts[c], characteristic_radius(s.lambda_min), s.lambda_min, s.lambda_max});
    if (capped) accepted[cell_of(pts[c])].push_back(static_cast<uint32_t>(keypoints.size() - 1));
    if (params.max_keypoints && keypoints.size() >= params.max_keypoints) break;
  }
  if (stats) *stats = st;
  return keypoints;
}

}  // namespace glimpse
