// The 12-D local descriptor of a keypoint (sec. 2.3): an 8-bin PFH, the angle between small- and
// large-window normals (eq. 4), the modified shape index (eqs. 7-8), rho2 (eq. 9) and the volume of
// the convex hull of the neighbourhood.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "glimpse/features/keypoints.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"

namespace glimpse {

inline constexpr int kDescriptorSize = 12;
using Descriptor = Eigen::Matrix<float, kDescriptorSize, 1>;

// Layout of a Descriptor.
enum DescriptorField : int {
  kPfhFirst = 0,        // 8 bins (alpha, phi, theta of eq. 6, split at 0), summing to 1
  kNormalAngle = 8,     // eq. 4, radians in [0, pi/2]
  kShapeIndex = 9,      // eq. 8, |1/2 - Ip| in [0, 1/2]
  kRho2 = 10,           // eq. 9, metres
  kHullVolume = 11,     // m^3
};

// Volume of the convex hull of the points (qhull); 0 for fewer than 4 or coplanar points.
double convex_hull_volume(std::span<const Vec3> points);

struct DescriptorParams {
  float large_window_supports = 2.5f;  // the large-window normal uses R = this x the neighbourhood (sec. 2.3, eq. 4)
  size_t max_pfh_points = 48;          // neighbourhood subsampled (deterministically) above this
  // The neighbourhood of the PFH and the hull: the support radius r (0), or the keypoint's own
  // characteristic radius rho1 (eq. 3) clamped to [r, this x r], so a keypoint is described at its scale.
  float characteristic_scale_supports = 0;
};

// The radius a keypoint is described over (see DescriptorParams), and the farthest any descriptor reads.
float descriptor_radius(const Keypoint& keypoint, float support_radius_m, const DescriptorParams& params);
float descriptor_reach(float support_radius_m, const DescriptorParams& params);

// eq. 7-8: |1/2 - Ip| with Ip = 1/2 - atan((k1 + k2) / (k1 - k2)) / pi: 1/2 on a sphere (cap or cup),
// 1/4 on a cylinder, 0 on a symmetric saddle (and on a plane).
float modified_shape_index(float k1, float k2);

// 8-bin PFH (Rusu 2008, sec. 2.3) over points with oriented normals; bins sum to 1 (all zero when
// fewer than 2 points).
std::array<float, 8> pfh8(const std::vector<Vec3>& points, const std::vector<Vec3>& normals);

Descriptor local_descriptor(const NeighbourIndex& tree, const std::vector<LocalSurface>& surfaces,
                            const Keypoint& keypoint, float support_radius_m,
                            const DescriptorParams& params, std::vector<Neighbour>& scratch);

}  // namespace glimpse
