// Upright shape histogram (USH): a descriptor of a whole (partial) cloud made of the per-point local
// surfaces every method already computes, measured against gravity. It is ours, not the paper's: the
// paper's keypoint methods see nothing until enough keypoints are visible, and VFH/ESF ignore where up
// is, yet a scanner knows it (sec. 3.4 stands every object upright; the exploration of sec. 4 runs top
// to bottom). Every point contributes, so a few hundred points are enough to decide on.
//
// Three blocks, each a histogram over the points with a fitted surface, each summing to 1:
//   1. local shape: shape index Ip (eq. 7, 8 bins) x curvedness sqrt((k1^2 + k2^2) / 2) (7 octaves);
//   2. orientation: the normal's elevation n . up (6 bins) x depth below the highest point (8 bins);
//   3. profile: horizontal distance from the cloud's vertical axis (6 bins) x depth below the top.
// Absolute sizes (metres) are kept: the cloud is in real-life units, and scale tells categories apart.
// Rotation about the up axis and horizontal translation leave it unchanged; the cloud's frame must
// have +z up (against gravity).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/geometry/surface_fit.h"

namespace glimpse {

inline constexpr int kShapeIndexBins = 8;
inline constexpr int kCurvednessBins = 7;
inline constexpr int kElevationBins = 6;
inline constexpr int kDepthBins = 8;
inline constexpr int kRadialBins = 6;
inline constexpr int kUprightHistogramSize =
    kShapeIndexBins * kCurvednessBins + kElevationBins * kDepthBins + kRadialBins * kDepthBins;  // 152

struct UprightHistogramParams {
  float max_depth_m = 2.0f;   // depth bins cover [0, max] on a square-root scale (finer near the top)
  float max_radius_m = 1.2f;  // radial bins likewise
  float flat_curvedness = 1.0f;  // 1/m; below it a point is in the first (flattest) curvedness octave
};

// eq. 7: Ip = 1/2 - atan((k1 + k2) / (k1 - k2)) / pi, in [0, 1]; 0 for a cup, 1 for a cap (k1 >= k2,
// signed w.r.t. the normal), 1/2 for a saddle. A plane (k1 = k2 = 0) gives 1/2.
float shape_index(float k1, float k2);

// `points[i]` and `surfaces[i]` describe the same point. All zero when no surface is valid.
Eigen::VectorXf upright_histogram(const Points& points, const std::vector<LocalSurface>& surfaces,
                                  const UprightHistogramParams& params = {});

// The size-only baseline: what a ruler sees of a (partial) cloud, in metres — its height (z extent)
// and its horizontal extents along the principal axes of the points' x, y (largest first), so a turn
// about the up axis changes nothing. A recogniser that does no better than this one is measuring size.
inline constexpr int kVisibleSizeSize = 3;
Eigen::VectorXf visible_size(const Points& points);

}  // namespace glimpse
