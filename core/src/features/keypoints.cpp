// Characteristic-scale keypoints (sec. 2.2, 3.2.2): candidates by their response, each accepted unless an
// accepted keypoint's sphere of characteristic radius claims it (eq. 3) or it touches the view's boundary.
#include "glimpse/features/keypoints.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>

namespace glimpse {

namespace {

// The points that may become keypoints, strongest response first (ties: the lower index): a valid
// surface whose lambda_min is positive and at least `lambda_threshold`; with the Harris response, a
// positive local maximum of it within r (ties: the lower index).
std::vector<uint32_t> keypoint_candidates(const NeighbourIndex& tree, const std::vector<LocalSurface>& surfaces, float r,
                                          float lambda_threshold, bool harris) {
  const Points& pts = tree.points();
  auto response = [&](uint32_t i) { return harris ? surfaces[i].harris_response : surfaces[i].lambda_min; };
  std::vector<uint32_t> candidates;
  std::vector<Neighbour> near;
  for (uint32_t i = 0; i < surfaces.size(); ++i) {
    const LocalSurface& s = surfaces[i];
    if (!s.valid || !(s.lambda_min > 0) || s.lambda_min < lambda_threshold) continue;
    if (harris) {
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
  return candidates;
}

// The spheres accepted keypoints claim (eq. 3: each claims its characteristic radius, at least
// claim_floor), in a grid of cells as large as the largest claim, so "is this point inside an accepted
// keypoint's sphere" looks at 27 cells, not at every keypoint. Without a cap on rho1 a claim has no
// bound: every accepted keypoint is looked at.
class Claims {
 public:
  Claims(const std::vector<Keypoint>& keypoints, float claim_floor, float claim_max, bool capped)
      : keypoints_(keypoints), claim_floor_(claim_floor), claim_max_(claim_max), capped_(capped) {}

  void add(uint32_t slot) {
    if (capped_) accepted_[cell_key(keypoints_[slot].position, claim_max_)].push_back(slot);
  }

  bool claimed(const Vec3& p) const {
    // A handful of keypoints (the usual case) are cheaper to scan than 27 cells to look up.
    if (keypoints_.size() <= 64 || !capped_) {
      for (uint32_t k = 0; k < keypoints_.size(); ++k)
        if (inside(k, p)) return true;
      return false;
    }
    const CellKey c = cell_key(p, claim_max_);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = accepted_.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == accepted_.end()) continue;
          for (uint32_t k : it->second)
            if (inside(k, p)) return true;
        }
    return false;
  }

 private:
  bool inside(uint32_t k, const Vec3& p) const {
    const float claim = std::max(keypoints_[k].characteristic_radius, claim_floor_);
    return (keypoints_[k].position - p).squaredNorm() <= claim * claim;
  }

  const std::vector<Keypoint>& keypoints_;
  float claim_floor_, claim_max_;
  bool capped_;
  std::unordered_map<CellKey, std::vector<uint32_t>, CellKeyHash> accepted_;  // cell -> keypoint slots
};

// Sec. 3.2.2: whether a point lies within the boundary band of a boundary point, each point's answer
// remembered in `memo` (a stream keeps it between calls).
class BoundaryBand {
 public:
  BoundaryBand(const NeighbourIndex& tree, const std::vector<LocalSurface>& surfaces, float r,
               const KeypointParams& params, BoundaryMemo& memo)
      : tree_(tree), surfaces_(surfaces), memo_(memo), band_(params.boundary_band_supports * r),
        radius_(params.boundary_radius_supports * r), gap_rad_(params.boundary_gap_rad) {
    memo_.boundary.resize(tree.points().size(), -1);
    memo_.touches_boundary.resize(tree.points().size(), -1);
  }

  bool touches(uint32_t c) {
    if (memo_.touches_boundary[c] < 0) {
      if (band_ > 0) {
        tree_.radius(tree_.points()[c], band_, near_);
        memo_.touches_boundary[c] =
            std::any_of(near_.begin(), near_.end(), [&](const Neighbour& q) { return on_boundary(q.index); });
      } else {
        memo_.touches_boundary[c] = on_boundary(c);
      }
    }
    return memo_.touches_boundary[c] == 1;
  }

 private:
  bool on_boundary(uint32_t i) {
    if (memo_.boundary[i] < 0) {
      const Vec3& n = surfaces_[i].valid ? surfaces_[i].normal : Vec3::Zero();
      memo_.boundary[i] = is_boundary_point(tree_, i, n, radius_, gap_rad_, scratch_) ? 1 : 0;
    }
    return memo_.boundary[i] == 1;
  }

  const NeighbourIndex& tree_;
  const std::vector<LocalSurface>& surfaces_;
  BoundaryMemo& memo_;
  float band_, radius_, gap_rad_;
  std::vector<Neighbour> near_, scratch_;
};

}  // namespace

std::vector<Keypoint> characteristic_scale_keypoints(const NeighbourIndex& tree, const std::vector<LocalSurface>& surfaces,
                                                     float r, const KeypointParams& params, KeypointStats* stats,
                                                     BoundaryMemo* memo) {
  KeypointStats st;
  const Points& pts = tree.points();
  const bool capped = params.max_characteristic_radius_m > 0 || params.max_radius_supports > 0;
  const float max_radius = params.max_characteristic_radius_m > 0 ? params.max_characteristic_radius_m
                           : capped ? params.max_radius_supports * r
                                    : std::numeric_limits<float>::infinity();
  st.max_radius_m = capped ? max_radius : 0;
  // rho1 <= max_radius  <=>  lambda_min >= 4 / max_radius^2 (eq. 3); rho1 must be finite in any case.
  const float lambda_threshold = capped ? 4.f / (max_radius * max_radius) : 0.f;
  const std::vector<uint32_t> candidates =
      keypoint_candidates(tree, surfaces, r, lambda_threshold, params.response == KeypointResponse::kHarris);
  st.candidates = candidates.size();

  std::vector<Keypoint> keypoints;
  const float claim_floor = params.claim_min_supports * r;
  Claims claims(keypoints, claim_floor, std::max(max_radius, claim_floor), capped);
  BoundaryMemo local;
  std::optional<BoundaryBand> boundary;
  if (params.exclude_boundary) boundary.emplace(tree, surfaces, r, params, memo ? *memo : local);
  for (uint32_t c : candidates) {
    // The keypoint claims the sphere of its characteristic radius: no other keypoint inside it (eq. 3).
    if (claims.claimed(pts[c])) continue;
    if (boundary && boundary->touches(c)) {
      ++st.boundary_rejected;
      continue;
    }
    const LocalSurface& s = surfaces[c];
    keypoints.push_back({c, pts[c], characteristic_radius(s.lambda_min), s.lambda_min, s.lambda_max});
    claims.add(static_cast<uint32_t>(keypoints.size() - 1));
    if (params.max_keypoints && keypoints.size() >= params.max_keypoints) break;
  }
  if (stats) *stats = st;
  return keypoints;
}

}  // namespace glimpse
