// Keypoints with a characteristic radius (sec. 2.2, 3.2.2): points where the smaller principal Harris
// curvature is large, taken greedily in descending order of it; each keypoint claims the sphere of its
// characteristic radius rho1 = 2 / sqrt(lambda_min) (eq. 3), so radii grow monotonically.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/geometry/boundaries.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"

namespace glimpse {

// What ranks candidate keypoints.
enum class KeypointResponse : uint8_t {
  kLambdaMin = 0,  // the paper (sec. 2.2): the smaller principal Harris curvature, descending
  kHarris = 1,     // Sipiran & Bustos: det - k tr^2 of the Harris matrix (LocalSurface::harris_response),
                   // candidates only where it is positive and the largest within r
};

struct KeypointParams {
  // Candidates whose rho1 would exceed this are flat, not keypoints. 0 = automatic:
  // max_radius_supports x the support radius r; max_radius_supports <= 0: no cap (the paper has none).
  float max_characteristic_radius_m = 0;
  float max_radius_supports = 8.f;
  // A keypoint claims the sphere of radius max(rho1, claim_min_supports x r): no other keypoint inside
  // it (sec. 2.2). 0: rho1 alone, as the paper words it.
  float claim_min_supports = 1.f;
  // Boundary points of a 2.5D view and their neighbourhood of boundary_band_supports x r never give
  // keypoints (sec. 3.2.2: "in a given radius").
  bool exclude_boundary = true;
  float boundary_gap_rad = std::numbers::pi_v<float> / 2;
  float boundary_band_supports = 1.f;
  // The boundary test looks at the neighbours within this x r: on irregular samplings (mesh vertices of
  // long thin triangles) a neighbourhood of r has angular gaps inside the surface.
  float boundary_radius_supports = 1.f;
  KeypointResponse response = KeypointResponse::kLambdaMin;
  size_t max_keypoints = 0;  // 0 = no limit
};

struct Keypoint {
  uint32_t index = 0;               // into the cloud the surfaces were computed on
  Vec3 position = Vec3::Zero();
  float characteristic_radius = 0;  // rho1, eq. 3 (metres)
  float lambda_min = 0;
  float lambda_max = 0;
};

struct KeypointStats {
  size_t candidates = 0;          // valid points with rho1 below the maximum
  size_t boundary_rejected = 0;   // candidates dropped for touching a boundary
  float max_radius_m = 0;         // the maximum rho1 used
};

// eq. 3: rho1 = 2 / sqrt(lambda_min); on a sphere of radius rho this is sqrt(2) rho (eq. 1-2).
inline float characteristic_radius(float lambda_min) {
  return lambda_min > 0 ? 2.f / std::sqrt(lambda_min) : std::numeric_limits<float>::infinity();
}

// What keypoint selection learns about points and may keep between calls on a growing cloud: per
// point, -1 unknown, 0 no, 1 yes. A caller that changes a point's neighbourhood resets its entries
// (boundary: the point; touches_boundary: every point within r of it).
struct BoundaryMemo {
  std::vector<int8_t> boundary;
  std::vector<int8_t> touches_boundary;
};

// Deterministic: the same surfaces give the same keypoints, in the same order (descending response,
// ties by index), whatever the thread count. A memo is valid for one boundary band width.
std::vector<Keypoint> characteristic_scale_keypoints(const NeighbourIndex& tree,
                                                     const std::vector<LocalSurface>& surfaces,
                                                     float support_radius_m,
                                                     const KeypointParams& params,
                                                     KeypointStats* stats = nullptr,
                                                     BoundaryMemo* memo = nullptr);

}  // namespace glimpse
